"""Jenike's radial stress fields in wedge (2D) and conical (3D) hoppers.

Gremaud & Matthews, sec. 4, eqs 16-17: the stresses of a Mohr-Coulomb
material at yield everywhere (passive state) in a converging hopper of half
angle theta_w, of the form T_ij(r, theta) = r T_ij(theta), written with the
Sokolovskii variables (sigma, psi) of eq. 8::

    T_rr = sigma (1 - s cos 2psi),  T_tt = sigma (1 + s cos 2psi),
    T_rt = -sigma s sin 2psi,       T_pp = sigma (1 + s)        (s = sin delta)

solve  A(sigma, psi) [sigma', psi']^T = B_d(theta, sigma, psi)  on (-theta_w, theta_w)
with psi(+-theta_w) = +-psi_w, psi_w = (phi_w + arcsin(sin phi_w / s)) / 2.

sigma is even and psi odd in theta, so the problem is solved on [0, theta_w]
by shooting on sigma(0) (psi(0) = 0); at theta = 0 the cone's cot(theta)
terms have finite limits, used to start the integration. Stresses are
compressive positive, per unit r [Pa/m]; r is measured from the apex, theta
from the axis, gravity points to the apex.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from foamsilo.errors import FoamsiloError

Dim = Literal[2, 3]
#: Corn in a steel hopper (Gremaud & Matthews sec. 6): rho = 790 kg/m^3, g = 9.81
RHO_G_CORN = 790.0 * 9.81
#: The paper's material: internal and wall friction angles [deg]
DELTA_PAPER = 32.1
PHI_W_PAPER = 11.7


class HopperError(FoamsiloError):
    """A hopper stress problem outside the range where the model holds."""


@dataclass(frozen=True)
class Material:
    """Mohr-Coulomb material and wall.

    Attributes
    ----------
    delta
        Angle of internal friction [rad].
    phi_w
        Angle of wall friction [rad] (mu = tan phi_w).
    rho_g
        Specific weight rho g [N/m^3].
    """

    delta: float
    phi_w: float
    rho_g: float = RHO_G_CORN

    @classmethod
    def degrees(cls, delta: float, phi_w: float, rho_g: float = RHO_G_CORN) -> Material:
        """Build from angles in degrees, checking their ranges."""
        if not 0.0 < delta < 90.0:
            raise HopperError(f"delta = {delta:g} deg: allowed 0 < delta < 90")
        if not 0.0 <= phi_w < 90.0:
            raise HopperError(f"phi_w = {phi_w:g} deg: allowed 0 <= phi_w < 90")
        if math.sin(math.radians(phi_w)) > math.sin(math.radians(delta)):
            raise HopperError(
                f"phi_w = {phi_w:g} deg > delta = {delta:g} deg: the wall is rougher than the "
                "material, no wall yield (psi_w needs sin phi_w <= sin delta)"
            )
        if not rho_g > 0:
            raise HopperError(f"rho_g = {rho_g:g}: allowed > 0")
        return cls(math.radians(delta), math.radians(phi_w), rho_g)

    @property
    def s(self) -> float:
        """Sin delta."""
        return math.sin(self.delta)

    @property
    def psi_w(self) -> float:
        """Sokolovskii angle at the wall, (phi_w + arcsin(sin phi_w / s)) / 2 [rad]."""
        return 0.5 * (self.phi_w + math.asin(math.sin(self.phi_w) / self.s))

    @property
    def chi_w(self) -> float:
        """Wall condition T_rr = chi_w T_rt, chi_w = -(1 - s cos 2psi_w)/(s sin 2psi_w)."""
        s, p = self.s, self.psi_w
        return -(1 - s * math.cos(2 * p)) / (s * math.sin(2 * p))

    @property
    def psi_hyperbolic(self) -> float:
        """pi/4 - delta/2: the largest |psi| the conservative DG formulation can hold."""
        return math.pi / 4 - self.delta / 2

    @property
    def psi_singular(self) -> float:
        """pi/4 + delta/2: where the radial problem (16) becomes singular."""
        return math.pi / 4 + self.delta / 2


def stresses(sigma: Any, psi: Any, s: float) -> tuple[Any, Any, Any, Any]:
    """Eq. 8: (T_rr, T_tt, T_rt, T_pp) from the Sokolovskii variables."""
    c2, s2 = np.cos(2 * psi), np.sin(2 * psi)
    return sigma * (1 - s * c2), sigma * (1 + s * c2), -sigma * s * s2, sigma * (1 + s)


def sokolovskii(t_rr: Any, t_rt: Any, t_tt: Any) -> tuple[Any, Any]:
    """Inverse of eq. 8: (sigma, psi) from T_rr, T_rt, T_tt on the yield cone."""
    sigma = 0.5 * (t_rr + t_tt)
    return sigma, 0.5 * np.arctan2(-t_rt, 0.5 * (t_tt - t_rr))


def _rhs(theta: float, y: np.ndarray, m: Material, dim: Dim) -> np.ndarray:
    """[sigma', psi'] of eq. 16 (rho g = 1: sigma scales with rho g)."""
    sig, psi = y
    s = m.s
    c2, s2 = math.cos(2 * psi), math.sin(2 * psi)
    a = np.array([[-s * s2, -2 * s * sig * c2], [1 + s * c2, -2 * s * sig * s2]])
    b = np.array([-math.cos(theta), math.sin(theta)])
    if dim == 2:
        b += sig * np.array([3 * s * c2 - 1, 3 * s * s2])
    else:
        cot = math.cos(theta) / math.sin(theta)
        b += sig * np.array([4 * s * c2 - 1 + s + s * cot * s2, 4 * s * s2 - s * (c2 - 1) * cot])
    return np.linalg.solve(a, b)


def _start_slope(sigma0: float, m: Material, dim: Dim) -> float:
    """psi'(0) from eq. 16 at theta = 0 (sigma' = 0 there by symmetry)."""
    s = m.s
    if dim == 2:  # -2 s sigma psi' = -1 + sigma (3s - 1)
        return (1 - sigma0 * (3 * s - 1)) / (2 * s * sigma0)
    # cone: cot(theta) sin(2 psi) -> 2 psi'(0): -4 s sigma psi' = -1 + sigma (5s - 1)
    return (1 - sigma0 * (5 * s - 1)) / (4 * s * sigma0)


@dataclass
class RadialField:
    """A radial stress field on [0, theta_w] (even/odd extension to the other half).

    Attributes
    ----------
    dim, theta_w, material
        The problem.
    sigma0
        sigma at the axis per unit r and per unit rho g [m] (sigma(0) / (rho g)).
    """

    dim: Dim
    theta_w: float
    material: Material
    sigma0: float
    _sol: Any

    def sigma_psi(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """Sigma [Pa/m] and psi [rad] at ``theta`` (|theta| <= theta_w; even/odd)."""
        th = np.asarray(theta, float)
        a = np.abs(th)
        if np.any(a > self.theta_w * (1 + 1e-9)):
            raise HopperError(f"theta outside the hopper |theta| <= {self.theta_w:g} rad")
        y = self._eval(np.minimum(a, self.theta_w))
        return y[0] * self.material.rho_g, np.sign(th) * y[1]

    def _eval(self, a: np.ndarray) -> np.ndarray:
        eps = self._sol.t_min
        small = a < eps
        out = np.empty((2,) + a.shape)
        out[:, ~small] = self._sol(a[~small]) if np.any(~small) else 0.0
        if np.any(small):  # the series start: sigma' = 0, psi = psi'(0) theta
            out[0, small] = self.sigma0
            out[1, small] = _start_slope(self.sigma0, self.material, self.dim) * a[small]
        return out

    def stresses(self, theta: Any) -> dict[str, np.ndarray]:
        """T_rr, T_tt, T_rt, T_pp per unit r [Pa/m] at ``theta``."""
        sig, psi = self.sigma_psi(theta)
        t_rr, t_tt, t_rt, t_pp = stresses(sig, psi, self.material.s)
        return {"Trr": t_rr, "Ttt": t_tt, "Trt": t_rt, "Tpp": t_pp}

    def psi_max(self) -> tuple[float, float]:
        """Largest psi over the hopper and where [rad, rad]."""
        th = np.linspace(0, self.theta_w, 2001)
        psi = self.sigma_psi(th)[1]
        i = int(np.argmax(psi))
        return float(psi[i]), float(th[i])

    def psi_monotonic(self) -> bool:
        """Whether psi increases from the axis to the wall (its maximum is at the wall)."""
        th = np.linspace(0, self.theta_w, 2001)
        return bool(np.all(np.diff(self.sigma_psi(th)[1]) >= -1e-12))


class _SingularError(Exception):
    pass


def _shoot(sigma0: float, theta_w: float, m: Material, dim: Dim, dense: bool = False) -> Any:
    """Integrate eq. 16 from the axis; return psi(theta_w) - psi_w (or the solution)."""
    eps = min(1e-6, 1e-4 * theta_w)
    y0 = [sigma0, _start_slope(sigma0, m, dim) * eps]

    def singular(_t: float, y: np.ndarray, *_: Any) -> float:  # |psi| -> pi/4 + delta/2
        return m.psi_singular - 1e-6 - abs(y[1])

    singular.terminal = True  # type: ignore[attr-defined]

    def negative(_t: float, y: np.ndarray, *_: Any) -> float:
        return y[0]

    negative.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(
        _rhs,
        (eps, theta_w),
        y0,
        args=(m, dim),
        method="DOP853",
        rtol=1e-11,
        atol=1e-13,
        events=(singular, negative),
        dense_output=dense,
    )
    if sol.status != 0 or sol.t[-1] < theta_w * (1 - 1e-12):
        raise _SingularError()
    return sol if dense else float(sol.y[1, -1] - m.psi_w)


def radial_field(dim: Dim, theta_w_deg: float, material: Material) -> RadialField:
    """Solve eqs 16-17 for the radial field of a wedge (2) or cone (3).

    Raises
    ------
    HopperError
        ``dim`` not 2 or 3, theta_w outside (0, 90) deg, or no radial field
        (the shooting finds no sigma(0) that meets the wall condition without
        reaching the singularity |psi| = pi/4 + delta/2: the hopper is too
        wide for mass flow with this material and wall).
    """
    if dim not in (2, 3):
        raise HopperError(f"dim = {dim}: allowed 2 (wedge) or 3 (cone)")
    if not 0.0 < theta_w_deg < 90.0:
        raise HopperError(f"theta_w = {theta_w_deg:g} deg: allowed 0 < theta_w < 90")
    tw = math.radians(theta_w_deg)

    def residual(x: float) -> float:
        try:
            return _shoot(x, tw, material, dim)
        except _SingularError:
            return math.nan

    # scan sigma(0)/(rho g) over decades: the residual is monotonic where defined
    grid = np.geomspace(1e-3, 1e3, 37)
    values = np.array([residual(x) for x in grid])
    ok = np.isfinite(values)
    bracket = None
    for i in range(len(grid) - 1):
        if ok[i] and ok[i + 1] and np.sign(values[i]) != np.sign(values[i + 1]):
            bracket = (grid[i], grid[i + 1])
            break
    if bracket is None:
        raise HopperError(
            f"no radial stress field for a {'wedge' if dim == 2 else 'cone'} of half angle "
            f"{theta_w_deg:g} deg with delta = {math.degrees(material.delta):g} deg and "
            f"phi_w = {math.degrees(material.phi_w):g} deg: psi cannot reach psi_w = "
            f"{math.degrees(material.psi_w):.2f} deg at the wall without |psi| reaching "
            f"pi/4 + delta/2 (the hopper is too wide for a radial mass flow)"
        )
    sigma0 = brentq(residual, *bracket, xtol=1e-14, rtol=1e-13)
    sol = _shoot(sigma0, tw, material, dim, dense=True)
    return RadialField(dim, tw, material, sigma0, sol.sol)
