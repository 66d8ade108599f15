"""Progress of many cases on a terminal: cases done / total, the running cases' time, an ETA.

The sweep runs for real with its stderr on a pseudo-terminal (what a user's
shell gives it); off a terminal and under ``--json`` there is no bar.
"""

from __future__ import annotations

import json
import os
import pty
import re
import subprocess
import sys
from pathlib import Path

import pytest

from foamsilo.run import log_time

SWEEP = """
base = "zhou-planar"
output = "{out}"
cpu_budget = 1
set = {{ "mesh.cells_across" = 16, "run.end_time" = 0.5, "run.write_interval" = 0.25 }}

[grid]
"silo.orifice_width" = [0.02, 0.025]
"""


def _on_a_terminal(argv: list[str]) -> tuple[int, str, str]:
    """Run ``argv`` with stderr on a pseudo-terminal; return its status, stdout and stderr."""
    master, slave = pty.openpty()
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=slave, text=True)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # the terminal closed: the program ended
            break
        if not data:
            break
        chunks.append(data)
    out = proc.stdout.read() if proc.stdout else ""
    os.close(master)
    text = b"".join(chunks).decode("utf-8", "replace")
    return proc.wait(), out, re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", text)  # colours and moves off


def test_the_log_time_is_the_solvers_latest_step(tmp_path):
    assert log_time(tmp_path) is None  # no log yet
    (tmp_path / "log.siloFoam").write_text(
        "Time = 0.01\n\nCourant Number mean: 0 max: 0.1\nTime = 0.0125\n\nsmoothSolver: ..."
    )
    assert log_time(tmp_path) == pytest.approx(0.0125)


@pytest.mark.openfoam
def test_a_sweep_on_a_terminal_shows_its_cases_their_time_and_an_eta(tmp_path, solver):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(SWEEP.format(out=tmp_path / "out"))
    code, out, err = _on_a_terminal([sys.executable, "-m", "foamsilo.cli", "sweep", str(sweep)])
    assert code == 0, err[-3000:]
    assert "0/2 cases" in err and "1/2 cases" in err  # done / total
    assert "ETA" in err
    assert "/0.5 s" in err  # a running case's simulated time over its end time
    assert "case 0 (000-orifice_width=0.02): ok" in err  # one line per finished case
    # under --json: one JSON object on stdout, no bar on the terminal
    code, out, err = _on_a_terminal(
        [sys.executable, "-m", "foamsilo.cli", "sweep", str(sweep), "--json"]
    )
    assert code == 0
    assert [r["status"] for r in json.loads(out)["cases"]] == ["ok", "ok"]
    assert "cases" not in err and "ETA" not in err
    assert Path(tmp_path / "out" / "summary.csv").exists()


@pytest.mark.openfoam
def test_a_run_on_a_terminal_prints_its_summary_after_the_bar(tmp_path, solver):
    # the bar starts inside the run, where the runner sends stdout to the
    # solver's log: it must not hand that (closed) log back as stdout
    argv = [sys.executable, "-m", "foamsilo.cli", "run", "zhou-planar", "-o", str(tmp_path / "c"),
            "--set", "mesh.cells_across=12", "--set", "run.end_time=0.1",
            "--set", "run.write_interval=0.05"]  # fmt: skip
    code, out, err = _on_a_terminal(argv)
    assert code == 0, err[-3000:]
    assert "siloFoam" in err and "t = " in err  # the bar was shown
    assert "mass balance error" in out  # the summary, on stdout
