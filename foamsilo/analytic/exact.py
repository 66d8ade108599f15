"""Exact and classical solutions used to verify the solver.

* steady mu(I) flow down an inclined plane (the Bagnold profile), and the
  Newtonian film it becomes at the viscosity cap;
* hydrostatic and Janssen vertical stress and wall pressure in a silo;
* Darcy (and Darcy-Forchheimer) flow through a uniform column, and Darcy
  flow into a slit: in a half-plane, and in a planar silo of width L with a
  centred bottom slot of width D (exact, by conformal mapping).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from foamsilo.analytic.rheology import FrictionLaw
from foamsilo.errors import FoamsiloError

GRAVITY = 9.81


# ------------------------------------------------------------------ Bagnold


def bagnold_inertial_number(
    theta: float, mu_s: float, delta_mu: float, i0: float, *, law: FrictionLaw | None = None
) -> float:
    """I on a plane inclined at theta [rad]: mu(I) = tan(theta).

    ``law`` replaces the plain law of (mu_s, delta_mu, i0), e.g. by its
    regularised form (:class:`foamsilo.analytic.rheology.FrictionLaw`).

    Raises
    ------
    FoamsiloError
        Outside mu_s < tan(theta) < mu_s + delta_mu (the law's own range for
        ``law``), where no steady uniform flow exists (the layer stops, or
        accelerates without bound).
    """
    t = math.tan(theta)
    if law is not None:
        try:
            return law.inertial_number(t)
        except FoamsiloError as exc:
            raise FoamsiloError(f"no steady flow at tan(theta) = {t:.4g}: {exc}") from None
    if not mu_s < t < mu_s + delta_mu:
        raise FoamsiloError(
            f"no steady flow: tan(theta) = {t:.4g} must lie in (mu_s, mu_s + delta_mu) = "
            f"({mu_s:g}, {mu_s + delta_mu:g})"
        )
    return i0 * (t - mu_s) / (mu_s + delta_mu - t)


def bagnold_velocity(
    z: ArrayLike,
    depth: float,
    theta: float,
    mu_s: float,
    delta_mu: float,
    i0: float,
    d: float,
    g: float = GRAVITY,
    *,
    law: FrictionLaw | None = None,
) -> np.ndarray:
    """Velocity u(z) of the steady mu(I) layer (z from the base, no slip).

    With p = rho g cos(theta) (h - z) and I uniform,
    u(z) = (2/3) (I/d) sqrt(g cos theta) [h^(3/2) - (h - z)^(3/2)].
    ``law``: as for :func:`bagnold_inertial_number`.
    """
    inertial = bagnold_inertial_number(theta, mu_s, delta_mu, i0, law=law)
    zz = np.clip(np.asarray(z, dtype=float), 0.0, depth)
    below = depth - zz
    scale = (2 / 3) * inertial / d * math.sqrt(g * math.cos(theta))
    return np.asarray(scale * (depth**1.5 - below**1.5))


def bagnold_mean_velocity(
    depth: float, theta: float, mu_s: float, delta_mu: float, i0: float, d: float,
    g: float = GRAVITY,
) -> float:  # fmt: skip
    """Depth-averaged velocity: 3/5 of the surface velocity."""
    inertial = bagnold_inertial_number(theta, mu_s, delta_mu, i0)
    return 0.4 * inertial / d * math.sqrt(g * math.cos(theta)) * depth**1.5


def bagnold_max_viscosity(
    depth: float, theta: float, mu_s: float, delta_mu: float, i0: float, d: float, rho: float,
    g: float = GRAVITY,
) -> float:  # fmt: skip
    """Largest mu(I) viscosity in the layer (at the base): the cap must exceed it."""
    inertial = bagnold_inertial_number(theta, mu_s, delta_mu, i0)
    p = rho * g * math.cos(theta) * depth
    shear = inertial * math.sqrt(p / rho) / d
    return math.tan(theta) * p / shear


def newtonian_film_velocity(
    z: ArrayLike, depth: float, theta: float, nu: float, g: float = GRAVITY
) -> np.ndarray:
    """Velocity u(z) of a steady Newtonian film down an inclined plane (no slip, free top).

    u(z) = (g sin theta / nu) (h z - z^2 / 2): the mu(I) layer where the
    viscosity cap holds throughout (below the yield slope, tan theta < mu_s,
    the rheology's viscosity mu p / (rho |grad u|) exceeds the film's own).
    """
    zz = np.clip(np.asarray(z, dtype=float), 0.0, depth)
    return np.asarray(g * math.sin(theta) / nu * (depth * zz - zz**2 / 2))


# ------------------------------------------------------- silo wall pressures


def hydrostatic_pressure(depth: ArrayLike, rho: float, g: float = GRAVITY) -> np.ndarray:
    """Return the hydrostatic pressure rho g s at depth s below the surface [Pa]."""
    return rho * g * np.clip(np.asarray(depth, float), 0.0, None)


def hydraulic_radius(shape: str, width: float, thickness: float | None = None) -> float:
    """Cross-section area over wetted perimeter [m].

    ``cylinder`` (diameter ``width``): width/4; ``slot`` (planar, two walls
    ``width`` apart): width/2; ``box`` (width x thickness): wt/(2(w + t)).
    """
    if shape == "cylinder":
        return width / 4
    if shape == "slot":
        return width / 2
    if shape == "box":
        if thickness is None:
            raise FoamsiloError("a box needs its thickness")
        return width * thickness / (2 * (width + thickness))
    raise FoamsiloError(f"unknown shape {shape!r}; allowed: cylinder, slot, box")


def janssen_vertical_stress(
    depth: ArrayLike, rho: float, hydraulic_radius: float, K: float, mu_w: float,
    g: float = GRAVITY,
) -> np.ndarray:  # fmt: skip
    """Janssen: sigma_v(s) = rho g R/(K mu_w) (1 - exp(-K mu_w s/R)) [Pa].

    Tends to the hydrostatic rho g s near the surface and saturates at
    rho g R/(K mu_w) deep down.
    """
    if K <= 0 or mu_w <= 0:
        return hydrostatic_pressure(depth, rho, g)
    s = np.clip(np.asarray(depth, float), 0.0, None)
    lam = hydraulic_radius / (K * mu_w)
    return rho * g * lam * (1.0 - np.exp(-s / lam))


def janssen_wall_pressure(
    depth: ArrayLike, rho: float, hydraulic_radius: float, K: float, mu_w: float,
    g: float = GRAVITY,
) -> np.ndarray:  # fmt: skip
    """Return the normal stress on the wall, K sigma_v [Pa]."""
    return K * janssen_vertical_stress(depth, rho, hydraulic_radius, K, mu_w, g)


# ----------------------------------------------------------------------- Darcy


def darcy_column_gradient(
    superficial_velocity: float,
    kappa_v: float,
    eta_f: float,
    kappa_i: float | None = None,
    rho_f: float = 1.2,
    d: float = 0.0,
) -> float:
    """-dp/dz for a gas flowing up (U > 0) through a uniform bed [Pa/m].

    Darcy, plus the Forchheimer term rho_f d U|U|/kappa_i (Zhou eq. 11)
    when ``kappa_i`` is given.
    """
    U = superficial_velocity
    grad = eta_f * U / kappa_v
    if kappa_i is not None:
        grad += rho_f * d * U * abs(U) / kappa_i
    return grad


def darcy_slit_pressure(
    x: ArrayLike,
    y: ArrayLike,
    flux: float,
    kappa: float,
    eta_f: float,
    slit_width: float,
    silo_width: float | None = None,
) -> np.ndarray:
    """Pore pressure of Darcy flow drawn into a slit (p = 0 on the slit) [Pa].

    Parameters
    ----------
    x, y
        Position: x from the slit centre, y > 0 above the slit wall.
    flux
        Gas volume flux through the slit per unit depth [m^2/s].
    kappa, eta_f
        Permeability [m^2] and gas viscosity [Pa s].
    slit_width
        D [m].
    silo_width
        L [m]: impermeable side walls at x = +-L/2 (the planar silo of Zhou
        et al. sec. III.B); None for a half-plane.

    Notes
    -----
    With p = 0 on the slit and no flux through the walls, the solution is
    p = (eta_f q / (pi kappa)) Re arccosh(w / a), where w = zeta, a = D/2 in
    the half-plane, and w = sin(pi zeta/L), a = sin(pi D/(2L)) in the strip
    (the map sends the strip onto the half-plane, walls onto walls).  Far
    from the slit the gradient is uniform, eta_f q/(kappa L).
    """
    zeta = np.asarray(x, float) + 1j * np.asarray(y, float)
    if silo_width is None:
        w, a = zeta, slit_width / 2
    else:
        if slit_width >= silo_width:
            raise FoamsiloError("slit_width must be < silo_width")
        w = np.sin(np.pi * zeta / silo_width)
        a = math.sin(math.pi * slit_width / (2 * silo_width))
    xi = np.real(np.arccosh(w / a))
    return eta_f * flux / (math.pi * kappa) * np.abs(xi)
