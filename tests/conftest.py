"""Shared fixtures.

Integration tests (marker ``openfoam``) need OpenFOAM, its headers and the
solver build; they fail when those are missing rather than skipping, so
that CI cannot go green without running them.  Deselect them explicitly
with ``-m "not openfoam"`` for a quick unit-test pass.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from foamsilo.scene import Scene, load_preset


@pytest.fixture(scope="session")
def openfoam():
    from foamsilo.toolchain import find_openfoam

    return find_openfoam()


@pytest.fixture(scope="session")
def solver(openfoam):
    from foamsilo.solver import ensure_solver

    return ensure_solver(of=openfoam)


def coarse_planar(**overrides: object) -> Scene:
    """The Zhou III.B planar silo at 16 cells across, 5 sqrt(L/g) long."""
    sets = ["mesh.cells_across=16", "run.end_time=0.5", "run.write_interval=0.25"]
    sets += [f"{k}={v}" for k, v in overrides.items()]
    return load_preset("zhou-planar", sets)


@pytest.fixture(scope="session")
def planar_run(tmp_path_factory, openfoam, solver):
    """One real run of the coarse planar silo, shared by the tests that read it."""
    from foamsilo.case import create_case
    from foamsilo.post import summarize
    from foamsilo.run import run_solver

    case_dir = tmp_path_factory.mktemp("planar") / "zhou-planar-16"
    case = create_case(coarse_planar(), case_dir, openfoam)
    result = run_solver(case.path, openfoam, solver)
    summary = summarize(case.path, result.as_dict())
    return case, result, summary


def repo_root() -> Path:
    return Path(__file__).resolve().parent.parent
