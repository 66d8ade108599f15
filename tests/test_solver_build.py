"""The solver build: cached by source hash, rebuilt only when a file changes."""

from __future__ import annotations

import shutil

import pytest

from foamsilo import solver as solver_mod

pytestmark = pytest.mark.openfoam


def test_build_is_found_again_without_rebuilding(solver, openfoam):
    again = solver_mod.ensure_solver(of=openfoam)
    assert again.root == solver.root
    assert again.executable.exists() and again.library.exists()
    assert (solver.root / "build.json").exists()
    # the solver finds its library by rpath, without LD_LIBRARY_PATH
    import subprocess

    out = subprocess.run(["ldd", str(solver.executable)], capture_output=True, text=True).stdout
    assert str(solver.library.parent) in out and "not found" not in out


def test_hash_changes_exactly_when_a_source_changes(tmp_path, monkeypatch, openfoam):
    src = tmp_path / "solver_src"
    shutil.copytree(solver_mod.solver_source_dir(), src)
    monkeypatch.setattr(solver_mod, "solver_source_dir", lambda: src)
    h0 = solver_mod.source_hash(openfoam)
    # build products do not count
    (src / "siloFoam" / "Make" / "linux64GccDPInt32Opt").mkdir(parents=True, exist_ok=True)
    (src / "siloFoam" / "Make" / "linux64GccDPInt32Opt" / "x.o").write_text("obj")
    assert solver_mod.source_hash(openfoam) == h0
    f = src / "siloFoam" / "pEqn.H"
    f.write_text(f.read_text() + "\n// changed\n")
    assert solver_mod.source_hash(openfoam) != h0


def test_doctor_reports_every_component(capsys, solver):
    import json

    from foamsilo.cli import main

    assert main(["doctor", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["ok"] and not r["missing"]
    for key in ("openfoam", "headers", "solver", "gmsh", "mpi"):
        assert r[key]["found"], key
    assert r["openfoam"]["version"] == "v1912" or r["openfoam"]["source"] == "user-environment"
