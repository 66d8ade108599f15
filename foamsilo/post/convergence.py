"""Grid convergence of a scalar: observed order, Richardson extrapolation, GCI.

The procedure of Celik et al. 2008 ("Procedure for estimation and reporting
of uncertainty due to discretization in CFD applications", J. Fluids Eng.
130, 078001), built on Roache's grid convergence index (GCI, Roache 1994,
J. Fluids Eng. 116, 405): from the three finest of a series of grids, with
possibly unequal refinement ratios,

* the observed order p, the root of ``p ln r21 = ln(e32/e21) + q(p)``,
  ``q(p) = ln((r21^p - 1) / (r32^p - 1))`` (Celik's eq. 3 for monotone
  convergence, s = 1, without its absolute value, which gave a positive
  order to increments that shrink too slowly for any: such a series has a
  negative order here, and is treated as one under 0.5, below);
* the extrapolated value ``phi_ext = (r21^p phi1 - phi2) / (r21^p - 1)``;
* the fine-grid index ``GCI = 1.25 |phi1 - phi2| / |phi1| / (r21^p - 1)``
  (1.25: Roache's safety factor for a three-grid study).

An observed order above the scheme's formal order is not trusted: three grids
that happen to fall faster than the scheme can converge would put the
extrapolation next to the finest value and shrink the GCI. The extrapolation,
the GCI and the resolution for a level then take the formal order,
``p = min(p_observed, p_formal)`` (Roache 1998, *Verification and Validation
in Computational Science and Engineering*, sec. 5.9; the observed order is
still reported). From 0.05 above it (Eca & Hoekstra 2014, below: their
2.05 for a second-order scheme) the GCI is at least 1.25 times the range of
the three values, relative to the finest (their uncertainty for such an
order), because increments that fall faster than the scheme allows say
that the grids are not in the asymptotic range, where the formal order's
GCI, computed from the smallest increment alone, would claim the most.

An observed order under 0.5 is not trusted either: the grids are not yet in
the asymptotic range, and as p falls to 0 the extrapolation runs off to
infinity. Such a series is extrapolated at first order, with the safety
factor 3 (Eca & Hoekstra 2014, "A procedure for the estimation of the
numerical uncertainty of CFD calculations based on grid refinement
studies", J. Comput. Phys. 262, 104: their factor for data whose observed
order is off the theoretical one).

Oscillatory convergence (e32 / e21 < 0) has no order; its uncertainty is half
the range of the three values (Stern et al. 2001, J. Fluids Eng. 123, 793).
A grid is described by its number of cells across (h ~ 1 / n).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from scipy.optimize import brentq

from foamsilo.errors import FoamsiloError

#: Roache's safety factor for a study of three or more grids
SAFETY_FACTOR = 1.25
#: Below this observed order a series is not in its asymptotic range
#: (Eca & Hoekstra 2014): first order and ``LOW_ORDER_SAFETY_FACTOR`` are used
LOW_ORDER = 0.5
LOW_ORDER_SAFETY_FACTOR = 3.0
#: The scheme's formal order in space (Gauss linear: second order; the code
#: verification measures it, docs/validation/verification.md)
FORMAL_ORDER = 2.0
#: An observed order this far above the formal one takes the data range as its
#: least GCI (Eca & Hoekstra 2014: 2.05 for a second-order scheme)
ABOVE_FORMAL = 0.05
#: The order's bracket: its ends
_ORDER_EPS = 1e-9
_ORDER_MAX = 64.0


def range_bounds_gci(order: float, formal_order: float = FORMAL_ORDER) -> bool:
    """Whether an order is far enough above the formal one for the range rule.

    From ``formal_order + ABOVE_FORMAL`` the GCI is at least 1.25 times the
    three finest values' range (Eca & Hoekstra 2014).
    """
    return order >= formal_order + ABOVE_FORMAL


@dataclass(frozen=True)
class GridConvergence:
    """The grid convergence of one scalar over a series of grids.

    Attributes
    ----------
    cells : list of int
        Cells across, coarsest first.
    values : list of float
        The scalar on each grid.
    kind : str
        ``monotone``, ``oscillatory`` or ``converged`` (the two finest agree
        to round-off), judged on the three finest grids.
    order : float or None
        Observed order p (monotone only).
    extrapolated : float or None
        Richardson-extrapolated value (monotone only), with ``order_used``.
    gci : float or None
        Relative uncertainty of the finest value: the fine-grid GCI
        (monotone; with an order above the formal one, at least 1.25 times
        the relative range of the three finest), half the relative range of
        the three finest (oscillatory).
    error_vs_extrapolated : list of float or None
        ``value / extrapolated - 1`` on each grid.
    orders_by_triple : list of float or None
        The order from each run of three consecutive grids: a series in its
        asymptotic range gives about the same p throughout.
    order_used : float or None
        The order the extrapolation, the GCI and :meth:`cells_for` take: the
        observed one, at most the formal order; first order where the
        observed one is under ``LOW_ORDER`` (monotone only).
    """

    cells: list[int]
    values: list[float]
    kind: str
    order: float | None
    extrapolated: float | None
    gci: float | None
    error_vs_extrapolated: list[float] | None
    orders_by_triple: list[float | None]
    order_used: float | None = None

    def cells_for(self, level: float) -> float | None:
        """Cells across at which the error against the extrapolation falls to ``level``.

        From the error model ``|e(n)| = |e(n1)| (n1 / n)^p`` anchored on the
        finest grid; a value above the finest grid is a projection. None
        without an order.
        """
        p = self.order_used
        if p is None or self.error_vs_extrapolated is None or p <= 0:
            return None
        e1 = abs(self.error_vs_extrapolated[-1])
        if e1 == 0.0:
            return float(self.cells[-1])
        return self.cells[-1] * (e1 / level) ** (1.0 / p)

    def coarsest_within(self, level: float) -> int | None:
        """Coarsest measured grid from which this and every finer one are within ``level``."""
        err = self.error_vs_extrapolated
        return None if err is None else coarsest_within(self.cells, err, level)

    def as_dict(self) -> dict[str, Any]:
        """Plain data, with the 1% and 2% resolutions."""
        out = asdict(self)
        for level in (0.02, 0.01):
            key = f"{round(level * 100)}pct"
            out[f"cells_for_{key}"] = self.cells_for(level)
            out[f"coarsest_within_{key}"] = self.coarsest_within(level)
        return out


def coarsest_within(cells: list[int], errors: list[float], level: float) -> int | None:
    """Return the coarsest grid from which it and every finer one have |error| <= ``level``."""
    for i, n in enumerate(cells):
        if all(abs(e) <= level for e in errors[i:]):
            return n
    return None


def _increment_ratio(r21: float, r32: float, p: float) -> float:
    """Return the ratio e32 / e21 that an error C h^p gives on three grids (p != 0)."""
    return r21**p * (r32**p - 1) / (r21**p - 1)


def _order(r21: float, r32: float, e21: float, e32: float) -> float | None:
    """Observed order of three grids (Celik et al. 2008, eqs. 3-4); None when not monotone.

    The order solves ``e32 / e21 = r21^p (r32^p - 1) / (r21^p - 1)``, Celik's
    eq. 3 without its absolute value (Brent's method): the ratio rises with p,
    from 0 (p -> -inf) through ``ln r32 / ln r21`` (p -> 0). With the
    absolute value a series whose increments shrink more slowly than any
    positive order allows (its refinement ratios unequal, or its increments
    growing) got a positive order, even a high one; here its order is
    negative (not in the asymptotic range, or diverging).
    """
    ratio = e32 / e21
    if ratio <= 0:
        return None
    at_zero = math.log(r32) / math.log(r21)
    if ratio == at_zero:
        return 0.0
    # the root lies on the side of p = 0 the ratio says (the model ratio rises with p)
    lo, hi = (_ORDER_EPS, _ORDER_MAX) if ratio > at_zero else (-_ORDER_MAX, -_ORDER_EPS)
    miss = [_increment_ratio(r21, r32, p) - ratio for p in (lo, hi)]
    if miss[1] < 0:
        return _ORDER_MAX
    if miss[0] > 0:
        return -_ORDER_MAX
    return float(brentq(lambda p: _increment_ratio(r21, r32, p) - ratio, lo, hi, xtol=1e-13))


def grid_convergence(
    cells: list[int], values: list[float], formal_order: float = FORMAL_ORDER
) -> GridConvergence:
    """Return the grid convergence of ``values`` over grids of ``cells`` across.

    Parameters
    ----------
    cells : list of int
        Cells across each grid, strictly increasing (at least three).
    values : list of float
        The scalar on each grid, finite and nonzero.
    formal_order : float
        The scheme's order: an observed order above it is replaced by it in
        the extrapolation and the GCI.

    Raises
    ------
    FoamsiloError
        Fewer than three grids, grids not strictly refining, or a value
        that is missing, zero or not finite.
    """
    if len(cells) != len(values) or len(cells) < 3:
        raise FoamsiloError(
            f"grid convergence needs three or more grids with a value each; "
            f"got {len(cells)} grids and {len(values)} values"
        )
    if not formal_order > 0:
        raise FoamsiloError(f"grid convergence: formal_order {formal_order}; allowed: > 0")
    if any(b <= a for a, b in zip(cells, cells[1:], strict=False)):
        raise FoamsiloError(f"grid convergence: cells across must increase; got {cells}")
    bad = [n for n, v in zip(cells, values, strict=True) if not math.isfinite(v) or v == 0]
    if bad:
        raise FoamsiloError(f"grid convergence: no finite nonzero value at {bad} cells across")
    triples = []
    for i in range(len(cells) - 2):
        n3, n2, n1 = cells[i : i + 3]
        f3, f2, f1 = values[i : i + 3]
        e21, e32 = f2 - f1, f3 - f2
        ok = e21 != 0 and e32 != 0
        triples.append(_order(n1 / n2, n2 / n3, e21, e32) if ok else None)
    n3, n2, n1 = cells[-3:]
    f3, f2, f1 = values[-3:]
    e21, e32 = f2 - f1, f3 - f2
    if abs(e21) <= 1e-12 * abs(f1):
        return GridConvergence(list(cells), list(values), "converged", None, f1, 0.0,
                               [v / f1 - 1 for v in values], triples)  # fmt: skip
    p = _order(n1 / n2, n2 / n3, e21, e32) if e32 != 0 else None
    if p is None:
        half_range = (max(values[-3:]) - min(values[-3:])) / 2 / abs(f1)
        return GridConvergence(list(cells), list(values), "oscillatory", None, None,
                               half_range, None, triples)  # fmt: skip
    low = p < LOW_ORDER
    used = min(1.0 if low else p, formal_order)
    rp = (n1 / n2) ** used
    ext = (rp * f1 - f2) / (rp - 1)
    safety = LOW_ORDER_SAFETY_FACTOR if low else SAFETY_FACTOR
    gci = safety * abs(e21 / f1) / (rp - 1)
    if range_bounds_gci(p, formal_order):  # not asymptotic: at least the data's own range
        gci = max(gci, SAFETY_FACTOR * (max(values[-3:]) - min(values[-3:])) / abs(f1))
    errors = [v / ext - 1 for v in values]
    return GridConvergence(
        list(cells), list(values), "monotone", p, ext, gci, errors, triples, used
    )


def extrapolation_time_error(
    cells: list[int],
    values: list[float],
    errors: list[float | None],
    formal_order: float = FORMAL_ORDER,
) -> float | None:
    """Return the standard error of the extrapolated value from the values' own errors.

    Each grid's value is a time average with a standard error (the batch
    means of its steady window); the extrapolation from the three finest
    grids amplifies them, by 1 / (r^p - 1) and through the observed order
    they set. Propagated to first order: each of the three values is moved
    by its error both ways, the extrapolation (order re-estimated) taken
    again, and the central differences added in quadrature (the runs'
    averages are independent).

    Parameters
    ----------
    cells, values, formal_order
        As :func:`grid_convergence`.
    errors : list of float or None
        Each value's standard error (absolute).

    Returns
    -------
    float or None
        The extrapolation's standard error, relative to the extrapolated
        value; None when the three finest grids have no extrapolation, an
        error is missing, or a value moved by its error leaves none (the
        series' kind changes within its own noise: no linear propagation).
    """
    base = grid_convergence(cells, values, formal_order).extrapolated
    last = errors[-3:]
    if base is None or len(last) < 3 or any(e is None or not math.isfinite(e) for e in last):
        return None
    total = 0.0
    for i in range(len(values) - 3, len(values)):
        e = errors[i]
        assert e is not None
        moved = []
        for sign in (1.0, -1.0):
            v = list(values)
            v[i] += sign * e
            moved.append(grid_convergence(cells, v, formal_order).extrapolated)
        up, down = moved
        if up is None or down is None:
            return None
        total += ((up - down) / 2) ** 2
    return math.sqrt(total) / abs(base)
