"""Restart bookkeeping, hostfiles and sweep files, without running OpenFOAM."""

from __future__ import annotations

import contextlib
import multiprocessing
import socket
from pathlib import Path
from typing import Any

import pytest

from foamsilo.case.times import (
    RESTART_FIELDS,
    prune_incomplete_times,
    prune_times_past_step_rows,
    resumable_times,
    time_directories,
)
from foamsilo.errors import SceneError
from foamsilo.run.runner import _all_local
from foamsilo.sweep import load_sweep

FOOTER = "\n// " + "*" * 73 + " //\n"


def write_time(root: Path, name: str, whole: bool = True, skip: str | None = None) -> None:
    """A time directory as siloFoam writes it; ``whole=False`` truncates U (killed write)."""
    for f in RESTART_FIELDS:
        if f == skip:
            continue
        p = root / name / f
        p.parent.mkdir(parents=True, exist_ok=True)
        body = "FoamFile {}\ninternalField uniform 0;\n"
        p.write_text(body if (f == "U" and not whole) else body + FOOTER)


def make_case(tmp_path: Path) -> Path:
    case = tmp_path / "case"
    (case / "0").mkdir(parents=True)
    (case / "0" / "U").write_text("x")
    (case / "0" / "alpha.granular").write_text("x")
    return case


def test_a_killed_write_is_not_a_restart_point_and_is_removed(tmp_path):
    case = make_case(tmp_path)
    write_time(case, "0.1")
    write_time(case, "0.2")
    write_time(case, "0.3", whole=False)  # U cut short
    write_time(case, "0.4", skip="phi")  # phi never written
    write_time(case, "0.5")
    (case / "0.5" / "alphaPhi0.granular").write_text("FoamFile {}\n")  # cut: read on restart
    assert time_directories(case) == ["0", "0.1", "0.2"]
    removed = prune_incomplete_times(case)
    assert sorted(removed) == ["0.3", "0.4", "0.5"]
    assert sorted(p.name for p in case.iterdir()) == ["0", "0.1", "0.2"]


def test_a_decomposed_time_counts_only_when_every_rank_has_it(tmp_path):
    case = make_case(tmp_path)
    for rank in (0, 1):
        write_time(case / f"processor{rank}", "0.1")
    write_time(case / "processor0", "0.2")
    write_time(case / "processor1", "0.2", whole=False)
    write_time(case / "processor0", "0.3")  # rank 1 never got there
    assert time_directories(case) == ["0", "0.1"]
    prune_incomplete_times(case)
    for rank in (0, 1):
        assert sorted(p.name for p in (case / f"processor{rank}").iterdir()) == ["0.1"]


def write_rows(case: Path, name: str, start: str, times: list[float]) -> None:
    """A per-step function-object table as OpenFOAM writes it (header, time first)."""
    table = case / "postProcessing" / name / start / "surfaceFieldValue.dat"
    table.parent.mkdir(parents=True, exist_ok=True)
    rows = "".join(f"{t:.8g}\t{0.1 * t:.6g}\n" for t in times)
    table.write_text("# Time    \tsum(phi)\n" + rows)


def test_a_time_written_before_its_step_s_rows_is_not_a_restart_point(tmp_path):
    # the kill came after 0.2 was written whole but before the function
    # objects ran for its step (they run at the next step's start): a
    # restart from 0.2 would leave that step out of the tables for good
    case = make_case(tmp_path)
    for t in ("0.1", "0.2"):
        write_time(case, t)
    write_rows(case, "orificeFlow", "0", [0.05, 0.1, 0.15, 0.1975])
    write_rows(case, "granularVolume", "0", [0.05, 0.1, 0.15, 0.1975])
    # what an interrupted run reports as the time to resume from is the one
    # the resume takes (a run stopped by Ctrl-C right after writing 0.2 said
    # 0.2 and resumed from 0.1)
    assert resumable_times(case) == ["0", "0.1"]
    assert prune_times_past_step_rows(case) == ["0.2"]
    assert time_directories(case) == ["0", "0.1"]
    # rows up to the written time (or past it): nothing removed; the
    # latest restart's table is the one read
    write_time(case, "0.2")
    write_rows(case, "orificeFlow", "0.1", [0.1, 0.15, 0.2])
    write_rows(case, "granularVolume", "0.1", [0.1, 0.15, 0.2, 0.205])
    assert prune_times_past_step_rows(case) == []
    assert time_directories(case) == resumable_times(case) == ["0", "0.1", "0.2"]


def test_hostfiles_naming_only_this_machine_are_local(tmp_path):
    local = tmp_path / "local"
    local.write_text(f"localhost\n# comment\n{socket.gethostname()}\n\n")
    remote = tmp_path / "remote"
    remote.write_text("localhost\nnode17.cluster slots=16\n")
    assert _all_local(None)
    assert _all_local(local)
    assert not _all_local(remote)


SWEEP = """
base = "zhou-planar"
output = "{out}"
{extra}
[set]
"mesh.cells_across" = 16
[grid]
"silo.orifice_width" = [0.02, 0.025]
"mesh.top_cell_ratio" = [2.0, 3.0]
[[cases]]
"silo.orifice_width" = 0.03
"""


def sweep_file(tmp_path: Path, extra: str = "", grid_value: str | None = None) -> Path:
    text = SWEEP.format(out=tmp_path / "out", extra=extra)
    if grid_value is not None:
        text = text.replace("[0.02, 0.025]", grid_value)
    p = tmp_path / "sweep.toml"
    p.write_text(text)
    return p


def test_sweep_grid_and_list_make_every_case(tmp_path):
    sw = load_sweep(sweep_file(tmp_path, "cpu_budget = 4\nranks_per_case = 2"))
    assert len(sw.cases) == 2 * 2 + 1
    assert sw.cases_at_once == 2  # 2 cases x 2 ranks <= 4 cores
    assert sw.cases[-1].overrides == {"mesh.cells_across": 16, "silo.orifice_width": 0.03}
    assert len({c.directory for c in sw.cases}) == len(sw.cases)
    assert all(c.directory.parent == tmp_path / "out" for c in sw.cases)


@pytest.mark.parametrize(
    ("extra", "grid_value", "field"),
    [
        ("cpu_budget = 1\nranks_per_case = 2", None, "sweep.cpu_budget"),
        ("ranks_per_case = 0", None, "sweep.ranks_per_case"),
        ("colour = 'red'", None, "sweep.colour"),
        ("", "[]", "sweep.grid.silo.orifice_width"),
        ("", "[0.02, 0.2]", "cases[2].silo.orifice_width"),  # wider than the silo
    ],
)
def test_bad_sweep_is_refused_before_anything_runs(tmp_path, extra, grid_value, field):
    with pytest.raises(SceneError) as err:
        load_sweep(sweep_file(tmp_path, extra, grid_value))
    assert err.value.field == field
    assert not (tmp_path / "out").exists()


def test_pyfoam_timers_that_rearm_themselves_are_stopped():
    """PyFoam's stop-file timer starts its successor; a cancel during its callback missed it.

    The missed timer re-armed forever and kept pytest from exiting after its
    summary (seen in a CI rehearsal). Here the cancel comes while a callback
    is running (it takes 0.1 s before it re-arms).
    """
    import threading
    import time

    from foamsilo.run.runner import _stop_pyfoam_timers

    class Thread:
        timer = None
        timer2 = None

    thrd = Thread()

    def rearm() -> None:
        time.sleep(0.1)
        thrd.timer2 = threading.Timer(0.01, rearm)
        thrd.timer2.start()

    thrd.timer2 = threading.Timer(0.01, rearm)
    thrd.timer2.start()
    time.sleep(0.05)  # the callback is running now
    _stop_pyfoam_timers(thrd)
    time.sleep(0.3)
    assert not thrd.timer2.is_alive()


def _start_runner_together(barrier: Any, case: str, answers: Any) -> None:
    """One run's first steps: the runner's start (refused before the solver), then PyFoam's log."""
    import time

    from PyFoam.Infrastructure import Hardcoded
    from PyFoam.Infrastructure.Logging import foamLogger

    from foamsilo.errors import UsageError
    from foamsilo.run.runner import run_solver

    makedirs = Hardcoded.makedirs

    def slow_makedirs(*args: Any, **kwargs: Any) -> None:
        time.sleep(0.2)  # a slow file system: every run checks before any creates
        makedirs(*args, **kwargs)

    Hardcoded.makedirs = slow_makedirs
    barrier.wait()
    try:
        with contextlib.suppress(UsageError):  # n_procs = 0: refused after the runner's set-up
            run_solver(Path(case), None, None, n_procs=0)  # type: ignore[arg-type]
        foamLogger()  # what PyFoam's runner does first
        answers.put("ok")
    except Exception as exc:  # noqa: BLE001 - the answer is the exception's name
        answers.put(type(exc).__name__)


def test_runs_started_together_on_a_fresh_machine_do_not_race_for_pyfoam_s_log(
    tmp_path, monkeypatch
):
    """Two cases started at once by ``--jobs 2`` on a fresh machine: one stopped with FileExistsError.

    PyFoam makes its log directory by a check and then ``os.makedirs``; here that
    window is widened to 0.2 s, as on a slow file system, and four runs start
    together on a fresh home directory (a user other than root, whose log
    directory would be /var/log/pyFoam). Without the runner making the directory
    first, three of the four stop with FileExistsError.
    """
    ctx = multiprocessing.get_context("fork")
    monkeypatch.setenv("USER", "foamsilo-test")
    monkeypatch.setenv("HOME", str(tmp_path))
    barrier, answers = ctx.Barrier(4), ctx.Queue()
    procs = [
        ctx.Process(
            target=_start_runner_together, args=(barrier, str(tmp_path / "no-case"), answers)
        )
        for _ in range(4)
    ]
    for p in procs:
        p.start()
    got = [answers.get(timeout=60) for _ in procs]
    for p in procs:
        p.join()
    assert got == ["ok"] * 4
    assert (tmp_path / ".pyFoam" / "log").is_dir()
