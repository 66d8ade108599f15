"""A real run of the planar silo of Zhou et al. 2019 (sec. III.B), coarse.

16 cells across L, 5 sqrt(L/g) of discharge, through the command line.

Band for the steady rate: the converged continuum value of the paper is
Q/(rho sqrt(g L^3)) = 0.16 +- 0.01 (Fig. 4a, 64 cells across), which is also
the 2D Beverloo law Q = C rho sqrt(g) D^(3/2) with the continuum constant
C = 1.28.  At 16 cells across the orifice spans 4 cells; resolution studies
of this problem (the paper's own code: 0.143 at 32 across against 0.157 at
64) show errors of order 10% at such coarse grids, so the test accepts
0.16 +- 15%: [0.136, 0.184].  Measured here: 0.1489.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from foamsilo.cli import main
from foamsilo.post import read_discharge
from foamsilo.scene import load_scene_file

pytestmark = pytest.mark.openfoam

BAND = (0.136, 0.184)


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory, solver):
    case = tmp_path_factory.mktemp("cli") / "planar16"
    args = [
        "run",
        "zhou-planar",
        "-o",
        str(case),
        "--quiet",
        "--json",
        "--set",
        "mesh.cells_across=16",
        "--set",
        "run.end_time=0.5",
        "--set",
        "run.write_interval=0.25",
    ]
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(args)
    assert code == 0, buf.getvalue()
    return case, json.loads(buf.getvalue())


def test_steady_discharge_in_the_paper_band(cli_run):
    _, s = cli_run
    assert s["ok"] and s["steady"], s["steady_reason"]
    assert BAND[0] <= s["Q_dimensionless"] <= BAND[1]
    # the fluctuation of the instantaneous rate is small (measured 1.7-1.9% at
    # 16 across, depending on round-off: the coarse flow is chaotic)
    assert s["Q_std_dimensionless"] < 0.03 * s["Q_dimensionless"]
    # Beverloo and paper comparisons are reported
    assert s["beverloo_2d"]["C"] == pytest.approx(1.28)
    assert abs(s["beverloo_2d"]["rel_diff"]) < 0.15


def test_flux_and_volume_estimates_agree(cli_run):
    _, s = cli_run
    assert s["flux_vs_volume_rel_diff"] < 0.01


def test_grains_are_conserved(cli_run):
    _, s = cli_run
    # V(t) + outflow(0..t) = V0 to the solver tolerances (explicit MULES)
    assert s["mass_balance_rel_error"] < 1e-8


def test_rate_does_not_depend_on_the_fill_height(cli_run):
    """Hourglass, not clepsydra: Q constant while the column drains."""
    case, s = cli_run
    scene = load_scene_file(case / "scene.toml")
    d = read_discharge(case, scene)
    t0, t1 = s["steady_window_s"]
    mid = 0.5 * (t0 + t1)
    first = (d.time >= t0) & (d.time < mid)
    second = (d.time >= mid) & (d.time <= t1)
    q1 = np.average(d.mass_flow[first], weights=d.delta_t[first])
    q2 = np.average(d.mass_flow[second], weights=d.delta_t[second])
    drop = (d.volume[first][0] - d.volume[second][-1]) / scene.silo.width
    assert drop > 0.5 * scene.silo.width  # the fill fell by more than L/2 ...
    # ... and Q changed by less than 3%. Each half-window mean carries ~1%
    # noise (1.9% fluctuations, ~4 independent samples in 0.2 s), so 3% is
    # 2 sigma of the difference; a clepsydra (Q ~ sqrt(h)) would lose about
    # half the relative drop in height: from 3.9L by more than L/2, > 6%.
    assert abs(q2 - q1) / q1 < 0.03


def test_outputs_are_written(cli_run):
    case, s = cli_run
    for name in (
        "discharge.csv",
        "discharge.png",
        "summary.json",
        "steps.csv",
        "log.siloFoam",
        "scene.toml",
        "case.foam",
    ):
        assert (case / name).exists(), name
    rows = (case / "discharge.csv").read_text().splitlines()
    assert rows[0].startswith("t_s,") and len(rows) > 100
    assert json.loads((case / "summary.json").read_text())["Q"] == pytest.approx(s["Q"])


def test_second_run_reuses_the_finished_case(cli_run, capsys):
    case, s = cli_run
    code = main(
        [
            "run",
            "zhou-planar",
            "-o",
            str(case),
            "--quiet",
            "--json",
            "--set",
            "mesh.cells_across=16",
            "--set",
            "run.end_time=0.5",
            "--set",
            "run.write_interval=0.25",
        ]
    )
    assert code == 0
    again = json.loads(capsys.readouterr().out)
    assert again["Q"] == pytest.approx(s["Q"])


def test_case_of_another_scene_is_not_overwritten(cli_run, capsys):
    case, _ = cli_run
    code = main(["run", "zhou-planar", "-o", str(case), "--json", "--set", "mesh.cells_across=32"])
    assert code == 1
    assert "another scene" in json.loads(capsys.readouterr().out)["error"]["message"]
