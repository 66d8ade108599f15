"""The small-step branch of the lab silo, and the implicit stress-pressure coupling (real runs).

With the granular stress lagged to the next outer iteration, the wall stress
of a tall column carries the last iterate's pressure down the column
(Janssen's feedback): below a step that grows with resolution the column's
pressure swings with a period of four steps and the rate falls onto a
second branch (lab silo, graded, 48 across, face acceleration, Courant
0.125: 8% low, swinging 3.6% from step to step; with a 0.15 m fill instead
of 0.5 m the same step runs steady). `numerics.stress_pressure_coupling =
"implicit"` puts d tau/d p into the projection (siloFoam pEqn.H).

The check: the same scene at Courant 0.25 and 0.125, 0.3 s each (the
branch sets in within the first 0.05 s). Tolerances: Q within 1%, the
accuracy a converged rate is asked to have (issue 18); the smaller step's
step-to-step swing under 1%, the level above which the report warns of a
numerical oscillation (docs/post.md). Measured with the implicit coupling
over 0.6 s: 0.027213 and 0.027251 kg/s, swing 0.02% and 0.00%; the lagged
coupling fails both (docs/solver.md).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from foamsilo.pipeline import Budget, CaseSpec, run_many

from .conftest import LAB_FORMER

pytestmark = pytest.mark.openfoam

SETS = (*LAB_FORMER, "mesh.cells_across=48", "mesh.growth_rate=1.1", "run.end_time=0.3",
        "run.write_interval=0.15", "numerics.open_boundary_acceleration='face'",
        "numerics.stress_pressure_coupling='implicit'")  # fmt: skip


def courant(c: float) -> tuple[str, str]:
    return (f"run.max_courant={c}", f"run.max_interface_courant={c}")


def test_the_small_step_keeps_the_rate_with_the_implicit_coupling(tmp_path, solver):
    specs = [
        CaseSpec(tmp_path / "courant-0.25", "zhou-cyl-bottom", SETS + courant(0.25)),
        CaseSpec(tmp_path / "courant-0.125", "zhou-cyl-bottom", SETS + courant(0.125)),
    ]
    larger, smaller = run_many(specs, Budget(cores=2))
    for o in (larger, smaller):
        assert o.status == "ok" and o.summary is not None, o.error
        assert o.summary["steady"], o.summary["steady_reason"]
        assert not o.summary["run"].get("recoveries"), o.summary["run"]["recoveries"]
    assert smaller.summary["Q_step_swing"] < 0.01
    assert smaller.summary["Q"] == pytest.approx(larger.summary["Q"], rel=0.01)
    assert smaller.summary["run"]["steps"] > 1.6 * larger.summary["run"]["steps"]


def test_the_thin_silo_s_wall_drag_does_not_saw_tooth(tmp_path, solver):
    """The thin lab silo's saw-tooth was the lagged stress, not the wall drag.

    The dry thin lab silo (zhou-rect-bottom without its air, W = 3.5 mm,
    32 across, 0.5 s). With the stress lagged its rate swings by 13% from one
    step to the next (spread 31%); with the implicit coupling (the default
    in a dry silo with wall friction) 0.13% (spread 0.4%); adding the wall drag's own
    pressure derivative changes neither (docs/solver.md). Tolerance: the 1%
    above which the report warns of a numerical oscillation (docs/post.md).
    """
    from foamsilo.scene import load_preset, load_scene_file

    assert load_preset("zhou-rect-bottom").stress_pressure_coupling == "implicit"
    text = (
        Path(__file__).parents[1] / "foamsilo" / "presets" / "zhou-rect-bottom.toml"
    ).read_text()
    start, end = text.index("[gas]"), text.index("[mesh]")
    scene = tmp_path / "rect-dry.toml"
    scene.write_text(text[:start] + text[end:])
    assert load_scene_file(scene).stress_pressure_coupling == "implicit"  # dry, wall friction
    sets = ("run.end_time=0.5", "run.write_interval=0.25")
    (out,) = run_many([CaseSpec(tmp_path / "dry", str(scene), sets)], Budget(cores=1))
    assert out.status == "ok" and out.summary is not None, out.error
    s = out.summary
    assert s["steady"], s["steady_reason"]
    assert s["Q_step_swing"] < 0.01
    assert s["Q_std"] < 0.02 * s["Q"]


def test_a_tall_planar_column_is_steady_at_its_defaults(tmp_path, solver):
    """The planar silo filled 19.5 widths high (the suite's tall silo, 16 across, 0.5 s).

    Lagged, its rate swings by 13% from one step to the next (7% at 32 across;
    up to 8 widths high the swing stays under 0.3%), so a planar column filled
    higher than 10 widths gets the implicit coupling by default (docs/solver.md,
    "Tall columns"). Tolerances: the swing under the 1% above which
    the report warns of a numerical oscillation; Q within 2% of the preset's
    column (3.9 widths) on the same scheme and grid, since a silo's rate does
    not depend on its fill once the column is a few widths high (Janssen's
    screening; Beverloo) (measured +1.0%).
    """
    from foamsilo.scene import load_preset

    grid = ("mesh.cells_across=16", "run.end_time=0.5", "run.write_interval=0.25")
    tall = (*grid, "silo.height=2.0", "silo.fill_height=1.95")
    assert load_preset("zhou-planar", tall).stress_pressure_coupling == "implicit"
    assert load_preset("zhou-planar", grid).stress_pressure_coupling == "lagged"
    specs = [
        CaseSpec(tmp_path / "tall", "zhou-planar", tall),
        CaseSpec(tmp_path / "preset", "zhou-planar",
                 (*grid, "numerics.stress_pressure_coupling='implicit'")),
    ]  # fmt: skip
    high, low = run_many(specs, Budget(cores=2))
    for o in (high, low):
        assert o.status == "ok" and o.summary is not None, o.error
        assert o.summary["steady"], o.summary["steady_reason"]
        assert o.summary["Q_step_swing"] < 0.01
    assert high.summary["Q"] == pytest.approx(low.summary["Q"], rel=0.02)
