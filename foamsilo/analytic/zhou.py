"""Discharge laws of Zhou et al. 2019 (Phys. Rev. Fluids 4, 124305).

Open-top laws (eqs 1, 2, 24, 25), the impermeable asymptote (eq. 3), the
Ergun permeabilities (after eq. 8) and the gas-assisted model (eqs 17-23),
with the Table I constants of the five silo configurations as presets.

Notation (SI units): D orifice size (diameter, or height of a rectangular
orifice), W orifice width (the silo thickness for a rectangular silo, the
arc length for a lateral orifice of a cylindrical silo), d grain diameter,
phi_b bulk volume fraction, rho_p grain density.

The gas-assisted model in reduced form: with Qbar = Q/Q0 and
Qtilde = phi_o rho_p Q_air / Q0, eqs 17, 18 and 20 give

    Qbar^2 = 1 + Nv (Qtilde - Qbar) + s Ni (Qtilde - Qbar)^2,
    s = sign(Qtilde - Qbar) = sign(Qtilde - 1)                        (eq. 19)

(+1 co-current, -1 counter-current flow of air at the orifice), which is the
quadratic of eq. 21; its physical root (eq. 23) lies between 1 and Qtilde.
The corrections of the paper: ``A`` multiplies Nv (zone over which the
pressure gradient acts, sec. IV.A: "replacing Nv by A Nv"), and ``lam``
replaces g by lam g for a lateral orifice (sec. V), i.e. divides Nv and Ni.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from foamsilo.errors import FoamsiloError

GRAVITY = 9.81
AIR_DENSITY = 1.2  # kg/m^3, Zhou et al. sec. II.A
AIR_VISCOSITY = 1.8e-5  # Pa s
GLASS_DENSITY = 2500.0  # kg/m^3
LPM = 1e-3 / 60.0  # one litre per minute in m^3/s


class NoPhysicalRootError(FoamsiloError, ArithmeticError):
    """The gas-assisted model has no root between 1 and Qtilde."""


# --------------------------------------------------------------------- Table I


@dataclass(frozen=True)
class SiloConfig:
    """One row of Zhou et al. 2019, Table I.

    Attributes
    ----------
    name
        Preset name.
    silo, orifice, position
        ``cylindrical``/``rectangular``, ``disk``/``rectangular``,
        ``bottom``/``lateral``.
    widths, heights, orifice_sizes, orifice_widths
        Dimensions of the experiments [m] (L, H, D and W of Table I).
    C0, C0l
        Prefactors of eq. 1 (bottom) and eq. 24 (lateral); None where "-".
    beta, alpha_D, alpha_W, gamma2
        Steric and wall-friction constants; None where "-" (G = 1).
    lam
        lambda = (C0l/C0)^2, the reduced driving force g -> lam g.
    xi_phi
        xi_phi of eq. 2; None where not fitted.
    """

    name: str
    description: str
    silo: Literal["cylindrical", "rectangular"]
    orifice: Literal["disk", "rectangular"]
    position: Literal["bottom", "lateral"]
    widths: tuple[float, ...]
    heights: tuple[float, ...]
    orifice_sizes: tuple[float, ...]
    orifice_widths: tuple[float, ...] = ()
    C0: float | None = None
    beta: float = 0.0
    alpha_D: float | None = None
    C0l: float | None = None
    alpha_W: float | None = None
    gamma2: float | None = None
    lam: float = 1.0
    xi_phi: float | None = None
    extra: dict[str, float] = field(default_factory=dict)


TABLE_I: dict[str, SiloConfig] = {
    c.name: c
    for c in (
        SiloConfig(
            "cyl-bottom", "cylindrical silo, disk orifice at the bottom (Fig. 1a)",
            "cylindrical", "disk", "bottom", (0.020, 0.040, 0.060), (0.540,), (0.010, 0.020),
            C0=0.69, beta=0.08, alpha_D=0.81, lam=1.0, xi_phi=0.83,
        ),
        SiloConfig(
            "cyl-lateral-disk", "cylindrical silo, lateral disk orifice 20 mm up (Fig. 1b)",
            "cylindrical", "disk", "lateral", (0.040,), (0.540,), (0.010, 0.020, 0.030),
            beta=0.08, alpha_D=0.82, C0l=0.36, lam=0.27,
        ),
        SiloConfig(
            "cyl-lateral-rect", "cylindrical silo, lateral rectangular orifice (Fig. 1b)",
            "cylindrical", "rectangular", "lateral", (0.020, 0.040, 0.060), (0.540,),
            (0.010, 0.020), (0.005, 0.010),
            beta=0.07, alpha_D=0.45, C0l=0.49, alpha_W=0.59, gamma2=1.13, lam=0.27,
            xi_phi=0.96,
        ),
        SiloConfig(
            "rect-bottom", "rectangular silo, rectangular orifice at the bottom (Fig. 1c)",
            "rectangular", "rectangular", "bottom", (0.060,), (0.500,), (0.010,), (0.0035,),
            C0=0.86, beta=0.08, alpha_D=0.81, lam=1.0, xi_phi=1.0,
        ),
        SiloConfig(
            "rect-lateral", "rectangular silo, lateral rectangular orifice (Fig. 1d)",
            "rectangular", "rectangular", "lateral", (0.060,), (0.500,), (0.010, 0.020),
            (0.0035,),
            beta=0.19, C0l=0.41, alpha_W=0.64, gamma2=0.56, lam=0.23, xi_phi=1.0,
        ),
    )
}  # fmt: skip


def config(name: str) -> SiloConfig:
    """Return a Table I configuration by name (the error lists the valid ones)."""
    if name not in TABLE_I:
        raise FoamsiloError(f"unknown configuration {name!r}; allowed: {', '.join(TABLE_I)}")
    return TABLE_I[name]


# ----------------------------------------------------------------- open top


def steric(alpha: float | None, beta: float, size: ArrayLike, d: ArrayLike) -> np.ndarray:
    """G(x) = 1 - alpha exp(-beta x/d): dilation at the aperture (G = 1 without alpha)."""
    if alpha is None:
        return np.ones(np.broadcast(np.asarray(size), np.asarray(d)).shape)
    return 1.0 - alpha * np.exp(-beta * np.asarray(size, float) / np.asarray(d, float))


def orifice_area(cfg: SiloConfig, D: float, W: float | None = None) -> float:
    """S_o: pi D^2/4 for a disk, W D for a rectangular orifice [m^2]."""
    if cfg.orifice == "disk":
        return math.pi * D**2 / 4
    if W is None:
        raise FoamsiloError(f"{cfg.name}: a rectangular orifice needs its width W")
    return W * D


def q0_bottom(
    D: ArrayLike, d: ArrayLike, phi_b: float, rho_p: float = GLASS_DENSITY,
    C0: float = 0.69, alpha_D: float | None = 0.81, beta: float = 0.08,
    area: ArrayLike | None = None, g: float = GRAVITY,
) -> np.ndarray:  # fmt: skip
    """Eq. 1: Q0 = C0 phi_b rho_p [1 - alpha_D e^(-beta D/d)] S_0 sqrt(g D) [kg/s].

    ``area`` defaults to the disk pi D^2/4.
    """
    D = np.asarray(D, float)
    S0 = np.pi * D**2 / 4 if area is None else np.asarray(area, float)
    return C0 * phi_b * rho_p * steric(alpha_D, beta, D, d) * S0 * np.sqrt(g * D)


def phi_orifice(
    D: float, d: ArrayLike, phi_b: float, xi_phi: float, alpha_D: float | None, beta: float,
    W: float | None = None, alpha_W: float | None = None,
) -> np.ndarray:  # fmt: skip
    """Eq. 2 (and eq. 25 with W): volume fraction at the orifice."""
    phi = xi_phi * phi_b * steric(alpha_D, beta, D, d)
    if W is not None and alpha_W is not None:
        phi = phi * steric(alpha_W, beta, W, d)
    return phi


def q0_lateral(
    D: float, W: float, d: ArrayLike, phi_b: float, rho_p: float = GLASS_DENSITY,
    C0l: float = 0.49, alpha_D: float | None = 0.45, alpha_W: float | None = 0.59,
    beta: float = 0.07, gamma2: float | None = 1.13, g: float = GRAVITY,
) -> np.ndarray:  # fmt: skip
    """Eq. 24: Q0l = C0l rho phi_b G_D(D/d) G_W(W/d) F(D/W) W sqrt(g D^3) [kg/s].

    F(D/W) = [1 + gamma2 D/W]^(-1/2) (wall friction of a thin orifice).
    """
    F = 1.0 if gamma2 is None else (1.0 + gamma2 * D / W) ** -0.5
    G = steric(alpha_D, beta, D, d) * steric(alpha_W, beta, W, d)
    return C0l * rho_p * phi_b * G * F * W * math.sqrt(g * D**3)


def q_impermeable(q_air: ArrayLike, phi_b: float, rho_p: float = GLASS_DENSITY) -> np.ndarray:
    """Eq. 3: Q = rho_p phi_b Q_air, grains pushed out by the air (zero permeability)."""
    return rho_p * phi_b * np.asarray(q_air, float)


# ---------------------------------------------------------------- permeability


def kappa_viscous(phi: ArrayLike, d: ArrayLike) -> np.ndarray:
    """Ergun: kappa_v = (1 - phi)^3 d^2 / (150 phi^2) [m^2]."""
    phi = np.asarray(phi, float)
    return (1 - phi) ** 3 * np.asarray(d, float) ** 2 / (150 * phi**2)


def kappa_inertial(phi: ArrayLike, d: ArrayLike) -> np.ndarray:
    """Ergun: kappa_i = (1 - phi)^3 d^2 / (1.75 phi) [m^2]."""
    phi = np.asarray(phi, float)
    return (1 - phi) ** 3 * np.asarray(d, float) ** 2 / (1.75 * phi)


# ------------------------------------------------------------ gas-assisted model


def reduced_numbers(
    Q0: ArrayLike, phi_o: ArrayLike, d: ArrayLike, S_o: float, rho_p: float = GLASS_DENSITY,
    eta_f: float = AIR_VISCOSITY, rho_f: float = AIR_DENSITY, g: float = GRAVITY,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Eq. 22: N_v and N_i (Ergun permeabilities at phi_o)."""
    Q0, phi_o = np.asarray(Q0, float), np.asarray(phi_o, float)
    kv, ki = kappa_viscous(phi_o, d), kappa_inertial(phi_o, d)
    Nv = eta_f * Q0 / (phi_o**2 * rho_p**2 * kv * g * S_o)
    Ni = rho_f * np.asarray(d, float) * Q0**2 / (phi_o**3 * rho_p**3 * ki * g * S_o**2)
    return Nv, Ni


def _solve_one(qt: float, Nv: float, Ni: float) -> float:
    if not (math.isfinite(qt) and math.isfinite(Nv) and math.isfinite(Ni)):
        raise NoPhysicalRootError(f"non-finite input: Qtilde={qt}, Nv={Nv}, Ni={Ni}")
    if Nv < 0 or Ni < 0:
        raise NoPhysicalRootError(f"Nv and Ni must be >= 0 (got Nv={Nv}, Ni={Ni})")
    if qt < 0:
        raise NoPhysicalRootError(f"Qtilde = {qt} < 0: air cannot be drawn out of a closed silo")
    if qt == 1.0:
        return 1.0
    s = 1.0 if qt > 1.0 else -1.0
    a = 1.0 - s * Ni
    b = Nv + 2.0 * s * Ni * qt
    c = -(1.0 + Nv * qt + s * Ni * qt * qt)
    lo, hi = min(1.0, qt), max(1.0, qt)
    tol = 1e-12 * hi
    if abs(a) < 1e-14:
        roots = [-c / b] if b != 0 else []
    else:
        disc = Nv * Nv + 4.0 * (1.0 + Nv * qt) + 4.0 * s * Ni * (qt * qt - 1.0)  # eq. 23
        if disc < 0:
            raise NoPhysicalRootError(f"negative discriminant {disc:.3g} (Nv={Nv}, Ni={Ni})")
        sq = math.sqrt(disc)
        # stable pair of roots (no cancellation)
        qq = -0.5 * (b + math.copysign(sq, b))
        roots = [qq / a, c / qq] if qq != 0 else [-b / (2 * a)]
    inside = [r for r in roots if lo - tol <= r <= hi + tol]
    if not inside:
        raise NoPhysicalRootError(
            f"no root between 1 and Qtilde = {qt:.6g} (roots {roots}; Nv={Nv:.6g}, Ni={Ni:.6g})"
        )
    return min(max(inside[0], lo), hi)


def reduced_flow_rate(qtilde: ArrayLike, Nv: ArrayLike, Ni: ArrayLike = 0.0) -> np.ndarray:
    """Eq. 23: Qbar = Q/Q0 from Qtilde = phi_o rho_p Q_air/Q0, N_v and N_i.

    Returns the physical root, which lies between 1 and Qtilde (co-current
    flow, Qtilde > 1, speeds the grains up; counter-current, Qtilde < 1,
    slows them down).  Vectorised over broadcastable inputs.

    Raises
    ------
    NoPhysicalRootError
        For negative inputs or when no root lies between 1 and Qtilde, with
        the values that caused it.
    """
    qt, nv, ni = np.broadcast_arrays(*(np.asarray(x, float) for x in (qtilde, Nv, Ni)))
    out = np.empty(qt.shape)
    for idx in np.ndindex(qt.shape):
        out[idx] = _solve_one(float(qt[idx]), float(nv[idx]), float(ni[idx]))
    return out


def flow_direction(qtilde: ArrayLike) -> np.ndarray:
    """Eq. 19: +1 for co-current air flow at the orifice, -1 counter-current, 0 balanced."""
    return np.sign(np.asarray(qtilde, float) - 1.0)


@dataclass(frozen=True)
class GasAssistedResult:
    """Everything the gas-assisted model computes for one case."""

    Q: float  # kg/s
    Q0: float  # kg/s
    Nv: float
    Ni: float
    phi_o: float
    Q_air_reduced: float  # Qtilde
    Q_reduced: float  # Qbar
    direction: int  # eq. 19
    kappa_v: float
    kappa_i: float
    S_o: float
    Q_impermeable: float  # eq. 3

    def as_dict(self) -> dict[str, float | int]:
        """JSON-friendly form."""
        return dict(self.__dict__)


def gas_assisted(
    cfg: SiloConfig | str,
    d: float,
    q_air: float,
    D: float | None = None,
    W: float | None = None,
    phi_b: float = 0.6,
    rho_p: float = GLASS_DENSITY,
    A: float = 1.0,
    inertial: bool = True,
    phi_o: float | None = None,
    eta_f: float = AIR_VISCOSITY,
    rho_f: float = AIR_DENSITY,
    g: float = GRAVITY,
) -> GasAssistedResult:
    """Mass flow rate of a silo with air injected at Q_air (eqs 1-2, 17-25).

    Parameters
    ----------
    cfg
        Table I configuration (or its name).
    d
        Grain diameter [m].
    q_air
        Air flow rate injected at the top [m^3/s]; 0 for a closed top.
    D, W
        Orifice size and width [m]; default the first of Table I.
    phi_b
        Bulk volume fraction.
    rho_p
        Grain density [kg/m^3].
    A
        Zone correction, multiplies N_v (the paper: 0.68 in its 2D simulations).
    inertial
        Keep the Forchheimer term (N_i); False for the Darcy model.
    phi_o
        Volume fraction at the orifice; default eq. 2 (or 25) with xi_phi.
    """
    c = config(cfg) if isinstance(cfg, str) else cfg
    D = c.orifice_sizes[0] if D is None else D
    if c.orifice == "rectangular" and W is None:
        W = c.orifice_widths[0]
    for name, val in (("d", d), ("D", D), ("phi_b", phi_b), ("rho_p", rho_p), ("A", A)):
        if not (val > 0 and math.isfinite(val)):
            raise FoamsiloError(f"{name} must be a positive number (got {val})")
    if not phi_b < 1:
        raise FoamsiloError(f"phi_b must be < 1 (got {phi_b})")
    if q_air < 0:
        raise FoamsiloError(f"q_air must be >= 0 (got {q_air})")
    S_o = orifice_area(c, D, W)
    if c.position == "bottom":
        if c.C0 is None:
            raise FoamsiloError(f"{c.name}: no C0 in Table I")
        Q0 = float(q0_bottom(D, d, phi_b, rho_p, c.C0, c.alpha_D, c.beta, S_o, g))
        g_eff = g
    else:
        if c.C0l is None:
            raise FoamsiloError(f"{c.name}: no C0l in Table I")
        if W is None:  # lateral disk: eq. 24 written with the disk's D and W = D
            W_l = D
        else:
            W_l = W
        Q0 = float(q0_lateral(D, W_l, d, phi_b, rho_p, c.C0l, c.alpha_D, c.alpha_W, c.beta,
                              c.gamma2, g))  # fmt: skip
        g_eff = c.lam * g
    if phi_o is None:
        if c.xi_phi is None:
            raise FoamsiloError(f"{c.name}: xi_phi not in Table I; give phi_o")
        W_phi = W if c.position == "lateral" else None
        phi_o = float(phi_orifice(D, d, phi_b, c.xi_phi, c.alpha_D, c.beta, W_phi, c.alpha_W))
    if not 0 < phi_o < 1:
        raise FoamsiloError(f"phi_o must be in (0, 1) (got {phi_o})")
    nv, ni = reduced_numbers(Q0, phi_o, d, S_o, rho_p, eta_f, rho_f, g_eff)
    Nv, Ni = A * float(nv), float(ni) if inertial else 0.0
    qt = phi_o * rho_p * q_air / Q0
    qbar = float(reduced_flow_rate(qt, Nv, Ni))
    return GasAssistedResult(
        Q=qbar * Q0,
        Q0=Q0,
        Nv=Nv,
        Ni=Ni,
        phi_o=phi_o,
        Q_air_reduced=qt,
        Q_reduced=qbar,
        direction=int(flow_direction(qt)),
        kappa_v=float(kappa_viscous(phi_o, d)),
        kappa_i=float(kappa_inertial(phi_o, d)),
        S_o=S_o,
        Q_impermeable=float(q_impermeable(q_air, phi_b, rho_p)),
    )


def with_overrides(cfg: SiloConfig, **kw: Any) -> SiloConfig:
    """Return a configuration with some constants replaced (fitted values)."""
    return replace(cfg, **{k: v for k, v in kw.items() if v is not None})
