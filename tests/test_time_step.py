"""A steady outflow that does not depend on the time step (real siloFoam runs).

Two step errors were found in the lab silo's rate (docs/solver.md). The
projection leaves on the orifice a flux dt (a_f - a_P.n)|S| that does not
vanish at a steady state (`numerics.open_boundary_acceleration = "face"`
removes it); and with the granular stress lagged, the column's pressure
lags the stress it carries (`numerics.stress_pressure_coupling =
"implicit"`, the axisymmetric default, takes it into the projection).

The scene: the lab silo (axisymmetric, graded, 96 cells across L, 16 across
the orifice), 0.3 s, at the default Courant limits (0.5) and at half of
them, with the default scheme (cell acceleration, implicit coupling).
Tolerance 1%, the accuracy a converged rate is asked to have (issue 18):
halving the step must not move Q by more. Measured (2026-12-04): -0.37%.
At 48 across it is -1.2%, which this check refuses: it ran there, at
-0.22%, until the light phase's density (docs/solver.md, "The light
phase's density") took out a pressure-tolerance error of the default step
that had hidden most of it (the half-step run is the same either way,
0.027674 kg/s). The same pair with the stress lagged was -1.2% at 48 across
with air's density; with face acceleration and the implicit coupling +1.7%.
"""

from __future__ import annotations

import pytest

from foamsilo.pipeline import Budget, CaseSpec, run_many

from .conftest import LAB_FORMER

pytestmark = pytest.mark.openfoam

SETS = (*LAB_FORMER, "mesh.cells_across=96", "mesh.growth_rate=1.1", "run.end_time=0.3",
        "run.write_interval=0.15")  # fmt: skip
HALF_STEP = ("run.max_courant=0.25", "run.max_interface_courant=0.25")


def test_halving_the_step_leaves_the_steady_rate(tmp_path, solver):
    specs = [
        CaseSpec(tmp_path / "default-step", "zhou-cyl-bottom", SETS),
        CaseSpec(tmp_path / "half-step", "zhou-cyl-bottom", SETS + HALF_STEP),
    ]
    full, half = run_many(specs, Budget(cores=2))
    for o in (full, half):
        assert o.status == "ok" and o.summary is not None, o.error
        assert o.summary["steady"], o.summary["steady_reason"]
    q_full, q_half = full.summary["Q"], half.summary["Q"]
    assert q_half == pytest.approx(q_full, rel=0.01)
    # the smaller step is the one the check is about: it was taken
    assert half.summary["run"]["steps"] > 1.6 * full.summary["run"]["steps"]


PLANAR = ("mesh.cells_across=16", "run.end_time=0.5", "run.write_interval=0.25",
          "run.max_courant=0.25")  # fmt: skip
COURANT_SMOOTHING = ("numerics.face_smoothing='courant'",)


def test_the_courant_smoothing_at_the_steps_size_gives_the_steps_rate(tmp_path, solver):
    """`numerics.face_smoothing = 'courant'` solves the pressure at its own smoothing step.

    The coarse planar silo at Courant 0.25. With the smoothing sized by
    Courant 0.5 (face_smoothing_courant, the default) it is about twice the
    step; halved again by `numerics.rhie_chow_scale = 0.5` it is the step's
    size, and the steady rate must then be the step mode's: what is left is
    the pressure's relaxation by dt/tau per step, which moves the start-up,
    not the steady state (measured: -0.01%). Tolerance 0.5%, a sixth of what
    the smoothing's size moves (twice the step: +3.0%, asserted above 1.5%
    so that the comparison can tell the two apart).
    """
    specs = [
        CaseSpec(tmp_path / "step", "zhou-planar", PLANAR),
        CaseSpec(tmp_path / "courant", "zhou-planar", PLANAR + COURANT_SMOOTHING),
        CaseSpec(
            tmp_path / "courant-half",
            "zhou-planar",
            PLANAR + COURANT_SMOOTHING + ("numerics.rhie_chow_scale=0.5",),
        ),  # fmt: skip
    ]
    step, courant, courant_half = run_many(specs, Budget(cores=2))
    for o in (step, courant, courant_half):
        assert o.status == "ok" and o.summary is not None, o.error
        assert o.summary["steady"], o.summary["steady_reason"]
    q_step = step.summary["Q"]
    assert courant_half.summary["Q"] == pytest.approx(q_step, rel=0.005)
    assert courant.summary["Q"] / q_step - 1 > 0.015
