"""The validation suite's reductions, on exactly known numbers (the runs are `foamsilo bench`)."""

from __future__ import annotations

import numpy as np
import pytest

from foamsilo.studies.suite import _recommend, beverloo_fit, checks, derive_work_precision


@pytest.mark.parametrize(("exponent", "C", "f"), [(2.5, 3871.0, 0.0062), (1.5, 1.135e4, 0.0025)])
def test_beverloo_fit_recovers_c_and_f(exponent, C, f):
    d = np.array([0.03, 0.045, 0.06, 0.09, 0.12])
    fit = beverloo_fit(d, C * (d - f) ** exponent, exponent)
    assert fit["C"] == pytest.approx(C, rel=1e-9)
    assert fit["f"] == pytest.approx(f, rel=1e-9)
    assert fit["R2"] == pytest.approx(1.0, abs=1e-12)


def test_recommended_resolution_is_the_coarsest_that_stays_within():
    cells = [16, 24, 32, 48, 64]
    err = [0.064, 0.019, 0.021, 0.008, 0.0]  # against the finest
    assert _recommend(cells, err, 0.05) == 24
    assert _recommend(cells, err, 0.02) == 48
    assert _recommend(cells, err, 0.001) is None


def test_work_precision_extrapolates_and_projects_the_cost():
    # Q = 0.034 - 0.3 / N (first order), CPU per simulated second = 1e-4 N^3
    cells = [36, 48, 72, 96]
    rows = [
        {"cells_across": n, "Q": 0.034 - 0.3 / n, "outcome": "steady",
         "cpu_s": 0.6 * 1e-4 * n**3, "simulated_time_s": 0.6}
        for n in cells
    ]  # fmt: skip
    rows.insert(0, {"cells_across": 24, "Q": None, "outcome": "stopped: diverged"})
    data = {"Q_law": 0.0208, "rows": rows}
    derive_work_precision(data)
    conv = data["convergence"]
    assert conv["cells"] == cells  # the diverged row is left out
    assert conv["order"] == pytest.approx(1.0, rel=1e-9)
    assert conv["extrapolated"] == pytest.approx(0.034, rel=1e-9)
    assert rows[-1]["err_vs_extrapolated"] == pytest.approx(-0.3 / 96 / 0.034, rel=1e-9)
    assert rows[0]["err_vs_extrapolated"] is None
    n1 = 0.3 / 0.034 / 0.01  # where |e| = 1%
    assert conv["cells_for_1pct"] == pytest.approx(n1, rel=1e-9)
    assert conv["cost_exponent"] == pytest.approx(3.0, rel=1e-9)
    assert conv["cpu_per_simulated_s_for_1pct"] == pytest.approx(1e-4 * n1**3, rel=1e-6)


def test_checks_flag_a_figure_outside_its_tolerance():
    rows = [
        {"cells_across": n, "Q": q, "Q_dimensionless": qd, "flux_vs_volume_rel_diff": e}
        for n, q, qd, e in (
            (36, 0.0254, 0.54, 0.001),
            (48, 0.0277, 0.59, 0.002),
            (72, 0.0299, 0.64, 0.03),
        )
    ]
    result = {
        "work-precision": {
            "zhou-planar": {"rows": [{"cells_across": 16, "Q_dimensionless": 0.12}]},
            "zhou-cyl-bottom": {"rows": rows},
        }
    }
    by_name = {c.name: c for c in checks(result)}
    assert not by_name["planar 16 across: Q*"].passed  # 0.12 is outside 0.16 +- 15%
    assert by_name["lab silo: Q rises with resolution"].passed
    assert by_name["lab silo, 36 across: |Q flux / Q volume - 1|"].passed
    # two estimates of one rate 3% apart: the check fails (tolerance 1%)
    assert not by_name["lab silo, 72 across: |Q flux / Q volume - 1|"].passed
    rows[-1]["Q"] = None  # a run that stopped has no rate: the check fails, not crashes
    by_name = {c.name: c for c in checks(result)}
    assert not by_name["lab silo: Q rises with resolution"].passed
