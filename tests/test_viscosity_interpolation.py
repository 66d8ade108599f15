"""The viscosity on a face of the stress: linear or harmonic mean (real siloFoam runs).

`numerics.viscosity_interpolation = "harmonic"` puts the harmonic mean of a
face's two cell viscosities into both parts of the granular stress (the
implicit div(mu grad U) and the explicit transpose; siloFoam's PIMPLE
switch viscosityInterpolation) instead of the linear mean that OpenFOAM's
stress terms take; a diagnostic (docs/solver.md, "The viscosity on a
face": it fails the code verification at a free surface).

The check: both means are consistent discretisations of one continuum, so
the two rates must approach each other as the cells shrink, at least at
first order (halved cells at least halve their gap; asserted below 0.6 of
it, leaving room for grids not yet in the asymptotic range); and the
harmonic mean never exceeds the linear one, so every face carries at most
the linear mean's stress and the rate is the higher one.
With the switch not reaching
the solver the two runs give the same rate and both assertions fail.
The lab silo, graded, 36 and 72 cells across L (6 and 12 across the
orifice), 0.3 s.
"""

from __future__ import annotations

import pytest

from foamsilo.pipeline import Budget, CaseSpec, run_many

from .conftest import LAB_FORMER

pytestmark = pytest.mark.openfoam

SETS = (*LAB_FORMER, "mesh.growth_rate=1.1", "run.end_time=0.3", "run.write_interval=0.15")
HARMONIC = ("numerics.viscosity_interpolation='harmonic'",)


def test_the_two_means_converge_to_one_rate(tmp_path, solver):
    specs = [
        CaseSpec(tmp_path / f"{mean}-{n}", "zhou-cyl-bottom",
                 (f"mesh.cells_across={n}", *SETS, *(HARMONIC if mean == "harmonic" else ())))
        for n in (36, 72)
        for mean in ("linear", "harmonic")
    ]  # fmt: skip
    outcomes = run_many(specs, Budget(cores=2))
    q = {}
    for spec, o in zip(specs, outcomes, strict=True):
        assert o.status == "ok" and o.summary is not None, o.error
        assert o.summary["steady"], o.summary["steady_reason"]
        assert o.summary["run"]["recoveries"] == []
        q[spec.case_dir.name] = o.summary["Q"]
    gap36 = q["harmonic-36"] / q["linear-36"] - 1
    gap72 = q["harmonic-72"] / q["linear-72"] - 1
    assert gap36 > 0 and gap72 > 0
    assert gap72 < 0.6 * gap36


def _steps(case) -> list[dict[str, str]]:
    import csv

    with open(case / "steps.csv") as f:
        return list(csv.DictReader(f))


def test_the_start_ups_face_mean_ends_with_the_start_up(tmp_path, solver):
    """`numerics.start_up_viscosity_interpolation` acts on the start-up's steps only.

    Three runs of the lab wedge to twice its start-up (sqrt(D/g), D = 10 mm):
    the harmonic mean in the start-up only (the default), everywhere, and
    nowhere. The first two take the same steps to the last digit until the
    start-up ends and part in the first step after it; the first and the
    third part from the first step. A switch that did not reach the solver,
    or one that did not end, fails one of the two.
    """
    start_up = (0.01 / 9.81) ** 0.5
    sets = (*LAB_FORMER, "mesh.cells_across=36", f"run.end_time={2 * start_up:.6g}",
            f"run.write_interval={2 * start_up:.6g}", "run.max_recoveries=0")  # fmt: skip
    means = {
        "start-up": (),
        "everywhere": HARMONIC,
        "nowhere": ("numerics.start_up_viscosity_interpolation='linear'",),
    }
    specs = [CaseSpec(tmp_path / k, "zhou-cyl-bottom", (*sets, *v)) for k, v in means.items()]
    for o in run_many(specs, Budget(cores=2)):
        assert o.status == "ok", o.error
    steps = {k: _steps(tmp_path / k) for k in means}
    # a step's start: the previous row's time
    first_after = next(
        i for i, r in enumerate(steps["start-up"])
        if float(r["time"]) - float(r["delta_t"]) >= start_up * (1 + 1e-9)
    )  # fmt: skip
    assert first_after > 20
    compared = ("time", "delta_t", "res_Ux", "res_Uy", "res_p_rgh")
    for a, b in zip(steps["start-up"][:first_after], steps["everywhere"], strict=False):
        assert [a[c] for c in compared] == [b[c] for c in compared]
    after = (steps["start-up"][first_after], steps["everywhere"][first_after])
    assert after[0]["res_Ux"] != after[1]["res_Ux"]
    assert steps["start-up"][1]["res_Ux"] != steps["nowhere"][1]["res_Ux"]


@pytest.mark.parametrize("preset", ["hopper-conical", "hopper-two-angle"])
def test_the_hoppers_start_up_at_their_presets_grid_without_a_recovery(tmp_path, solver, preset):
    """The hoppers' start-up (80 cells across, six across the outlet's radius), 0.1 s.

    With the linear mean in the start-up too, both blew up in it (the volume
    fraction out of bounds within a step's outer iterations, t = 3-16 ms) and
    needed two of the runner's recoveries; with the default harmonic start-up
    they run through with neither a step retake nor a recovery allowed
    (docs/solver.md, "The start-up's face mean").
    """
    sets = ("run.end_time=0.1", "run.write_interval=0.1", "run.max_step_retakes=0",
            "run.max_recoveries=0")  # fmt: skip
    (out,) = run_many([CaseSpec(tmp_path / preset, preset, sets)], Budget(cores=1))
    assert out.status == "ok", out.error
    assert out.summary is not None and out.summary["cells_across"] == 80
    assert out.summary["run"]["recoveries"] == [] and out.summary["run"]["step_retakes"] == []


def test_the_lab_silo_starts_up_at_its_presets_grid_without_a_recovery(tmp_path, solver):
    """The main job's silo at its default grid (84 across, edges 3x, exit rows 4x), 0.1 s.

    Its former grid (96 across) with its edges refined 4x instead of 3x
    crashed in the start-up now and then (a floating-point trap, by the
    written times alone: docs/solver.md, "The lab silo's default grid"),
    which the runner recovers from t = 0; the preset's grid starts with
    neither a step retake nor a recovery allowed.
    """
    # its first written time, as the preset writes it (the written times set
    # the steps that reach them)
    sets = ("run.end_time=0.1", "run.max_step_retakes=0", "run.max_recoveries=0")
    spec = CaseSpec(tmp_path / "lab", "zhou-cyl-bottom", sets)
    (out,) = run_many([spec], Budget(cores=1))
    assert out.status == "ok", out.error
    assert out.summary is not None and out.summary["cells_across"] == 84
    assert out.summary["run"]["recoveries"] == [] and out.summary["run"]["step_retakes"] == []
