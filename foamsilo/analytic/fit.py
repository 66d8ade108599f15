"""Fitting the constants of Zhou et al. 2019 as the paper does.

* C0, alpha_D, beta from open-top flow rates against D/d (eq. 1, sec. II.B);
* phi_o (one per grain size, Fig. 7a/b) or xi_phi (eq. 2, all sizes at
  once) from flow rates against the injected air flow (eq. 23).

Nonlinear least squares (scipy), with 1-sigma parameter uncertainties from
the covariance scaled by the residual variance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import curve_fit, least_squares

from foamsilo.analytic.zhou import (
    AIR_DENSITY,
    AIR_VISCOSITY,
    GLASS_DENSITY,
    GRAVITY,
    SiloConfig,
    config,
    orifice_area,
    phi_orifice,
    q0_bottom,
    reduced_flow_rate,
    reduced_numbers,
)
from foamsilo.errors import FoamsiloError


@dataclass(frozen=True)
class FitResult:
    """Fitted parameters with their 1-sigma uncertainties."""

    values: dict[str, float]
    sigmas: dict[str, float]
    rms_relative_residual: float
    n_points: int

    def as_dict(self) -> dict[str, object]:
        """JSON-friendly form."""
        return dict(self.__dict__)


def fit_open_top(
    D: ArrayLike,
    d: ArrayLike,
    Q: ArrayLike,
    phi_b: float,
    rho_p: float = GLASS_DENSITY,
    orifice: str = "disk",
    W: float | None = None,
    g: float = GRAVITY,
    guess: tuple[float, float, float] = (0.7, 0.8, 0.08),
) -> FitResult:
    """Fit C0, alpha_D, beta of eq. 1 to open-top rates Q(D, d).

    Relative residuals are minimised (rates span decades across D).
    """
    D, d, Q = (np.asarray(x, float) for x in np.broadcast_arrays(D, d, Q))
    if len(Q) < 4:
        raise FoamsiloError(f"need at least 4 points to fit 3 constants (got {len(Q)})")
    area = np.pi * D**2 / 4 if orifice == "disk" else W * D if W else None
    if area is None:
        raise FoamsiloError("a rectangular orifice needs W")

    def model(x: np.ndarray, C0: float, alpha: float, beta: float) -> np.ndarray:
        Dx, dx, ax = x
        return C0 * phi_b * rho_p * (1 - alpha * np.exp(-beta * Dx / dx)) * ax * np.sqrt(g * Dx)

    x = np.vstack([D, d, np.broadcast_to(area, D.shape)])
    popt, pcov = curve_fit(model, x, Q, p0=guess, sigma=Q, absolute_sigma=False, maxfev=20000)
    rel = (model(x, *popt) - Q) / Q
    names = ("C0", "alpha_D", "beta")
    return FitResult(
        dict(zip(names, map(float, popt), strict=True)),
        dict(zip(names, map(float, np.sqrt(np.diag(pcov))), strict=True)),
        float(np.sqrt(np.mean(rel**2))),
        len(Q),
    )


def _model_q(
    cfg: SiloConfig, D: float, W: float | None, d: np.ndarray, q_air: np.ndarray, phi_b: float,
    phi_o: np.ndarray, rho_p: float, A: float, inertial: bool, g: float,
) -> np.ndarray:  # fmt: skip
    S_o = orifice_area(cfg, D, W)
    assert cfg.C0 is not None
    Q0 = q0_bottom(D, d, phi_b, rho_p, cfg.C0, cfg.alpha_D, cfg.beta, S_o, g)
    Nv, Ni = reduced_numbers(Q0, phi_o, d, S_o, rho_p, AIR_VISCOSITY, AIR_DENSITY, g)
    qt = phi_o * rho_p * q_air / Q0
    return Q0 * reduced_flow_rate(qt, A * Nv, Ni if inertial else 0.0)


def fit_phi_o(
    cfg: SiloConfig | str,
    d: float,
    q_air: ArrayLike,
    Q: ArrayLike,
    D: float | None = None,
    W: float | None = None,
    phi_b: float = 0.6,
    rho_p: float = GLASS_DENSITY,
    A: float = 1.0,
    inertial: bool = True,
    g: float = GRAVITY,
) -> FitResult:
    """Fit phi_o of eq. 23 to Q(Q_air) for one grain size (Fig. 7a)."""
    c = config(cfg) if isinstance(cfg, str) else cfg
    D = c.orifice_sizes[0] if D is None else D
    qa, Q = (np.asarray(x, float) for x in (q_air, Q))

    def resid(p: np.ndarray) -> np.ndarray:
        m = _model_q(c, D, W, np.full_like(qa, d), qa, phi_b, np.full_like(qa, p[0]), rho_p, A,
                     inertial, g)  # fmt: skip
        return (m - Q) / Q

    sol = least_squares(resid, x0=[0.9 * phi_b], bounds=([0.05], [0.74]))
    return _result(sol, ("phi_o",), len(Q))


def fit_xi_phi(
    cfg: SiloConfig | str,
    d: ArrayLike,
    q_air: ArrayLike,
    Q: ArrayLike,
    D: float | None = None,
    W: float | None = None,
    phi_b: float = 0.6,
    rho_p: float = GLASS_DENSITY,
    A: float = 1.0,
    inertial: bool = True,
    g: float = GRAVITY,
) -> FitResult:
    """Fit xi_phi (eq. 2) to Q(Q_air) over several grain sizes at once."""
    c = config(cfg) if isinstance(cfg, str) else cfg
    D = c.orifice_sizes[0] if D is None else D
    dd, qa, Q = (np.asarray(x, float) for x in np.broadcast_arrays(d, q_air, Q))

    def resid(p: np.ndarray) -> np.ndarray:
        phi_o = phi_orifice(D, dd, phi_b, p[0], c.alpha_D, c.beta)
        m = _model_q(c, D, W, dd, qa, phi_b, phi_o, rho_p, A, inertial, g)
        return (m - Q) / Q

    sol = least_squares(resid, x0=[0.9], bounds=([0.1], [1.2]))
    return _result(sol, ("xi_phi",), len(Q))


def _result(sol: object, names: tuple[str, ...], n: int) -> FitResult:
    jac = sol.jac  # type: ignore[attr-defined]
    res = sol.fun  # type: ignore[attr-defined]
    dof = max(1, n - len(names))
    s2 = float(res @ res) / dof
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
        sig = np.sqrt(np.diag(cov))
    except np.linalg.LinAlgError:
        sig = np.full(len(names), math.inf)
    return FitResult(
        dict(zip(names, map(float, sol.x), strict=True)),  # type: ignore[attr-defined]
        dict(zip(names, map(float, sig), strict=True)),
        float(np.sqrt(np.mean(res**2))),
        n,
    )
