"""Cases on Slurm: a real one-node cluster (munged, slurmctld, slurmd on localhost).

The cluster is started by the ``slurm`` fixture from Debian's packages and
stopped by PID after the tests; a missing Slurm fails them with the install
command. Nothing is mocked: sbatch submits the worker that local runs use,
the solver runs in the job (under mpirun for a case on two ranks), and the
rates are set against the same cases run on this machine.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from foamsilo.errors import SceneError
from foamsilo.pipeline import CaseSpec
from foamsilo.slurm import SlurmOptions, batch_script, job_dir
from foamsilo.sweep import load_sweep

from .conftest import LAB_UNIFORM_72
from .test_running import LAGGED, cli, sets

SWEEP = """
base = "zhou-planar"
output = "{out}"
ranks_per_case = 1
cpu_budget = 2
set = {{ "mesh.cells_across" = 24, "run.end_time" = 0.5, "run.write_interval" = 0.25 }}

[[cases]]                      # the longest: cancelled while it runs
"silo.orifice_width" = 0.025
"run.end_time" = 1.0

[[cases]]
"silo.orifice_width" = 0.03

[[cases]]                      # on two MPI ranks: --ntasks=2, mpirun in the job
"silo.orifice_width" = 0.025
"run.n_procs" = 2

[slurm]
time_limit = "30"
sbatch = ["--job-name=foamsilo-test"]
"""


def test_a_job_script_carries_the_ranks_and_the_options(tmp_path):
    spec = CaseSpec(tmp_path / "c", "zhou-planar", ("mesh.cells_across=24",), n_procs=2)
    opts = SlurmOptions(partition="compute", account="silo", time_limit="01:00:00",
                        sbatch=("--qos=short",))  # fmt: skip
    script = batch_script(spec, 2, opts)
    for line in ("#SBATCH --ntasks=2", "#SBATCH --partition=compute", "#SBATCH --account=silo",
                 "#SBATCH --time=01:00:00", "#SBATCH --qos=short"):  # fmt: skip
        assert line in script.splitlines()
    jd = job_dir(spec.case_dir)
    assert f"-m foamsilo.pipeline < {jd / 'spec.json'}" in script
    assert jd.name == "c.slurm" and jd.parent == spec.case_dir.resolve().parent


def test_bad_slurm_options_are_refused_by_name(tmp_path):
    with pytest.raises(SceneError, match=r"slurm\.sbatch\[0\].*one sbatch option"):
        SlurmOptions(sbatch=("qos=short",))
    with pytest.raises(SceneError, match=r"slurm\.partition"):
        SlurmOptions(partition="two words")
    sweep = tmp_path / "s.toml"
    sweep.write_text(SWEEP.format(out=tmp_path / "o") + 'queue = "x"\n')
    with pytest.raises(SceneError, match=r"sweep\.slurm\.queue.*allowed"):
        load_sweep(sweep)
    # the command line's options go over the sweep file's
    ok = tmp_path / "ok.toml"
    ok.write_text(SWEEP.format(out=tmp_path / "o"))
    opts = load_sweep(ok).slurm.merged(partition="p", sbatch=("--qos=q",), time_limit=None)
    assert (opts.partition, opts.time_limit) == ("p", "30")
    assert opts.sbatch == ("--job-name=foamsilo-test", "--qos=q")


def _rows(out: Path) -> list[dict]:
    try:
        return json.loads((out / "summary.json").read_text())["cases"]
    except (OSError, ValueError):
        return []


def _job(case_dir: str | Path) -> str:
    return json.loads((job_dir(Path(case_dir)) / "job.json").read_text())["job_id"]


def _state(job_id: str) -> str:
    res = subprocess.run(["squeue", "--noheader", "--format=%T", f"--jobs={job_id}"],
                         capture_output=True, text=True, env=dict(os.environ))  # fmt: skip
    return res.stdout.strip()


@pytest.mark.openfoam
def test_a_sweep_on_slurm_gives_the_local_rates_and_resumes(tmp_path, solver, slurm):
    local, remote = tmp_path / "local", tmp_path / "slurm"
    (tmp_path / "l.toml").write_text(SWEEP.format(out=local))
    (tmp_path / "s.toml").write_text(SWEEP.format(out=remote))
    code, ref = cli("sweep", str(tmp_path / "l.toml"), "--quiet")
    assert code == 0, ref

    # the sweep on Slurm, followed by a driver that is killed (kill -9) once
    # the first case's job was cancelled half-way and another case finished
    argv = [sys.executable, "-m", "foamsilo.cli", "sweep", str(tmp_path / "s.toml"),
            "--backend", "slurm", "--poll", "0.5", "--quiet", "--json"]  # fmt: skip
    driver = subprocess.Popen(argv, start_new_session=True, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)  # fmt: skip
    first = load_sweep(tmp_path / "s.toml").cases[0].directory
    cancelled = None
    deadline = time.monotonic() + 300
    try:
        while time.monotonic() < deadline and driver.poll() is None:
            # cancelled once it has written a complete time (0.25 s) to go on from
            if cancelled is None and (first / "0.25" / "uniform" / "time").exists():
                job = _job(first)
                if _state(job) == "RUNNING":
                    subprocess.run(["scancel", job], check=True, env=dict(os.environ))
                    cancelled = job
            rows = _rows(remote)
            if rows and rows[0]["status"] != "pending" and "ok" in [r["status"] for r in rows]:
                break
            time.sleep(0.2)
    finally:
        os.killpg(driver.pid, signal.SIGKILL)
        driver.wait()
    assert cancelled is not None
    rows = _rows(remote)
    # the cancelled job is reported as such, with its job id and state
    assert rows[0]["status"] == "SlurmJobError", rows[0]
    assert "CANCELLED" in rows[0]["error"] and cancelled in rows[0]["error"]
    finished = {r["directory"]: _job(r["directory"]) for r in rows if r["status"] == "ok"}
    assert finished

    # run again: finished cases are not submitted again, the cancelled one is
    # (it goes on from its latest complete time), a queued one is followed
    code, s = cli("sweep", str(tmp_path / "s.toml"), "--backend", "slurm", "--poll", "0.5",
                  "--quiet")  # fmt: skip
    assert code == 0, [(r["status"], r.get("error")) for r in s["cases"]]
    assert all(_job(d) == j for d, j in finished.items())
    again = _job(s["cases"][0]["directory"])
    assert again != cancelled
    first_run = json.loads((Path(s["cases"][0]["directory"]) / "run.json").read_text())
    assert first_run["start_time"] >= 0.25  # resumed, not started over
    # the two-rank case ran decomposed, in a job of two tasks
    two = Path(s["cases"][2]["directory"])
    assert (two / "processor1").is_dir()
    assert "#SBATCH --ntasks=2" in (job_dir(two) / "job.sh").read_text()
    # the rates: Slurm's equal this machine's within 1% (the same worker and
    # solver; the cancelled case restarted from a written time)
    for a, b in zip(s["cases"], ref["cases"], strict=True):
        assert a["Q"] == pytest.approx(b["Q"], rel=0.01), (a["directory"], a["Q"], b["Q"])


@pytest.mark.openfoam
def test_a_failed_job_is_reported_with_its_diagnosis(tmp_path, solver, slurm):
    # the lab-silo wedge with one PIMPLE pass and the stress lagged diverges
    # at t ~ 0.011 s (tests/test_running.py); in a job, the worker's
    # diagnosis comes back: quantity, time, last good time, the case kept
    case = tmp_path / "unstable"
    scene = [*LAB_UNIFORM_72, "numerics.outer_correctors=1", "run.end_time=0.05",
             "run.write_interval=0.05",
             LAGGED, "run.max_recoveries=0", "run.max_step_retakes=0"]  # fmt: skip
    code, s = cli("run", "zhou-cyl-bottom", "-o", str(case), "--slurm", "--poll", "0.5",
                  "--quiet", *sets(scene))  # fmt: skip
    assert code == 1
    err = s["error"]
    assert err["type"] == "DivergenceError", err
    assert 0.005 < err["time"] < 0.03
    assert err["last_good_time"] == "0"
    assert (case / "log.siloFoam").exists()
    assert (job_dir(case) / "outcome.json").exists()


@pytest.mark.openfoam
def test_the_validation_suite_runs_through_slurm(tmp_path, solver, slurm):
    # the quick suite's viscosity-cap entry (planar and axisymmetric silos at
    # eta_max = 1e2 and 1e5): each case a job, the same checks as on this machine
    work, out = tmp_path / "work", tmp_path / "out"
    code, res = cli("bench", "validation", "--quick", "--only", "cap", "--backend", "slurm",
                    "--work-dir", str(work), "-o", str(out), "--poll", "0.5", "--quiet")  # fmt: skip
    checks = [c for c in res["checks"] if c["entry"] == "cap"]
    assert checks and all(c["passed"] for c in checks), checks
    assert code == 0
    assert len(list(work.rglob("*.slurm/job.json"))) == 4  # one job per case
    assert "on SlurmBackend" in (out / "suite-quick.md").read_text()


def test_the_suite_on_slurm_wants_a_shared_work_dir(tmp_path):
    code, res = cli("bench", "validation", "--quick", "--only", "cap", "--backend", "slurm",
                    "-o", str(tmp_path / "out"))  # fmt: skip
    assert code == 2
    assert res["error"]["field"] == "--work-dir"
    assert not (tmp_path / "out").exists()  # nothing written


@pytest.mark.openfoam
def test_ctrl_c_leaves_the_job_queued_and_says_how_to_cancel_it(tmp_path, solver, slurm):
    case = tmp_path / "long"
    argv = [sys.executable, "-m", "foamsilo.cli", "run", "zhou-planar", "-o", str(case),
            "--slurm", "--poll", "0.5", "--json", "--set", "run.end_time=5"]  # fmt: skip
    driver = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                              text=True, start_new_session=True)  # fmt: skip
    deadline = time.monotonic() + 120
    while not (job_dir(case) / "job.json").exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    job = _job(case)
    while _state(job) != "RUNNING" and time.monotonic() < deadline:
        time.sleep(0.2)
    driver.send_signal(signal.SIGINT)  # what the terminal sends the driver on Ctrl-C
    out, _ = driver.communicate(timeout=60)
    try:
        assert driver.returncode == 130
        err = json.loads(out)["error"]
        assert f"scancel {job}" in err["message"]
        assert _state(job) in {"RUNNING", "PENDING"}  # the job goes on without its follower
    finally:
        subprocess.run(["scancel", job], env=dict(os.environ))
