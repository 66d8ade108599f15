"""The case lifecycle and the defects a careful user found, each reproduced for real.

Two runs on one case, a killed sweep, ``--overwrite`` on a directory that is
not a case, ``--rerun``, a lost mesh, Ctrl-C and kill -9 while meshing, and
every input that used to end in a traceback: each test runs the command line
(in-process, or as a separate process where a signal is involved) on real
cases of the coarse planar silo.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from foamsilo.cli import main

from .conftest import PLANAR_UNIFORM

PLANAR_16 = ["mesh.cells_across=16", *PLANAR_UNIFORM, "run.end_time=0.5", "run.write_interval=0.25"]


def cli(*args: str) -> tuple[int, dict]:
    """Run the command line in-process with --json; return the exit code and its object."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main([*args, "--json"])
    text = buf.getvalue()
    return code, json.loads(text)  # strict: one object, no NaN


def sets(values: list[str]) -> list[str]:
    return [a for v in values for a in ("--set", v)]


def start(args: list[str], **kw: object) -> subprocess.Popen[str]:
    """``foamsilo ARGS`` as its own process group (a terminal's job)."""
    return subprocess.Popen([sys.executable, "-m", "foamsilo", *args], start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)  # fmt: skip


def wait_for(cond, timeout: float = 120.0, what: str = "") -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)


def processes_on(path: Path) -> list[str]:
    """Command lines of the processes that name ``path`` (solvers, workers)."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if str(path) in cmd and int(d.name) != os.getpid():
            out.append(f"{d.name}: {cmd.strip()}")
    return out


# ----------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("make", "field", "words"),
    [
        (lambda d: d.joinpath("s.toml").write_bytes(b"\x00\x01\xff\xfe\x89PNG"), "scene", "not UTF-8"),
        (lambda d: d.joinpath("s.toml").write_bytes('name = "caf\xe9"\n'.encode("latin-1")),
         "scene", "not UTF-8"),
        (lambda d: d.joinpath("s.toml").mkdir(), "scene", "is a directory"),
    ],
)  # fmt: skip
def test_unreadable_scene_files_are_refused_with_a_message(tmp_path, make, field, words):
    make(tmp_path)
    code, out = cli("new", str(tmp_path / "s.toml"), "-o", str(tmp_path / "case"))
    assert code == 2 and out["ok"] is False
    assert out["error"]["field"] == field or out["error"]["field"].startswith(field)
    assert words in out["error"]["message"]
    assert not (tmp_path / "case").exists()


def test_a_non_ascii_scene_name_is_refused_before_anything_is_written(tmp_path):
    code, out = cli("new", "zhou-planar", "-o", str(tmp_path / "c"), "--set", "name='café'")
    assert code == 2 and out["error"]["field"] == "name"
    assert "ASCII" in out["error"]["message"]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("output", "words"),
    [
        ("file", "is a file"),
        ("file/case", "lies under the file"),
        ("with space/case", "cannot use ' '"),
        ("caf\u00e9/case", "cannot use 'é'"),
        ("/proc/foamsilo-case", "cannot"),
        ("/sys/foamsilo/case", "cannot"),
    ],
)
def test_unusable_output_paths_are_refused_up_front(tmp_path, output, words):
    (tmp_path / "file").write_text("a user's file\n")
    target = output if output.startswith("/") else str(tmp_path / output)
    code, out = cli("new", "zhou-planar", "-o", target, *sets(PLANAR_16))
    assert code == 2, out
    assert out["error"]["field"] == "--output"
    assert words in out["error"]["message"]
    # nothing half-written: no empty parent left behind, the file untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
    assert (tmp_path / "file").read_text() == "a user's file\n"


def test_a_directory_that_is_not_a_case_is_refused_as_the_scene(tmp_path):
    d = tmp_path / "notes"
    d.mkdir()
    (d / "todo.txt").write_text("x\n")
    code, out = cli("run", str(d))
    assert code == 2 and out["error"]["field"] == "scene"
    assert "not a foamsilo case" in out["error"]["message"]
    code, out = cli("post", str(d))
    assert code == 2 and "not a foamsilo case" in out["error"]["message"]
    assert sorted(p.name for p in d.iterdir()) == ["todo.txt"]


def test_argument_errors_are_json_under_json(capsys):
    assert main(["run", "--json"]) == 2  # the scene is missing
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is False and out["error"]["type"] == "UsageError"
    assert "scene" in out["error"]["message"]
    assert main(["bench", "nonsense", "--json"]) == 2
    assert "invalid choice" in json.loads(capsys.readouterr().out)["error"]["message"]


def test_overwrite_never_deletes_a_directory_that_is_not_a_case(tmp_path):
    d = tmp_path / "mine"
    d.mkdir()
    (d / "important.txt").write_text("keep me\n")
    code, out = cli("new", "zhou-planar", "-o", str(d), "--overwrite", *sets(PLANAR_16))
    assert code == 1 and out["error"]["type"] == "CaseStateError"
    assert "not a foamsilo case" in out["error"]["message"]
    assert (d / "important.txt").read_text() == "keep me\n"
    assert sorted(p.name for p in d.iterdir()) == ["important.txt"]


# ----------------------------------------------------------------------------- damaged output


@pytest.fixture(scope="module")
def finished(tmp_path_factory, solver):
    case = tmp_path_factory.mktemp("life") / "planar"
    code, s = cli("run", "zhou-planar", "-o", str(case), "--quiet", *sets(PLANAR_16))
    assert code == 0, s
    return case, s


def _copy(case: Path, dst: Path) -> Path:
    import shutil

    shutil.copytree(case, dst, ignore=shutil.ignore_patterns(".foamsilo.lock"))
    return dst


@pytest.mark.openfoam
def test_post_refuses_nan_and_garbage_output_naming_the_file(finished, tmp_path):
    case = finished[0]
    for name, bad in (("nan", "0.31\tnan\t0\n"), ("garbage", "Killing PID 1234\n")):
        c = _copy(case, tmp_path / name)
        dat = next((c / "postProcessing" / "orificeFlow" / "0").glob("*.dat"))
        lines = dat.read_text().splitlines(keepends=True)
        lines.insert(len(lines) // 2, bad)
        dat.write_text("".join(lines))
        code, out = cli("post", str(c))
        assert code == 2, out
        assert out["ok"] is False and out["error"]["type"] == "DamagedOutputError"
        assert str(dat) in out["error"]["message"]
        assert not (c / "summary.json").read_text().count("NaN")


@pytest.mark.openfoam
def test_a_table_cut_to_half_the_run_is_flagged_not_reduced_silently(finished, tmp_path):
    c = _copy(finished[0], tmp_path / "cut")
    for name in ("orificeFlow", "granularVolume", "topFlow"):
        dat = next((c / "postProcessing" / name / "0").glob("*.dat"))
        lines = dat.read_text().splitlines(keepends=True)
        dat.write_text("".join(lines[: len(lines) // 2]))
    code, s = cli("post", str(c))
    assert code == 0, s
    assert any("truncated" in w for w in s["warnings"]), s["warnings"]
    assert "truncated" in (c / "report.md").read_text()


# ----------------------------------------------------------------------------- lifecycle


@pytest.mark.openfoam
def test_two_runs_on_one_case_the_second_is_refused_and_one_solver_runs(tmp_path, solver):
    case = tmp_path / "busy"
    first = start(["run", "zhou-planar", "-o", str(case), "--quiet", "--json",
                   *sets(["mesh.cells_across=24", "run.end_time=0.5", "run.write_interval=0.1"])])  # fmt: skip
    try:
        wait_for(lambda: (case / "log.siloFoam").exists(), what="the first solver")
        for extra in ([], ["--resume"], ["--rerun"], ["--overwrite"]):
            code, out = cli("run", str(case), "--quiet", *extra)
            assert code == 1, (extra, out)
            assert out["error"]["type"] == "CaseStateError" and out["error"]["state"] == "running"
            assert f"PID {first.pid}" in out["error"]["message"]
        code, out = cli("new", "zhou-planar", "-o", str(case), "--overwrite", *sets(PLANAR_16))
        assert code == 1 and "being run by" in out["error"]["message"]
        solvers = [p for p in processes_on(case) if "siloFoam" in p and "setpriv" not in p]
        assert len(solvers) == 1, solvers
    finally:
        out, err = first.communicate(timeout=300)
    assert first.returncode == 0, err[-2000:]
    assert json.loads(out)["steady"]


@pytest.mark.openfoam
def test_rerun_really_reruns_and_overwrite_starts_an_interrupted_case_over(tmp_path, solver):
    case = tmp_path / "again"
    scene = ["mesh.cells_across=16", "run.end_time=0.3", "run.write_interval=0.05"]
    code, s = cli("run", "zhou-planar", "-o", str(case), "--quiet", *sets(scene))
    assert code == 0, s
    first_steps = s["run"]["steps"]
    code, s = cli("run", str(case), "--quiet", "--rerun")
    assert code == 0, s
    assert s["run"]["start_time"] == 0.0 and s["run"]["steps"] == first_steps
    # interrupted (kill -9), then --overwrite writes it afresh from its scene and runs
    p = start(["run", str(case), "--quiet", "--rerun"])
    wait_for(lambda: (case / "0.1").exists() and not (case / "0.3").exists()
             and (case / "log.siloFoam").stat().st_size > 0, what="t = 0.1")  # fmt: skip
    os.killpg(p.pid, signal.SIGKILL)
    p.communicate()
    code, out = cli("run", str(case), "--quiet")
    assert code == 1 and out["error"]["state"] == "interrupted"
    assert "--resume" in out["error"]["message"] and "--rerun" in out["error"]["message"]
    code, s = cli("run", str(case), "--quiet", "--overwrite")
    assert code == 0, s
    assert s["run"]["start_time"] == 0.0 and s["steady"] in (True, False)


@pytest.mark.openfoam
def test_a_lost_mesh_is_rebuilt_from_the_case_scene(tmp_path, solver):
    import shutil

    case = tmp_path / "nomesh"
    code, _ = cli("new", "zhou-planar", "-o", str(case), *sets(PLANAR_16))
    assert code == 0
    faces = (case / "constant" / "polyMesh" / "faces").read_bytes()
    shutil.rmtree(case / "constant" / "polyMesh")
    code, s = cli("run", str(case), "--quiet")
    assert code == 0, s
    assert (case / "constant" / "polyMesh" / "faces").read_bytes() == faces  # the same mesh
    assert s["steady"]


@pytest.mark.openfoam
def test_a_stale_lock_of_a_dead_process_is_cleared(tmp_path, solver):
    case = tmp_path / "stale"
    code, _ = cli("new", "zhou-planar", "-o", str(case), *sets(PLANAR_16))
    assert code == 0
    dead = subprocess.Popen(["true"])
    dead.wait()
    lock = {"pid": dead.pid, "host": os.uname().nodename, "started": "then", "command": "x"}
    (case / ".foamsilo.lock").write_text(json.dumps(lock))
    code, s = cli("run", str(case), "--quiet")
    assert code == 0, s


@pytest.mark.openfoam
def test_a_killed_sweep_leaves_no_orphan_and_resumes(tmp_path, solver):
    out = tmp_path / "out"
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        f'base = "zhou-planar"\noutput = "{out}"\ncpu_budget = 2\n[set]\n'
        '"mesh.cells_across" = 24\n"run.end_time" = 0.5\n"run.write_interval" = 0.1\n'
        '[grid]\n"silo.orifice_width" = [0.02, 0.03]\n'
    )
    p = start(["sweep", str(sweep), "--quiet", "--json"])
    wait_for(lambda: any("siloFoam" in c for c in processes_on(out)), what="a solver")
    os.kill(p.pid, signal.SIGKILL)  # the driver alone, as `kill -9 PID` does
    p.communicate()
    wait_for(lambda: not processes_on(out), timeout=20, what="the sweep's children to go")
    code, s = cli("sweep", str(sweep), "--quiet")
    assert code == 0, [(r["status"], r.get("error")) for r in s["cases"]]
    assert [r["status"] for r in s["cases"]] == ["ok", "ok"]
    assert not processes_on(out)


# ----------------------------------------------------------------------------- meshing

#: the circular lateral silo's uniform rows at 40 across: 352,800 cells, seconds of gmsh
UNIFORM_LATERAL_40 = ["--set", "mesh.cells_across=40", "--set", "mesh.growth_rate=1",
                      "--set", "mesh.coarse_cells_across=16", "--set", "mesh.orifice_region=1"]  # fmt: skip


@pytest.mark.openfoam
def test_ctrl_c_during_meshing_stops_at_once_and_leaves_nothing(tmp_path, openfoam):
    # a 3D mesh of ~350k cells (uniform rows) takes gmsh several seconds
    args = ["new", "zhou-cyl-lateral", "-o", str(tmp_path / "c"), *UNIFORM_LATERAL_40]
    p = start(args)
    # once meshing has begun (the temporary case is made just before), not
    # while the interpreter is still importing (seen under load: exit 1)
    wait_for(lambda: any(tmp_path.glob(".c.foamsilo-tmp-*")), what="the temporary case")
    time.sleep(1.0)
    t0 = time.monotonic()
    os.killpg(p.pid, signal.SIGINT)
    p.communicate(timeout=60)
    assert p.returncode == 130
    assert time.monotonic() - t0 < 2.0  # not after gmsh finishes
    assert list(tmp_path.iterdir()) == []


@pytest.mark.openfoam
def test_a_temporary_case_left_by_kill_9_is_removed_by_the_next_one(tmp_path, openfoam):
    args = ["new", "zhou-cyl-lateral", "-o", str(tmp_path / "c"), *UNIFORM_LATERAL_40]
    p = start(args)
    wait_for(lambda: any(tmp_path.glob(".c.foamsilo-tmp-*")), what="the temporary case")
    time.sleep(1.0)
    os.killpg(p.pid, signal.SIGKILL)
    p.communicate()
    assert list(tmp_path.glob(".c.foamsilo-tmp-*"))  # what kill -9 leaves
    code, out = cli("new", "zhou-planar", "-o", str(tmp_path / "c"), *sets(PLANAR_16))
    assert code == 0, out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c"]


@pytest.mark.openfoam
def test_a_rate_swinging_from_step_to_step_is_warned_of(finished, tmp_path):
    """The same run with its orifice flux smoothed, then made to swing +-3% every step."""
    import numpy as np

    def rewrite(c: Path, swing: float) -> None:
        dat = next((c / "postProcessing" / "orificeFlow" / "0").glob("*.dat"))
        lines = dat.read_text().splitlines(keepends=True)
        head = [x for x in lines if x.startswith("#")]
        rows = np.array([[float(v) for v in x.split()] for x in lines if not x.startswith("#")])
        k = np.arange(len(rows))
        padded = np.pad(rows[:, 1], 20, mode="edge")  # no dip at the ends
        smooth = np.convolve(padded, np.ones(41) / 41, mode="valid")
        rows[:, 1] = smooth * (1 + swing * (-1.0) ** k)
        dat.write_text("".join(head) + "".join("\t".join(f"{v:.10e}" for v in r) + "\n"
                                               for r in rows))  # fmt: skip

    calm, swinging = _copy(finished[0], tmp_path / "calm"), _copy(finished[0], tmp_path / "swing")
    rewrite(calm, 0.0)
    rewrite(swinging, 0.03)
    code, s = cli("post", str(calm))
    assert code == 0 and s["steady"], s
    assert s["Q_step_swing"] < 0.01 and not any("swings" in w for w in s["warnings"])
    code, s = cli("post", str(swinging))
    assert code == 0 and s["steady"], s["steady_reason"]  # the mean is as flat as before
    # +-a every step: the step-to-step change is 2a, over sqrt(2): sqrt(2) a
    assert s["Q_step_swing"] == pytest.approx(0.03 * np.sqrt(2), rel=0.05)
    assert any("swings by 4.2%" in w for w in s["warnings"]), s["warnings"]
    assert "swings by 4.2%" in (swinging / "report.md").read_text()


def test_a_study_keeps_its_failed_cases_for_inspection(tmp_path, monkeypatch, capsys):
    """A temporary work directory goes, but for the cases a report calls kept."""
    import argparse
    import json

    from foamsilo.cli import _work_dir

    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    args = argparse.Namespace(work_dir=None)
    with _work_dir(args, "study-") as work:
        for name, status in (("00", "diverged"), ("01", "finished"), ("02", "interrupted")):
            case = work / name
            case.mkdir()
            (case / "foamsilo.json").write_text("{}")
            (case / "run.json").write_text(json.dumps({"status": status}))
        (work / "study.log").write_text("")
    assert (work / "00").is_dir() and (work / "02").is_dir()  # kept
    assert not (work / "01").exists() and not (work / "study.log").exists()
    assert "kept for inspection" in capsys.readouterr().err
    with _work_dir(args, "clean-") as clean:
        (clean / "00").mkdir()
    assert not clean.exists()  # nothing failed: nothing left behind
