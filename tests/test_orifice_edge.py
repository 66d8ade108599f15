"""Refining the orifice's edges (real siloFoam runs, the lab silo's wedge).

The flow turns round the orifice's edge, from the stagnant corner into the
jet, and the rate's grid error sits there: with the same cells elsewhere,
columns that narrow to h / 4 at the edge (`mesh.orifice_edge_refinement`)
must carry the rate further than halving every cell does. Both are steps
towards the same converged rate from below (the rate rises with
resolution: docs/validation/suite.md), so the check is an ordering:
Q(36 across) < Q(72 across) < Q(36 across, edge refined 4x). With the key not
reaching the mesh the refined run is the 36-across run and the second
comparison fails. The lab silo, graded (growth 1.1), 0.3 s.
"""

from __future__ import annotations

import pytest

from foamsilo.pipeline import Budget, CaseSpec, run_many

from .conftest import LAB_FORMER

pytestmark = pytest.mark.openfoam

SETS = (*LAB_FORMER, "mesh.growth_rate=1.1", "run.end_time=0.3", "run.write_interval=0.15")


def test_refining_the_orifice_edge_beats_halving_every_cell(tmp_path, solver):
    cases = {
        "36": ("mesh.cells_across=36",),
        "72": ("mesh.cells_across=72",),
        "36-edge": ("mesh.cells_across=36", "mesh.orifice_edge_refinement=4"),
    }
    # the scene's own sets after the pins of the former preset
    specs = [CaseSpec(tmp_path / name, "zhou-cyl-bottom", (*SETS, *sets))
             for name, sets in cases.items()]  # fmt: skip
    q = {}
    for spec, o in zip(specs, run_many(specs, Budget(cores=2)), strict=True):
        assert o.status == "ok" and o.summary is not None, o.error
        assert o.summary["steady"], o.summary["steady_reason"]
        assert o.summary["run"]["recoveries"] == []
        q[spec.case_dir.name] = o.summary["Q"]
    assert q["36"] < q["72"] < q["36-edge"]
