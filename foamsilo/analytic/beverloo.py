"""Beverloo (Hagen) discharge laws.

Two-dimensional (slot) form, per unit depth::

    Q = C rho sqrt(g) (D - k d)^(3/2)

The continuum mu(I) model has no steric exclusion at the orifice edges, so
k = 0 for it; C is then fixed by one reference value.  The reference used
here is the converged continuum rate of Zhou et al. 2019 (sec. III.B, Fig.
4a, open top) for D = L/4: Q/(rho sqrt(g L^3)) = 0.16 +- 0.01, i.e.
C = 0.16/(1/4)^(3/2) = 1.28 +- 0.08.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

#: Converged Q/(rho sqrt(g L^3)) of the open-top planar silo, D = L/4 (Zhou et al. 2019)
ZHOU_PLANAR_Q = 0.16
#: Its uncertainty
ZHOU_PLANAR_Q_SPREAD = 0.01
#: D/L of that silo
ZHOU_PLANAR_D_OVER_L = 0.25


def beverloo_2d_constant(
    q_dimensionless: float = ZHOU_PLANAR_Q, d_over_l: float = ZHOU_PLANAR_D_OVER_L
) -> float:
    """C of the slot law from one reference rate Q/(rho sqrt(g L^3)) at D/L (k = 0)."""
    return q_dimensionless / d_over_l**1.5


def beverloo_2d(
    orifice_width: ArrayLike,
    density: float,
    gravity: float = 9.81,
    C: float | None = None,
    k: float = 0.0,
    grain_diameter: float = 0.0,
) -> np.ndarray:
    """Mass flow rate per unit depth of a slot orifice [kg/(m s)].

    Parameters
    ----------
    orifice_width
        D [m] (array-like).
    density
        Bulk density of the flowing material [kg/m^3].
    gravity
        |g| [m/s^2].
    C
        Prefactor; default from Zhou et al.'s continuum reference.
    k, grain_diameter
        Empty-annulus correction k d (0 for the continuum model).

    Returns
    -------
    numpy.ndarray
        Q, zero where D <= k d.
    """
    c = beverloo_2d_constant() if C is None else C
    width = np.clip(np.asarray(orifice_width, dtype=float) - k * grain_diameter, 0.0, None)
    return c * density * np.sqrt(gravity) * width**1.5
