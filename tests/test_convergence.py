"""Grid convergence (observed order, Richardson extrapolation, GCI) on exact series.

A series phi(n) = phi_inf + C n^-p is what the procedure assumes; on it the
order and the extrapolation must come back to round-off, with equal and with
unequal refinement ratios (the suite's 36, 48, 72, 96 across).
"""

from __future__ import annotations

import pytest

from foamsilo.errors import FoamsiloError
from foamsilo.post.convergence import grid_convergence


def series(cells, p, phi_inf=0.034, c=-0.3):
    return [phi_inf + c * n ** (-p) for n in cells]


def assert_richardson(g, cells, values, p, safety):
    """The extrapolation and the GCI of the two finest grids at order ``p``."""
    rp = (cells[-1] / cells[-2]) ** p
    assert g.order_used == p
    assert g.extrapolated == pytest.approx((rp * values[-1] - values[-2]) / (rp - 1), rel=1e-12)
    assert g.gci == pytest.approx(safety * abs(values[-2] / values[-1] - 1) / (rp - 1), rel=1e-12)


@pytest.mark.parametrize("cells", [[10, 20, 40, 80], [36, 48, 72, 96], [16, 24, 32, 48, 64, 96]])
@pytest.mark.parametrize("p", [1.0, 1.5, 2.0])
def test_exact_series_recovered(cells, p):
    g = grid_convergence(cells, series(cells, p))
    assert g.kind == "monotone"
    assert g.order == pytest.approx(p, rel=1e-9)
    assert g.extrapolated == pytest.approx(0.034, rel=1e-9)
    assert all(o == pytest.approx(p, rel=1e-9) for o in g.orders_by_triple)
    # the GCI is 1.25 times the finest grid's true error (relative to its own value)
    fine = series(cells, p)[-1]
    assert g.gci == pytest.approx(1.25 * abs(fine - 0.034) / abs(fine), rel=1e-9)


def test_resolution_for_a_level():
    cells = [36, 48, 72, 96]
    g = grid_convergence(cells, series(cells, 1.0))
    # |e(n)| = 0.3 / (0.034 n): 1% at n = 0.3 / 0.034 / 0.01 = 882
    assert g.cells_for(0.01) == pytest.approx(0.3 / 0.034 / 0.01, rel=1e-9)
    assert g.coarsest_within(0.2) == 48  # e(48) = 18.4%, e(36) = 24.5%
    assert g.coarsest_within(0.01) is None
    d = g.as_dict()
    assert d["cells_for_2pct"] == pytest.approx(0.3 / 0.034 / 0.02, rel=1e-9)


def test_oscillatory_series_has_no_order():
    g = grid_convergence([16, 32, 64], [1.0, 1.02, 0.99])
    assert g.kind == "oscillatory"
    assert g.order is None and g.extrapolated is None
    assert g.gci == pytest.approx(0.015 / 0.99)
    assert g.cells_for(0.01) is None


def test_converged_series():
    g = grid_convergence([16, 32, 64], [1.1, 1.0, 1.0])
    assert g.kind == "converged" and g.gci == 0.0 and g.extrapolated == 1.0


@pytest.mark.parametrize(
    ("cells", "values", "match"),
    [
        ([16, 32], [1.0, 1.1], "three or more"),
        ([32, 16, 64], [1.0, 1.1, 1.2], "must increase"),
        ([16, 32, 64], [1.0, float("nan"), 1.2], r"\[32\]"),
    ],
)
def test_bad_series_refused(cells, values, match):
    with pytest.raises(FoamsiloError, match=match):
        grid_convergence(cells, values)


def test_an_order_above_the_formal_one_is_not_trusted():
    # three grids falling as n^-3 (faster than the second-order scheme can):
    # the observed order is reported, the extrapolation and the GCI take 2
    cells = [28, 40, 56]
    values = series(cells, 3.0)
    g = grid_convergence(cells, values)
    assert g.order == pytest.approx(3.0, rel=1e-9)
    rp = (56 / 40) ** 2
    assert g.order_used == 2.0
    assert g.extrapolated == pytest.approx((rp * values[2] - values[1]) / (rp - 1), rel=1e-12)
    # the GCI: 1.25 times the three grids' range (Eca & Hoekstra), here wider
    # than the formal order's index from the finest increment alone
    at_formal = 1.25 * abs(values[1] / values[2] - 1) / (rp - 1)
    data_range = 1.25 * (values[2] - values[0]) / values[2]
    assert data_range > 3 * at_formal
    assert g.gci == pytest.approx(data_range, rel=1e-12)
    # wider than the n^-3 model's own index, and beyond the true value
    true_gci = 1.25 * abs(values[2] - 0.034) / abs(values[2])
    assert g.gci > 1.5 * true_gci
    assert g.extrapolated > 0.034 > values[2]  # the lower order extrapolates further
    assert g.cells_for(0.01) == pytest.approx(
        56 * (abs(g.error_vs_extrapolated[-1]) / 0.01) ** 0.5, rel=1e-12
    )
    # an order below the formal one is taken as observed
    lower = grid_convergence(cells, series(cells, 1.2))
    assert lower.order_used == pytest.approx(lower.order, rel=1e-12)
    assert_richardson(lower, cells, series(cells, 1.2), lower.order, 1.25)
    with pytest.raises(FoamsiloError, match="formal_order"):
        grid_convergence(cells, values, formal_order=0.0)


def test_an_order_near_zero_is_not_trusted():
    # a rate that creeps up by about the same step per refinement (observed
    # order near 0, not yet asymptotic): its own order would extrapolate far
    # beyond every grid, so first order with Eca & Hoekstra's safety factor 3
    cells = [64, 96, 128]
    values = series(cells, 0.2)
    g = grid_convergence(cells, values)
    assert g.order == pytest.approx(0.2, rel=1e-9)
    assert_richardson(g, cells, values, 1.0, 3.0)
    r = 128 / 96
    own = (r**0.2 * values[2] - values[1]) / (r**0.2 - 1)
    assert abs(g.extrapolated - values[2]) < abs(own - values[2]) / 4
    # from LOW_ORDER up the observed order is taken
    assert grid_convergence(cells, series(cells, 0.6)).order_used == pytest.approx(0.6, rel=1e-9)


@pytest.mark.parametrize("cells", [[10, 20, 40], [30, 36, 40], [36, 48, 72, 96]])
@pytest.mark.parametrize("p", [-1.0, -0.3])
def test_a_diverging_series_gets_its_negative_order(cells, p):
    # increments that grow as the grid is refined (phi ~ C n^|p|): Celik's
    # eq. 3 with its absolute value gave such a series a positive order (with
    # equal ratios |p|; with 30/36/40 across even one above 2, whose
    # extrapolation and GCI at the formal order then looked converged)
    values = series(cells, p)
    g = grid_convergence(cells, values)
    assert g.kind == "monotone"
    assert g.order == pytest.approx(p, rel=1e-9)
    # not in the asymptotic range: first order and the safety factor 3
    assert_richardson(g, cells, values, 1.0, 3.0)


def test_equal_increments_over_shrinking_ratios_get_no_positive_order():
    # the 3D lateral silo's three regular grids (refinement ratios 1.2 and
    # 1.11): its increments per refinement are nearly equal, that is they
    # shrink more slowly than any positive order allows over these ratios
    g = grid_convergence([30, 36, 40], [0.095362, 0.09619, 0.097009])
    assert g.order is not None and g.order < 0
    assert g.order_used == 1.0 and g.gci > 0.2


def test_the_report_says_when_the_gci_is_the_data_range():
    from foamsilo.studies.suite import _convergence_words

    cells = [28, 40, 56]
    fast = _convergence_words(grid_convergence(cells, series(cells, 3.0)).as_dict())
    assert "take p = 2" in fast and "three grids' range" in fast
    # at the formal order, or under it, the GCI is Roache's alone
    for p in (2.0, 1.2):
        words = _convergence_words(grid_convergence(cells, series(cells, p)).as_dict())
        assert "three grids' range" not in words


@pytest.mark.parametrize(("cells", "p"), [([36, 48, 72, 96], 1.5), ([40, 48, 56], 1.0),
                                          ([104, 144, 192], 1.2)])  # fmt: skip
def test_the_extrapolations_time_error_is_its_rows_noise_carried_through(cells, p):
    """The propagated error is the spread of extrapolations from noisy rows (Monte Carlo).

    Rows of an exact series, each given a time-averaging noise of 0.001%,
    small beside the increments (a first-order propagation is what is
    checked): the standard deviation of the extrapolations of 4,000 noisy
    draws is the propagated error to 5% (the Monte Carlo's own error is
    1.1%). Every error zero: zero; a missing one: none. (At the suite's
    0.05% the draws spread up to 20% more than the first-order figure: the
    order's estimate is not linear over such noise.)
    """
    import numpy as np

    from foamsilo.post.convergence import extrapolation_time_error

    values = series(cells, p)
    se = [1e-5 * abs(v) for v in values]
    rng = np.random.default_rng(1)
    draws = []
    for _ in range(4000):
        noisy = [v + s * z for v, s, z in zip(values, se, rng.standard_normal(len(values)),
                                              strict=True)]  # fmt: skip
        ext = grid_convergence(cells, noisy).extrapolated
        if ext is not None:
            draws.append(ext)
    assert len(draws) > 3900
    mc = float(np.std(draws)) / abs(grid_convergence(cells, values).extrapolated)
    assert extrapolation_time_error(cells, values, se) == pytest.approx(mc, rel=0.05)
    assert extrapolation_time_error(cells, values, [0.0] * len(cells)) == 0.0
    assert extrapolation_time_error(cells, values, [*se[:-1], None]) is None


def test_the_report_gives_the_extrapolations_time_error():
    from foamsilo.studies.suite import _convergence_words

    cells = [36, 48, 72, 96]
    conv = grid_convergence(cells, series(cells, 1.5)).as_dict()
    assert "time averages alone move the extrapolation by 1.23%" in _convergence_words(
        {**conv, "extrapolated_time_error": 0.0123}
    )
    assert "its time error is not known" in _convergence_words(
        {**conv, "extrapolated_time_error": None}
    )
