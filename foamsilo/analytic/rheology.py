"""The mu(I) friction law, its well-posedness, and its partial regularisation.

The plain law of Jop, Forterre & Pouliquen (2006), with the high-I term of
Barker & Gray (2017),

    mu(I) = (mu_s I0 + mu_2 I + mu_inf I^2) / (I0 + I),   mu_2 = mu_s + delta_mu,

makes the incompressible equations ill-posed where

    C(I) = 4 nu^2 - 4 nu + mu^2 (1 - nu/2)^2 >= 0,   nu = I mu'(I) / mu(I)

(Barker, Schaeffer, Bohorquez & Gray 2015, eq. 3.9): always at low I, and at
high I unless mu_inf > 0. Barker & Gray's partial regularisation replaces the
law below the lower bound I1 of its well-posed range by

    mu(I) = sqrt(alpha / ln(A / I)),   A = I1 exp(alpha / mu(I1)^2),

well posed for alpha < 2 (they take 1.9). siloFoam's ``muIRegularised``
model computes I1 and A the same way; the Bagnold verification compares the two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from scipy.optimize import brentq

from foamsilo.errors import FoamsiloError

#: Barker & Gray's (2017) exponent of the low-I curve
BARKER_GRAY_ALPHA = 1.9
# the scan for the well-posed range: I from 1e-12 to 1e3
_I_SCAN = tuple(1e-12 * 10 ** (15 * k / 1500) for k in range(1501))


@dataclass(frozen=True)
class FrictionLaw:
    """A mu(I) friction law: plain (``alpha`` None) or partially regularised."""

    mu_s: float
    delta_mu: float
    i0: float
    mu_inf: float = 0.0
    alpha: float | None = None

    def __post_init__(self) -> None:
        if self.alpha is not None and not 0 < self.alpha < 2:
            raise FoamsiloError(
                f"alpha = {self.alpha:g}: allowed 0 < alpha < 2 (the low-I curve is "
                "ill-posed above 2)"
            )

    def plain(self, i: float) -> float:
        """Return the law above I1 (everywhere when not regularised)."""
        return (self.mu_s * self.i0 + (self.mu_s + self.delta_mu) * i + self.mu_inf * i * i) / (
            self.i0 + i
        )

    def well_posedness(self, i: float) -> float:
        """C(I) of the plain law: negative where the equations are well posed."""
        d = (self.delta_mu * self.i0 + self.mu_inf * i * (i + 2 * self.i0)) / (self.i0 + i) ** 2
        mu = self.plain(i)
        nu = i * d / mu
        return 4 * nu * nu - 4 * nu + mu * mu * (1 - nu / 2) ** 2

    # computed once per law: mu() and inertial_number() use both in every call
    @cached_property
    def i1(self) -> float:
        """Lower bound of the plain law's well-posed range.

        Raises
        ------
        FoamsiloError
            The law is ill-posed at every I from 1e-12 to 1e3.
        """
        prev = _I_SCAN[0]
        for i in _I_SCAN[1:]:
            if self.well_posedness(i) < 0:
                return float(brentq(self.well_posedness, prev, i, xtol=1e-14, rtol=1e-12))
            prev = i
        raise FoamsiloError(
            f"the mu(I) law (mu_s {self.mu_s:g}, delta_mu {self.delta_mu:g}, I0 {self.i0:g}, "
            f"mu_inf {self.mu_inf:g}) is ill-posed at every I: nothing to regularise"
        )

    @cached_property
    def a(self) -> float:
        """A of the low-I curve (regularised laws only)."""
        if self.alpha is None:
            raise FoamsiloError("a plain mu(I) law has no low-I curve")
        return self.i1 * math.exp(self.alpha / self.plain(self.i1) ** 2)

    def mu(self, i: float) -> float:
        """Return the friction coefficient at I > 0."""
        if self.alpha is not None and i < self.i1:
            return math.sqrt(self.alpha / math.log(self.a / i))
        return self.plain(i)

    def inertial_number(self, mu: float) -> float:
        """Return the I at which mu(I) = ``mu``.

        Raises
        ------
        FoamsiloError
            ``mu`` outside the law's range: below mu_s for the plain law (the
            grains stay at rest), at or above mu_2 with mu_inf = 0 (no I is
            large enough).
        """
        top = math.inf if self.mu_inf > 0 else self.mu_s + self.delta_mu
        bottom = 0.0 if self.alpha is not None else self.mu_s
        if not bottom < mu < top:
            raise FoamsiloError(
                f"mu = {mu:.4g} must lie in ({bottom:g}, {top:g}), the range of this mu(I) law"
            )
        if self.alpha is not None and mu < self.plain(self.i1):
            return self.a * math.exp(-self.alpha / mu**2)
        if self.mu_inf == 0:
            return self.i0 * (mu - self.mu_s) / (self.mu_s + self.delta_mu - mu)
        hi = 1.0
        while self.plain(hi) < mu:
            hi *= 10
        return float(brentq(lambda i: self.plain(i) - mu, 0.0, hi, xtol=1e-15, rtol=1e-13))
