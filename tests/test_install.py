"""``pip install .`` (not editable) into a fresh venv, then a real run from another directory.

The templates, the solver sources, the presets and the study tables must come
from the installed package, not from the checkout. The fresh venv gets
foamsilo alone (``--no-deps``); its dependencies are seen through a ``.pth``
line naming the test environment's site-packages, whose editable foamsilo is
not on that path (an editable install is a finder, which a ``.pth`` line does
not install). The solver sources hash the same either way, so the build in
the cache is reused.
"""

from __future__ import annotations

import json
import os
import site
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import PLANAR_UNIFORM_ARGS

pytestmark = pytest.mark.openfoam

ROOT = Path(__file__).resolve().parent.parent


def test_a_plain_install_runs_a_preset_from_another_directory(tmp_path, solver):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    purelib = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    deps = [p for p in site.getsitepackages() if Path(p).is_dir()]
    Path(purelib, "foamsilo-test-deps.pth").write_text("\n".join(deps) + "\n")
    build = subprocess.run(
        [str(py), "-m", "pip", "install", "--no-deps", "--no-build-isolation", "--quiet",
         str(ROOT)], capture_output=True, text=True, cwd=tmp_path,
    )  # fmt: skip
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    where = subprocess.run([str(py), "-c", "import foamsilo; print(foamsilo.__file__)"],
                           capture_output=True, text=True, cwd=tmp_path, check=True).stdout  # fmt: skip
    assert Path(where.strip()).is_relative_to(venv), where  # the installed copy, not the checkout
    away = tmp_path / "elsewhere"
    away.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    run = subprocess.run(
        [str(venv / "bin" / "foamsilo"), "run", "zhou-planar", "-o", "case", "--json",
         "--set", "mesh.cells_across=16", *PLANAR_UNIFORM_ARGS, "--set", "run.end_time=0.3",
         "--set", "run.write_interval=0.15"],
        capture_output=True, text=True, cwd=away, env=env,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    s = json.loads(run.stdout)
    assert s["ok"] and s["cells"] == 1024
    assert (away / "case" / "report.md").exists()
    # the planar rate of the coarse silo: the band of tests/test_planar_discharge.py
    if s["steady"]:
        assert 0.136 <= s["Q_dimensionless"] <= 0.184
    else:
        assert s["mass_balance_rel_error"] < 1e-8
