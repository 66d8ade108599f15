"""The validation suite's reductions, on exactly known numbers (the runs are `foamsilo bench`)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from foamsilo.errors import FoamsiloError
from foamsilo.scene import load_preset
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
        {
            "cells_across": n,
            "Q": q,
            "Q_dimensionless": qd,
            "flux_vs_volume_rel_diff": e,
            "outcome": "steady",
        }
        for n, q, qd, e in (
            (36, 0.0254, 0.54, 0.001),
            (48, 0.0277, 0.59, 0.002),
            (72, 0.0299, 0.64, 0.03),
        )
    ]
    result = {
        "work-precision": {
            "zhou-planar": {"rows": [
                {"cells_across": 16, "Q_dimensionless": 0.12, "outcome": "steady"},
                {"cells_across": 24, "Q_dimensionless": 0.154, "outcome": "steady"},
                {"cells_across": 32, "Q_dimensionless": 0.157, "outcome": "oscillating"},
            ]},
            "zhou-cyl-bottom": {"rows": rows},
        }
    }  # fmt: skip
    by_name = {c.name: c for c in checks(result)}
    assert not by_name["planar 16 across: Q*"].passed  # 0.12 is outside 0.16 +- 15%
    assert by_name["planar 24 across: Q*"].passed
    assert not by_name["planar 32 across: Q*"].passed  # an oscillating rate is no Q*
    assert by_name["lab silo: Q rises with resolution"].passed
    assert by_name["lab silo, 36 across: |Q flux / Q volume - 1|"].passed
    # two estimates of one rate 3% apart: the check fails (tolerance 1%)
    assert not by_name["lab silo, 72 across: |Q flux / Q volume - 1|"].passed
    rows[-1]["Q"] = None  # a run that stopped has no rate: the check fails, not crashes
    by_name = {c.name: c for c in checks(result)}
    assert not by_name["lab silo: Q rises with resolution"].passed
    rows[-1]["Q"], rows[-1]["outcome"] = 0.0301, "oscillating"  # rising, but no rate
    by_name = {c.name: c for c in checks(result)}
    assert not by_name["lab silo: Q rises with resolution"].passed


def test_report_rewritten_from_the_json_alone(tmp_path):
    import json

    from foamsilo.studies.suite import rewrite_report

    def rows(cells, q_inf, c):
        return [{"cells_across": n, "Q": q_inf - c / n, "Q_dimensionless": 0.16, "outcome":
                 "steady", "case_dir": str(tmp_path / "gone"), "flux_vs_volume_rel_diff": 0.001,
                 "wall_s": float(n)}
                for n in cells]  # fmt: skip

    result = {
        "quick": False, "jobs": 2, "commit": "abc", "wall_s": {"work-precision": 60.0},
        "machine": {"cpu": "test", "cores": 2, "date": "2026-12-01"},
        "work-precision": {
            "zhou-planar": {"law": "beverloo-2d", "Q_law": 40.0,
                            "rows": rows([16, 32, 64], 41.0, 80.0)},
            "zhou-cyl-bottom": {"law": "zhou-eq1", "Q_law": 0.0208,
                                "rows": rows([36, 48, 72], 0.034, 0.3)},
            # a hopper has no analytic law (its entry: law = false)
            "hopper-conical": {"law": None, "Q_law": None,
                               "rows": rows([40, 80, 160], 0.61, 1.0)},
        },
        # a row that needed recoveries says so beside its rate
        "time-step": {"scenes": [{"label": "recovered", "rows": [
            {"courant": 0.5, "outcome": "steady", "Q": 0.615, "Q_std": 0.001,
             "Q_step_swing": 1e-4, "dt_median": 1.5e-3, "steps": 908, "recoveries": 2,
             "cpu_s": 13.0}]}]},
    }  # fmt: skip
    (tmp_path / "suite.json").write_text(json.dumps(result))
    out = rewrite_report(False, tmp_path)
    # the grid study is derived again from the rows: Q = Q_inf - C / N is first order
    conv = out["work-precision"]["zhou-cyl-bottom"]["convergence"]
    assert conv["order"] == pytest.approx(1.0, rel=1e-9)
    assert conv["extrapolated"] == pytest.approx(0.034, rel=1e-9)
    md = (tmp_path / "suite.md").read_text()
    assert "extrapolated Q = 0.034" in md and "observed order p = 1.00" in md
    assert "| steps | recoveries | CPU [s] |" in md
    assert "**hopper-conical** (no analytic law)" in md
    assert out["work-precision"]["hopper-conical"]["convergence"]["extrapolated"] == pytest.approx(
        0.61, rel=1e-9)  # fmt: skip
    assert "| 0.0015 | 908 | 2 | 13 |" in md
    with pytest.raises(FoamsiloError, match="no suite results"):
        rewrite_report(True, tmp_path)


def test_one_work_precision_series_is_named_and_a_wrong_one_listed(tmp_path):
    from foamsilo.studies.cases import study_table
    from foamsilo.studies.suite import run_suite, work_precision_series

    names = work_precision_series()
    assert {"zhou-planar", "zhou-cyl-bottom", "zhou-cyl-bottom-graded"} <= set(names)
    # the graded series are in the full suite only (no quick_values)
    entries = dict(zip(names, study_table("suite")["work-precision"], strict=True))
    assert "quick_values" not in entries["zhou-cyl-bottom-graded"]
    with pytest.raises(
        FoamsiloError, match=r"work-precision/nope.*work-precision/zhou-planar-graded"
    ):
        run_suite(False, tmp_path, tmp_path, only=["work-precision/nope"])
    with pytest.raises(FoamsiloError, match=r"'beverloo/venier'"):
        run_suite(False, tmp_path, tmp_path, only=["beverloo/venier"])
    with pytest.raises(FoamsiloError, match=r"'presets/nope'.*presets/zhou-cyl-lateral"):
        run_suite(False, tmp_path, tmp_path, only=["presets/nope"])
    assert not any(tmp_path.iterdir())  # refused before anything ran or was written


def test_time_step_rows_are_judged_against_the_default_step():
    from foamsilo.studies.suite import derive_time_step

    def row(c, q, outcome="steady", q_std=1e-5):
        return {"courant": c, "Q": q, "Q_std": q_std, "outcome": outcome}

    scenes = [
        {"label": "converged", "rows": [row(0.5, 0.0300), row(0.25, 0.02991)]},
        # a smaller step drops Q by 4% and makes it swing by 2.4%: both visible
        {"label": "step-bound", "rows": [row(0.5, 0.0310), row(0.25, 0.02976, q_std=7.1e-4)]},
        {"label": "stopped", "rows": [row(0.5, 0.0300), row(0.25, None, "stopped: diverged")]},
    ]
    data = {"scenes": scenes}
    derive_time_step(data)
    assert scenes[0]["rows"][1]["vs_default_step"] == pytest.approx(-0.003, rel=1e-9)
    assert scenes[1]["rows"][1]["vs_default_step"] == pytest.approx(-0.04, rel=1e-9)
    assert scenes[1]["rows"][1]["spread"] == pytest.approx(7.1e-4 / 0.02976, rel=1e-9)
    by_name = {c.name: c for c in checks({"time-step": data})}
    assert by_name["converged, Courant 0.25: Q against Courant 0.5"].passed  # -0.3%, within 1%
    assert not by_name["step-bound, Courant 0.25: Q against Courant 0.5"].passed
    assert not by_name["stopped, Courant 0.25: Q against Courant 0.5"].passed  # no Q: fails
    assert len(by_name) == 3  # the reference rows are not checked against themselves


def test_a_rate_swinging_from_step_to_step_is_no_steady_outcome(tmp_path):
    from foamsilo.pipeline import CaseSpec, Outcome
    from foamsilo.studies.cases import _outcome_words

    spec = CaseSpec(tmp_path, "zhou-planar")

    def words(swing):
        return _outcome_words(Outcome(spec, "ok", {"steady": True, "Q_step_swing": swing}))

    assert words(0.004) == ("steady", "")
    word, detail = words(0.22)  # the lagged gas-assisted lab silo's swing
    assert word == "oscillating" and "22.0%" in detail
    assert _outcome_words(Outcome(spec, "ok", {"steady": False, "steady_reason": "drift"}))[0] == (
        "not steady"
    )


def test_gas_rows_are_judged_on_eq17_with_their_own_zone_gradient():
    from foamsilo.studies.suite import derive_gas_lab

    def row(q_air, q, zone=None, outcome="steady", swing=0.0):
        return {"label": f"{q_air}", "grain_diameter": 538e-6, "q_air_lpm": q_air, "Q": q,
                "outcome": outcome, "zone_gradient_scaled": zone, "Q_step_swing": swing}  # fmt: skip

    rows = [
        row(None, 0.0275),
        row(12.0, 0.0275 * 3.0 * 1.05, zone=8.0),  # eq. 17: sqrt(9) = 3; 5% above it
        row(25.0, 0.0275 * 2.0, zone=8.0),  # a third below eq. 17
        row(4.0, 0.04, zone=1.2, outcome="oscillating", swing=0.2),
        # near G = -1 (the 190 um closed top): sqrt(1 + G) = 0.276 turns on
        # 1 + G = 0.076; the force balance stays judged on 1 + |G|
        row(0.0, 0.0275 * 0.218, zone=-0.924),  # rate -21%, force -1.5%
        row(1.0, 0.0275 * 0.9, zone=-0.924),  # force (0.81 - 0.076) / 1.924 = +38%
        row(2.0, 0.0275 * 0.1, zone=-1.05),  # no flow by sqrt(1 + G); force +2.9%
    ]
    data = {"rows": rows}
    derive_gas_lab(data)
    assert rows[1]["eq17_ratio"] == pytest.approx(3.0, rel=1e-12)
    assert rows[1]["eq17_rel_error"] == pytest.approx(0.05, rel=1e-9)
    assert rows[1]["eq17_force_error"] == pytest.approx((3.15**2 - 9) / 9, rel=1e-9)
    assert rows[1]["eq23_ratio"] > 1  # the Table I law, computed
    assert rows[3]["sim_ratio"] is None  # no Q/Q0 from an oscillating rate
    assert rows[4]["eq17_rel_error"] == pytest.approx(0.218 / 0.076**0.5 - 1, rel=1e-9)
    assert rows[4]["eq17_force_error"] == pytest.approx((0.218**2 - 0.076) / 1.924, rel=1e-9)
    assert rows[6]["eq17_ratio"] is None
    by_name = {c.name: c for c in checks({"gas-lab": data})}

    def eq17(label):
        return by_name[f"{label}: eq. 17's force balance, ((Q/Q0)^2 - 1 - G) / (1 + |G|)"]

    assert eq17("12.0").passed
    assert not eq17("25.0").passed  # a third below: (4 - 9) / 9
    assert not eq17("4.0").passed  # no steady rate, no figure
    assert eq17("0.0").passed
    assert not eq17("1.0").passed
    assert eq17("2.0").passed
    assert by_name["None: steady at its defaults"].passed
    assert not by_name["4.0: steady at its defaults"].passed


def test_one_preset_rerun_replaces_its_row_only(tmp_path, monkeypatch):
    import json

    from foamsilo.studies import suite

    def row(name, q):
        return {"label": name, "preset": name, "outcome": "steady", "Q": q, "Q_std": 0.0,
                "representation": "planar", "scheme": "lagged",
                "flow_rate_scale": "rho sqrt(g L^3)"}  # fmt: skip

    old = {"presets": {"rows": [row("zhou-planar", 1.0), row("venier-test1", 2.0)]},
           "wall_s": {"presets": 120.0}, "commits": {}, "jobs": "2 cases at a time",
           "machine": {"cpu": "Elsewhere CPU", "cores": 2}}  # fmt: skip
    (tmp_path / "suite.json").write_text(json.dumps(old))
    ran = []

    def fake(quick, work, jobs, limit, on_row=None, only=None):
        ran.append(only)
        return {"rows": [row(only, 3.0)]}

    monkeypatch.setattr(suite, "presets", fake)
    result = suite.run_suite(False, tmp_path, tmp_path / "work", only=["presets/zhou-planar"],
                             jobs=1)  # fmt: skip
    assert ran == ["zhou-planar"]
    q = {r["label"]: r["Q"] for r in result["presets"]["rows"]}
    assert q == {"venier-test1": 2.0, "zhou-planar": 3.0}
    report = (tmp_path / "suite.md").read_text()
    assert "| zhou-planar | planar | lagged |" in report
    # each entry says how its own cases ran, and where: the earlier one 2 at a
    # time on another machine, the rerun 1 here
    here = result["machine"]["cpu"]
    assert "presets 2.0 min (2 cases at a time, Elsewhere CPU)" in report
    assert f"presets/zhou-planar 0.0 min (1 cases at a time, {here})" in report
    assert "Elsewhere CPU" in report.splitlines()[2].split(";")[0]
    assert result["jobs_by_entry"] == {"presets": "2 cases at a time",
                                       "presets/zhou-planar": "1 cases at a time"}  # fmt: skip
    assert result["cpu_by_entry"] == {"presets": "Elsewhere CPU", "presets/zhou-planar": here}
    # the whole entry rerun: the part's rerun is in it, and its own timing,
    # commit, jobs and machine go
    monkeypatch.setitem(suite.ENTRIES, "presets", lambda quick, work, jobs, limit, on_row=None: {
        "rows": [row("zhou-planar", 4.0), row("venier-test1", 5.0)]})  # fmt: skip
    result = suite.run_suite(False, tmp_path, tmp_path / "work", only=["presets"], jobs=1)
    for book in ("wall_s", "commits", "jobs_by_entry", "cpu_by_entry"):
        assert list(result[book]) == ["presets"], (book, result[book])
    assert "presets/zhou-planar" not in (tmp_path / "suite.md").read_text()


def test_every_stiff_case_is_a_valid_scene():
    # the extremes are scenes the suite runs for minutes: a key a preset
    # does not take, or one it must drop (the thin silo's air flow, unset
    # with "" for its closed and open tops), fails here, not in the run
    from foamsilo.scene import load_preset
    from foamsilo.studies.cases import overrides, study_table

    table = study_table("suite")["extremes"]
    scenes = {e["label"]: load_preset(e["preset"], overrides(e.get("set"))) for e in table}
    labels = set(scenes)
    assert all(e["twin"] in labels for e in table if e.get("twin"))
    thin = {k: s for k, s in scenes.items() if k.startswith("thin rectangular silo")}
    assert {s.gas.mode for s in thin.values()} == {"closed-top", "open-top"}
    assert all(s.gas.q_air_lpm is None and s.silo.thickness == 0.0035 for s in thin.values())


def test_a_stiff_case_that_diverges_fails_its_check():
    # the quick suite's former divergences and the full suite's stiff cases
    # pass only when steady: a recovered-but-steady row passes, a row that
    # stopped diverged or never settled fails
    rows = [
        {"label": "wedge", "outcome": "steady", "Q": 0.0212, "recoveries": 1},
        {"label": "thin, closed top", "outcome": "diverged", "Q": None},
        {"label": "thin, open top", "outcome": "not steady", "Q": 5.5},
    ]
    by_name = {c.name: c for c in checks({"extremes": {"rows": rows}})}
    assert by_name["wedge: steady at its defaults"].passed
    assert not by_name["thin, closed top: steady at its defaults"].passed
    assert not by_name["thin, open top: steady at its defaults"].passed


def test_a_preset_s_own_wall_limit_extends_the_suite_s_and_is_checked():
    from foamsilo.errors import SceneError
    from foamsilo.scene import preset_names
    from foamsilo.studies.cases import StudyCase, study_table, wall_limits
    from foamsilo.studies.suite import longest_wall_limit

    own = wall_limits(study_table("suite")["presets"], "presets", preset_names())
    assert own, "suite.toml [presets] wall_limits is empty"
    name, seconds = next(iter(own.items()))
    # the larger of the two applies, and no limit stays no limit
    case = StudyCase(name, name, [], wall_limit=seconds)
    assert case.spec(Path("c"), 60.0).max_wall_seconds == seconds
    assert case.spec(Path("c"), 2 * seconds).max_wall_seconds == 2 * seconds
    assert case.spec(Path("c"), None).max_wall_seconds is None
    assert StudyCase("x", name, []).spec(Path("c"), 60.0).max_wall_seconds == 60.0
    # a batch job's --time covers the longest
    assert longest_wall_limit(60.0) == max(own.values())
    with pytest.raises(SceneError, match=r"presets\.wall_limits\.nope: unknown case; allowed"):
        wall_limits({"wall_limits": {"nope": 10}}, "presets", preset_names())
    with pytest.raises(SceneError, match=r"wall_limits\.zhou-planar: got -1; allowed: wall"):
        wall_limits({"wall_limits": {"zhou-planar": -1}}, "presets", preset_names())


def test_a_gas_lab_row_s_own_wall_limit_extends_the_suite_s_and_is_checked(monkeypatch):
    """suite.toml [gas-lab] wall_limits: by row label, checked against the full entry's labels."""
    from foamsilo.errors import SceneError
    from foamsilo.studies.cases import study_table, wall_limits
    from foamsilo.studies.suite import gas_lab_cases, gas_lab_wall_limits, longest_wall_limit

    own = gas_lab_wall_limits()
    assert own, "suite.toml [gas-lab] wall_limits is empty"
    cases = {c.label: c for c in gas_lab_cases(quick=False)[0]}
    for label, seconds in own.items():
        assert cases[label].spec(Path("c"), 900.0).max_wall_seconds == seconds
    # the other rows keep the suite's limit
    plain = [c for label, c in cases.items() if label not in own]
    assert plain and all(c.spec(Path("c"), 900.0).max_wall_seconds == 900.0 for c in plain)
    # a batch job's --time covers it, whatever the presets' limits
    monkeypatch.setattr("foamsilo.studies.suite.preset_wall_limits", dict)
    assert longest_wall_limit(60.0) == max(own.values())
    labels = list(cases)
    with pytest.raises(
        SceneError, match=r"gas-lab\.wall_limits\.d = 190 um: unknown case; allowed"
    ):
        wall_limits({"wall_limits": {"d = 190 um": 10}}, "gas-lab", labels)
    assert study_table("suite")["gas-lab"]["wall_limits"] == own


def test_3d_and_axisymmetric_are_compared_at_their_finest_common_steady_grid():
    def series(rows):
        return {"rows": [{"cells_across": n, "Q": q, "outcome": o} for n, q, o in rows]}

    result = {
        "work-precision": {
            "zhou-planar": series([]),
            "zhou-cyl-bottom": series([]),
            # 56 across is finest in 3D, but its axisymmetric twin is not steady
            "venier-test1-3d": series(
                [(28, 4.6, "steady"), (40, 4.8, "steady"), (56, 4.9, "steady")]
            ),
            "venier-test1-axi": series(
                [
                    (28, 4.5, "steady"),
                    (40, 4.9, "steady"),
                    (56, 4.9, "not steady"),
                    (80, 5.0, "steady"),
                ]
            ),
        }
    }
    (c,) = [c for c in checks(result) if "venier-test1-3d" in c.name]
    assert c.name.endswith(", 40 across") and c.value == pytest.approx(4.8 / 4.9 - 1)
    assert not c.passed  # -2%: outside the 1% a converged rate is asked for
    result["work-precision"]["venier-test1-3d"]["rows"][1]["Q"] = 4.88
    (c,) = [c for c in checks(result) if "venier-test1-3d" in c.name]
    assert c.passed


def test_a_row_counts_the_runner_s_recoveries_and_the_solver_s_retakes(tmp_path):
    # what run.json lists (pipeline._record): each kind counted, so a change to the
    # retakes shows which rows it touched; a case with no record gives nothing
    from foamsilo.case.lifecycle import RUN_RECORD
    from foamsilo.studies.cases import record_fields

    assert record_fields(tmp_path) == {}
    (tmp_path / RUN_RECORD).write_text(
        '{"status": "finished", "recoveries": [{"time": 0.1}],'
        ' "step_retakes": [{"time": 0.2}, {"time": 0.3}],'
        ' "share_retakes": [{"time": 0.2, "growth": 3.0}, {"time": 0.25, "growth": 2.5},'
        ' {"time": 0.4, "growth": 9.0}]}'
    )
    assert record_fields(tmp_path) == {"recoveries": 1, "step_retakes": 2, "share_retakes": 3}
    # and the processor its CPU time was measured on, where the record names it
    (tmp_path / RUN_RECORD).write_text('{"status": "finished", "cpu": "A CPU"}')
    assert record_fields(tmp_path)["cpu"] == "A CPU"


def test_a_3d_series_leaves_its_o_grid_floor_rows_out_of_the_convergence():
    from foamsilo.studies.suite import derive_work_precision

    def row(n):
        sets = ["mesh.representation='3d'", f"mesh.cells_across={n}"]
        return {"label": f"{n} across", "preset": "venier-test1", "sets": sets,
                "cells_across": n, "Q": 5.0 * (1 - 1.0 / n), "outcome": "steady"}  # fmt: skip

    rows = [row(n) for n in (40, 56, 80, 112, 160)]
    data = {"rows": rows, "Q_law": None}
    derive_work_precision(data)
    # 12 cells on a quarter circle up to 56 across (the floor), not after
    assert [r["o_grid_floored"] for r in rows] == [True, True, False, False, False]
    conv = data["convergence"]
    assert conv["cells"] == [80, 112, 160]
    assert conv["order"] == pytest.approx(1.0, rel=1e-9)
    assert conv["extrapolated"] == pytest.approx(5.0, rel=1e-9)
    assert rows[0]["err_vs_extrapolated"] is None
    # two family rows only: no estimate, said so
    data = {"rows": [row(n) for n in (40, 56, 80, 112)], "Q_law": None}
    derive_work_precision(data)
    assert data["convergence"] is None


def test_a_partial_run_into_a_fresh_report_directory_writes_its_report(tmp_path):
    """`--only` one series with `-o` a new directory: the report holds what ran, no crash.

    The checks of series that did not run are left out, not read from a
    result that lacks them (a KeyError there once lost a finished run's rows).
    """
    from foamsilo.studies.cases import machine_info
    from foamsilo.studies.suite import derive_work_precision, write_report

    def row(n, q):
        return {"label": f"{n} across", "preset": "zhou-cyl-lateral-rect",
                "sets": [f"mesh.cells_across={n}"], "cells_across": n, "Q": q,
                "outcome": "steady", "wall_s": 5.0 * n, "cpu_s": 10.0 * n,
                "simulated_time_s": 0.6, "cells": 1000 * n}  # fmt: skip

    key = "work-precision/zhou-cyl-lateral-rect"
    series = {"law": None, "Q_law": None,
              "rows": [row(30, 0.0422), row(40, 0.0457), row(48, 0.0470)]}  # fmt: skip
    derive_work_precision(series)
    result = {"quick": False, "machine": machine_info(), "jobs": "1 case at a time",
              "work-precision": {"zhou-cyl-lateral-rect": series},
              "commits": {key: "abc"}, "commit": "abc", "wall_s": {key: 10.0}}  # fmt: skip
    res = write_report(result, tmp_path, "suite")
    assert res["checks"] == []  # no check reads this series
    assert json.loads((tmp_path / "suite.json").read_text())["work-precision"].keys() == {
        "zhou-cyl-lateral-rect"
    }
    assert "**zhou-cyl-lateral-rect**" in (tmp_path / "suite.md").read_text()


def test_a_table_whose_rows_ran_on_several_processors_names_each_row_s():
    # a CPU time is its machine's: where a table's rows name two processors
    # each CPU cell says which; where they name one, none does
    from foamsilo.studies.suite import short_cpu, suite_markdown

    assert short_cpu("Intel(R) Xeon(R) Processor") == "Intel Xeon"
    assert short_cpu("Intel(R) Core(TM) i7-8700 CPU @ 3.20GHz") == "Intel Core i7-8700"
    assert short_cpu("AMD EPYC") == "AMD EPYC"
    rows = [_series_row(n, q) for n, q in ((36, 0.0259), (48, 0.0280), (72, 0.0300))]
    for r, cpu in zip(rows, ("Intel(R) Xeon(R) Processor", "AMD EPYC", "AMD EPYC"), strict=True):
        r["cpu"] = cpu
    series = {"law": None, "Q_law": None, "rows": rows}
    derive_work_precision(series)
    result = {"quick": False, "machine": {"cpu": "AMD EPYC", "cores": 2},
              "jobs": "1 case at a time", "work-precision": {"zhou-cyl-bottom": series},
              "commit": "abc", "wall_s": {}, "checks": []}  # fmt: skip
    text = suite_markdown(result, "suite")
    assert "| 72 | 72 (Intel Xeon) | - |" in text and "| 96 | 96 (AMD EPYC) | - |" in text
    # the time-step table alike
    steps = [{"courant": c, "outcome": "steady", "Q": 0.03, "cpu_s": 10.0 / c, "cpu": cpu}
             for c, cpu in ((0.5, "AMD EPYC"), (0.25, "Intel(R) Xeon(R) Processor"))]  # fmt: skip
    result["time-step"] = {"scenes": [{"label": "a scene", "rows": steps}]}
    text = suite_markdown(result, "suite")
    assert "| 20 (AMD EPYC) |" in text and "| 40 (Intel Xeon) |" in text
    for r in [*rows, *steps]:
        r["cpu"] = "AMD EPYC"
    text = suite_markdown(result, "suite")
    assert "| 144 | 144 | - |" in text and "| 40 |" in text and "(AMD EPYC) |" not in text


def _series_row(n, q, sets=()):
    return {"label": f"{n} across", "preset": "zhou-cyl-bottom", "case_dir": f"/nowhere/{n}",
            "sets": [f"mesh.cells_across={n}", *sets], "cells_across": n, "Q": q,
            "outcome": "steady", "wall_s": 2.0 * n, "cpu_s": 2.0 * n,
            "simulated_time_s": 0.6, "cells": 100 * n}  # fmt: skip


def test_some_rows_of_a_series_rerun_into_the_report_and_the_others_kept(tmp_path, monkeypatch):
    """`--only work-precision/NAME --values ...`: those rows run, the others stay.

    The new rows take their places in the series' order and in the work
    directory (an earlier case at another place is not overwritten), a row at
    a resolution the series no longer lists goes, the grid convergence is
    taken again over the whole series, and the series' commit, time and
    machine keep the earlier run's beside the new one's.
    """
    from foamsilo.studies import suite
    from foamsilo.studies.cases import study_table

    name, key = "zhou-cyl-bottom-graded", "work-precision/zhou-cyl-bottom-graded"
    entry = next(e for e in study_table("suite")["work-precision"] if e.get("name") == name)
    cells = entry["values"]
    assert {36, 48, 72, 96, 144, 192} <= set(cells) and 100 not in cells
    q = {36: 0.0259, 48: 0.0280, 72: 0.0300, 96: 0.0309, 100: 0.5, 144: 0.0320}
    old = {"work-precision": {name: {"law": None, "Q_law": None,
                                     "rows": [_series_row(n, v) for n, v in q.items()]}},
           "wall_s": {key: 100.0}, "commits": {key: "abc1234"}, "jobs": "2 cases at a time",
           "jobs_by_entry": {key: "2 cases at a time"}, "cpu_by_entry": {key: "Elsewhere CPU"},
           "machine": {"cpu": "Elsewhere CPU", "cores": 2}}  # fmt: skip
    (tmp_path / "suite.json").write_text(json.dumps(old))
    ran = []

    def fake_rows(cases, work, jobs, limit, on_row=None, dirs=None):
        ran.append(([c.label for c in cases], dirs, Path(work).name))
        new_q = {96: 0.0310, 192: 0.03245}
        return [_series_row(n, new_q[n]) for n in (int(c.label.split()[0]) for c in cases)]

    monkeypatch.setattr(suite, "run_rows", fake_rows)
    monkeypatch.setattr(suite, "git_commit", lambda: "def5678")
    result = suite.run_suite(False, tmp_path, tmp_path / "work",
                             only=[key], jobs=1, values=[192, 96])  # fmt: skip
    places = [f"{cells.index(n):02d}" for n in (96, 192)]
    assert ran == [(["96 across", "192 across"], places, name)]
    series = result["work-precision"][name]
    assert [r["cells_across"] for r in series["rows"]] == [36, 48, 72, 96, 144, 192]
    assert [r["Q"] for r in series["rows"]] == [0.0259, 0.0280, 0.0300, 0.0310, 0.0320, 0.03245]
    # the grid convergence taken again, on the new rows: the finest three
    conv = series["convergence"]
    assert conv["values"][-3:] == [0.0310, 0.0320, 0.03245]
    assert conv["kind"] == "monotone" and conv["extrapolated"] > 0.03245
    assert result["commits"][key] == "abc1234, def5678"
    assert result["commit"] == "abc1234, def5678"
    assert result["cpu_by_entry"][key] == f"Elsewhere CPU, {result['machine']['cpu']}"
    assert result["wall_s"][key] >= 100.0
    saved = json.loads((tmp_path / "suite.json").read_text())
    assert [r["cells_across"] for r in saved["work-precision"][name]["rows"]][-1] == 192


def test_a_rerun_records_the_commit_its_cases_ran_at(tmp_path, monkeypatch):
    """A commit made while the cases run is not theirs: the one before is recorded."""
    from foamsilo.studies import suite

    commits = iter(["abc1234", "fed4321"])
    monkeypatch.setattr(suite, "git_commit", lambda: next(commits))

    def fake(quick, work, jobs, limit, on_row=None, only=None):
        suite.git_commit()  # a commit made while the case runs (read here)
        return {"rows": [{"label": only, "preset": only, "outcome": "steady", "Q": 1.0,
                          "Q_std": 0.0, "representation": "planar", "scheme": "lagged",
                          "flow_rate_scale": "rho sqrt(g L^3)"}]}  # fmt: skip

    monkeypatch.setattr(suite, "presets", fake)
    result = suite.run_suite(False, tmp_path, tmp_path / "work", only=["presets/zhou-planar"],
                             jobs=1)  # fmt: skip
    assert result["commits"]["presets/zhou-planar"] == "abc1234"


def test_one_time_step_scene_reruns_into_the_report_and_the_others_kept(tmp_path, monkeypatch):
    """`--only "time-step/LABEL"`: that scene's cases run, in their places.

    Its cases keep the directories they have in the whole entry (a rerun
    overwrites no other scene's case), its rows replace the scene's earlier
    ones, the other scenes stay in suite.toml's order, and the change of Q
    against the default step is taken again on the new rows.
    """
    from foamsilo.studies import suite
    from foamsilo.studies.cases import study_table

    table = study_table("suite")["time-step"]
    labels = suite.time_step_scenes()
    first, label = labels[0], "planar silo (the preset), 104 across"
    courants = next(e.get("courants", table["courants"]) for e in table["cases"]
                    if e["label"] == label)  # fmt: skip
    # its cases' places in the whole entry: after every case of the scenes before it
    before = sum(len(e.get("courants", table["courants"]))
                 for e in table["cases"][: labels.index(label)])  # fmt: skip

    def scene(name, qs):
        rows = [{"label": f"{name}, Courant {c:g}", "outcome": "steady", "Q": q, "Q_std": 0.0,
                 "courant": c} for c, q in zip([0.5, 0.25], qs, strict=True)]  # fmt: skip
        return {"label": name, "rows": rows}

    old = {"time-step": {"scenes": [scene(label, [1.0, 1.0]), scene(first, [2.0, 1.0])]},
           "wall_s": {"time-step": 60.0}, "commits": {"time-step": "abc1234"},
           "jobs": "2 cases at a time", "machine": {"cpu": "Elsewhere CPU", "cores": 2}}  # fmt: skip
    (tmp_path / "suite.json").write_text(json.dumps(old))
    ran = []

    limits = []  # each case's run settings, as its scene loads them

    def fake_rows(cases, work, jobs, limit, on_row=None, dirs=None):
        ran.append(([c.label for c in cases], dirs, Path(work).name))
        limits.extend(load_preset(c.preset, c.sets).run for c in cases)
        return [{"label": c.label, "outcome": "steady", "Q": 40.0 - i, "Q_std": 0.0}
                for i, c in enumerate(cases)]  # fmt: skip

    monkeypatch.setattr(suite, "run_rows", fake_rows)
    result = suite.run_suite(False, tmp_path, tmp_path / "work",
                             only=[f"time-step/{label}"], jobs=1)  # fmt: skip
    assert ran == [([f"{label}, Courant {c:g}" for c in courants],
                    [f"{before + i:02d}" for i in range(len(courants))], "time-step")]  # fmt: skip
    scenes = result["time-step"]["scenes"]
    assert [s["label"] for s in scenes] == [first, label]  # suite.toml's order
    assert [r["Q"] for r in scenes[0]["rows"]] == [2.0, 1.0]  # the other scene kept
    mine = scenes[1]["rows"]
    assert [r["courant"] for r in mine] == courants
    # the preset as it runs: 0.75 over all cells, 0.5 at the free surface, both halved
    assert [(r.max_courant, r.max_interface_courant) for r in limits] == [
        (0.75, 0.5), (0.375, 0.25), (0.1875, 0.125)]  # fmt: skip
    assert [r["interface_courant"] for r in mine] == [0.5, 0.25, 0.125]
    assert (load_preset("zhou-planar").run.max_courant,
            load_preset("zhou-planar").run.max_interface_courant) == (0.75, 0.5)  # fmt: skip
    assert mine[1]["vs_default_step"] == pytest.approx(39.0 / 40.0 - 1)
    assert result["commits"]["time-step"] == "abc1234"
    assert f"time-step/{label}" in result["wall_s"]
    # a scene suite.toml does not list is refused, with the ones it does
    with pytest.raises(FoamsiloError, match=r"'time-step/nope'.*'time-step/planar silo, 64 acr"):
        suite.run_suite(False, tmp_path, tmp_path / "work", only=["time-step/nope"])


@pytest.mark.parametrize(
    ("only", "values", "match"),
    [
        (None, [96], r"--values: needs one series"),
        (["work-precision/zhou-cyl-bottom-graded", "presets"], [96], r"needs one series"),
        (["presets/zhou-planar"], [96], r"needs one series"),
        (["work-precision"], [96], r"needs one series"),
        (["work-precision/zhou-cyl-bottom-graded"], [100],
         r"has no resolution 100; its resolutions: 36, 48, 72, 96, 144"),
    ],
)  # fmt: skip
def test_rows_of_a_series_are_refused_unless_the_series_lists_them(tmp_path, only, values, match):
    from foamsilo.studies.suite import run_suite

    with pytest.raises(FoamsiloError, match=match):
        run_suite(False, tmp_path, tmp_path / "work", only=only, values=values)
    assert not any(tmp_path.iterdir())  # refused before anything ran or was written


def test_a_series_refined_as_a_whole_scales_its_grading_with_the_cells():
    from foamsilo.studies.suite import _series

    entry = {"name": "s", "preset": "zhou-cyl-bottom", "key": "mesh.cells_across",
             "values": [72, 144], "similar_to": 72,
             "set": {"mesh.growth_rate": 1.1, "mesh.coarse_cells_across": 16}}  # fmt: skip
    _, cases = _series(entry, False)
    assert cases[0].sets == ["mesh.cells_across=72", "mesh.growth_rate=1.1",
                             "mesh.coarse_cells_across=16"]  # fmt: skip
    growth = float(cases[1].sets[1].split("=")[1])
    assert growth == pytest.approx(1.1**0.5, rel=1e-12)  # two cells where there was one
    assert cases[1].sets[2] == "mesh.coarse_cells_across=32"
    del entry["set"]["mesh.coarse_cells_across"]
    with pytest.raises(FoamsiloError, match="similar_to needs .*mesh.coarse_cells_across"):
        _series(entry, False)


@pytest.mark.openfoam
def test_one_row_of_a_series_runs_for_real_and_joins_the_others(tmp_path, openfoam, solver):
    """`--values 36` on Venier Test 2's series: that row runs, at its feeder's rate; the rest stay.

    The cheapest series of the suite (3D, a few seconds a row), its rows as
    the suite's report holds them. Tolerance: the feeder's rate to 0.1%, as
    tests/test_feeder.py asks of the preset.
    """
    from foamsilo.scene import load_preset
    from foamsilo.studies.suite import run_suite

    report = json.loads((Path(__file__).parents[1] / "docs/validation/suite.json").read_text())
    old = {k: report[k] for k in ("machine", "jobs", "commits", "wall_s") if k in report}
    old["work-precision"] = {"venier-test2": report["work-precision"]["venier-test2"]}
    before = old["work-precision"]["venier-test2"]["rows"]
    assert [r["cells_across"] for r in before] == [24, 36, 48, 72]
    (tmp_path / "suite.json").write_text(json.dumps(old))
    res = run_suite(False, tmp_path, tmp_path / "work", only=["work-precision/venier-test2"],
                    jobs=1, values=[36])  # fmt: skip
    rows = res["work-precision"]["venier-test2"]["rows"]
    assert [r["cells_across"] for r in rows] == [24, 36, 48, 72]
    # the row in its place in the series' work directory, the others as they were
    assert rows[1]["case_dir"] == str(tmp_path / "work/work-precision/venier-test2/01")
    assert [(r["Q"], r["case_dir"]) for r in rows if r["cells_across"] != 36] == [
        (r["Q"], r["case_dir"]) for r in before if r["cells_across"] != 36
    ]
    scene = load_preset("venier-test2")
    assert scene.silo.feeder_flow_rate is not None
    rate = scene.material.density * scene.silo.feeder_flow_rate
    assert rows[1]["outcome"] == "steady"
    assert rows[1]["Q"] == pytest.approx(rate, rel=1e-3)


def _preset_tables(node, preset):
    """Every table of a study that runs ``preset`` (its sets)."""
    if isinstance(node, dict):
        if node.get("preset") == preset:
            yield node
        for v in node.values():
            yield from _preset_tables(v, preset)
    elif isinstance(node, list):
        for v in node:
            yield from _preset_tables(v, preset)


#: The mesh keys every study table on a graded preset names
MESH_KEYS = {"mesh.growth_rate", "mesh.orifice_edge_refinement", "mesh.orifice_region",
             "mesh.coarse_cells_across"}  # fmt: skip
#: And the stress coupling's keys the lab silo's preset sets since 2026-12-07
SHARE_KEYS = {"numerics.stress_pressure_divergence", "numerics.outer_growth_limit",
              "numerics.outer_change_limit"}  # fmt: skip
#: And the exit's rows, which the lab silo's preset refines since 2026-12-07
EXIT_KEYS = {"mesh.orifice_exit_refinement"}


@pytest.mark.parametrize(
    ("preset", "keys", "least"),
    [("zhou-planar", MESH_KEYS, 15), ("zhou-cyl-bottom", MESH_KEYS | SHARE_KEYS | EXIT_KEYS, 25)],
)
def test_every_suite_case_on_a_graded_preset_names_its_grading(preset, keys, least):
    # the planar and lab silo presets are graded since issue 18 (the lab
    # silo's with half the stress's divergence share): an entry that does not
    # name its grading (and share) would run the preset's grid, not the one
    # its rows were measured on (the quick sets replace the full ones: both
    # count; the main job's target names no set: it judges the preset)
    from foamsilo.scene import load_preset
    from foamsilo.studies.cases import overrides, study_table

    tables = [t for t in _preset_tables(study_table("suite"), preset) if "kind" not in t]
    assert all("set" in t for t in tables), [t for t in tables if "set" not in t]
    sets = [t[k] for t in tables for k in ("set", "quick_set") if k in t]
    assert len(sets) > least
    for table in sets:
        assert keys <= set(table), table
        scene = load_preset(preset, overrides(table))
        assert scene.mesh.graded == (table["mesh.growth_rate"] > 1), table


def test_the_lab_silo_s_bench_and_verification_cases_name_its_former_defaults():
    # the MPI and post benchmarks and the pipe flow were measured on the lab
    # silo's preset before it was graded with half the share
    from foamsilo.studies.cases import study_table

    for study, least in (("bench", 2), ("verification", 1)):
        tables = list(_preset_tables(study_table(study), "zhou-cyl-bottom"))
        assert len(tables) >= least, study
        for t in tables:
            named = set(t.get("set", {}))
            if t.get("law") != "pipe":  # the channel builds its own mesh
                assert MESH_KEYS | EXIT_KEYS <= named, (study, t)
            assert SHARE_KEYS <= named, (study, t)


def test_a_worker_s_wall_time_leaves_out_a_first_build_of_the_solver(monkeypatch, tmp_path):
    # the suite's rows take a case's wall time from its worker: a build of the
    # solver (about a minute, once per source change) is no part of it (it once
    # put 133 s for a 43 CPU-s row); the build and the case stand in here
    import io
    import sys
    import time
    from types import SimpleNamespace

    import foamsilo.pipeline as pipeline

    built: list[bool] = []

    def ensure_solver(*args, **kwargs):  # a build the first time, found after
        if not built:
            time.sleep(1.0)
            built.append(True)

    def run_case(spec):  # as the pipeline's: the solver first, then the case
        pipeline.ensure_solver()
        return SimpleNamespace(as_json=lambda: {"Q": 1.0})

    monkeypatch.setattr(pipeline, "ensure_solver", ensure_solver)
    monkeypatch.setattr(pipeline, "run_case", run_case)
    spec = pipeline.CaseSpec(tmp_path / "c", "zhou-planar")
    monkeypatch.setattr(sys, "stdin", io.StringIO(json.dumps(spec.as_dict())))
    out = io.StringIO()
    monkeypatch.setattr(sys, "stdout", out)
    assert pipeline._worker_main() == 0
    outcome = json.loads(out.getvalue())
    assert outcome["status"] == "ok" and outcome["wall_s"] < 0.5


def test_a_series_grid_is_within_a_level_only_with_its_time_band_inside():
    # first order to 2.0, c = 0.5: 64 across is 0.78% low. With a standard
    # error of 0.15% of Q its 95% band (0.3%) takes it past 1%: the series'
    # 1% grid is then 128 across (0.39% low), as in the targets
    for se, grid in ((0.0, 64), (0.0015, 128)):
        rows = [{"cells_across": n, "Q": 2.0 * (1 - 0.5 / n), "outcome": "steady",
                 "Q_time_error": se * 2.0} for n in (8, 16, 32, 64, 128)]  # fmt: skip
        data = {"rows": rows, "Q_law": None}
        derive_work_precision(data)
        assert data["convergence"]["extrapolated"] == pytest.approx(2.0, rel=1e-9)
        assert data["convergence"]["coarsest_within_1pct"] == grid, se


def test_every_planar_study_case_names_the_courant_limit_it_was_measured_at():
    # the planar preset steps at Courant 0.75 over all cells since the evening
    # of 2026-12-07; every study case measured before names the 0.5 it ran at
    # (the time-step scenes set both limits per value; a target names no set)
    from foamsilo.studies.cases import study_table

    suite = study_table("suite")
    stepped = [id(t) for t in suite["time-step"]["cases"]]
    for study in ("suite", "bench", "verification"):
        data = suite if study == "suite" else study_table(study)
        tables = [t for t in _preset_tables(data, "zhou-planar")
                  if "kind" not in t and id(t) not in stepped]  # fmt: skip
        assert tables, study
        for t in tables:
            for key in ("set", "quick_set"):
                if key in t:
                    assert "run.max_courant" in t[key], (study, t.get("label", t.get("name")))
