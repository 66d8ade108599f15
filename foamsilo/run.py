"""Run siloFoam on a case through PyFoam, with progress and a divergence stop.

The solver runs under a :class:`PyFoam.Execution.BasicRunner.BasicRunner`
subclass; every log line goes to a :class:`LogMonitor`, which keeps one row
per time step (time, step, Courant numbers, residuals, continuity) and
decides whether the run diverged:

* a NaN or Inf in a residual, a Courant number or the time step;
* a Courant number far above its limit (``COURANT_BLOWUP`` times);
* a time step collapsed by ``DT_COLLAPSE`` from the largest one so far.

A diverged run is stopped at once and reported with
:class:`~foamsilo.errors.DivergenceError` (quantity, time, last good time
directory); the case is kept for inspection.
"""

from __future__ import annotations

import contextlib
import csv
import math
import os
import re
import resource
import shlex
import shutil
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from foamsilo.errors import (
    DivergenceError,
    FoamError,
    FoamsiloError,
    RunInterruptedError,
    RunTimeLimitError,
)
from foamsilo.solver import SolverBuild
from foamsilo.toolchain import OpenFOAM

COURANT_BLOWUP = 20.0
DT_COLLAPSE = 1e-4
LOG_NAME = "log.siloFoam"
STEP_TABLE = "steps.csv"

_FLOAT = r"([-+]?(?:\d+\.?\d*(?:[eE][-+]?\d+)?|nan|inf|-nan|-inf))"
_RE_TIME = re.compile(r"^Time = " + _FLOAT + r"\s*$")
_RE_DT = re.compile(r"^deltaT = " + _FLOAT)
_RE_CO = re.compile(r"^Courant Number mean: " + _FLOAT + r" max: " + _FLOAT)
_RE_ACO = re.compile(r"^Interface Courant Number mean: " + _FLOAT + r" max: " + _FLOAT)
_RE_GCO = re.compile(r"^Granular Courant Number max: " + _FLOAT)
_RE_RES = re.compile(
    r"^\w+:\s+Solving for (\S+), Initial residual = "
    + _FLOAT
    + r", Final residual = "
    + _FLOAT
    + r", No Iterations (\d+)"
)
_RE_CONT = re.compile(r"^time step continuity errors : sum local = " + _FLOAT)
_RE_EXEC = re.compile(r"^ExecutionTime = " + _FLOAT + r" s")


def _isbad(x: float) -> bool:
    return not math.isfinite(x)


@dataclass
class Step:
    """What the log says about one time step."""

    time: float
    delta_t: float = math.nan
    courant: float = math.nan
    interface_courant: float = math.nan
    granular_courant: float = math.nan
    residuals: dict[str, float] = field(default_factory=dict)
    iterations: dict[str, int] = field(default_factory=dict)
    continuity: float = math.nan
    execution_time: float = math.nan


@dataclass
class Divergence:
    """Why and when a run diverged."""

    quantity: str
    time: float | None
    detail: str


class LogMonitor:
    """Parse siloFoam's log line by line; detect divergence.

    Parameters
    ----------
    max_courant, max_interface_courant, max_granular_courant
        The limits the run uses (from controlDict); 0 disables a check.
    """

    def __init__(
        self,
        max_courant: float,
        max_interface_courant: float,
        max_granular_courant: float = 0.0,
    ) -> None:
        self.limits = {
            "Courant number": max_courant,
            "interface Courant number": max_interface_courant,
            "granular Courant number": max_granular_courant,
        }
        self.steps: list[Step] = []
        self.divergence: Divergence | None = None
        self.fatal: list[str] = []
        self._in_fatal = False
        self._pending: dict[str, float] = {}
        self._max_dt = 0.0
        self.end_seen = False

    @property
    def current_time(self) -> float | None:
        """Latest simulated time reached."""
        return self.steps[-1].time if self.steps else None

    def _diverge(self, quantity: str, detail: str) -> None:
        if self.divergence is None:
            self.divergence = Divergence(quantity, self.current_time, detail)

    def _check_courant(self, name: str, value: float) -> None:
        limit = self.limits[name]
        if _isbad(value):
            self._diverge(name, f"{name} is {value}")
        elif limit > 0 and value > COURANT_BLOWUP * limit:
            self._diverge(name, f"{name} {value:.3g} > {COURANT_BLOWUP:g} x limit {limit:g}")

    def feed(self, line: str) -> None:
        """Consume one log line."""
        line = line.rstrip()
        if "FOAM FATAL" in line or "sigFpe::sigHandler" in line or "error::printStack" in line:
            self._in_fatal = True
        if self._in_fatal:
            self.fatal.append(line)
            return
        if line == "End":
            self.end_seen = True
            return
        m = _RE_CO.match(line)
        if m:
            self._pending["courant"] = float(m.group(2))
            self._check_courant("Courant number", float(m.group(2)))
            return
        m = _RE_ACO.match(line)
        if m:
            self._pending["interface_courant"] = float(m.group(2))
            self._check_courant("interface Courant number", float(m.group(2)))
            return
        m = _RE_GCO.match(line)
        if m:
            self._pending["granular_courant"] = float(m.group(1))
            self._check_courant("granular Courant number", float(m.group(1)))
            return
        m = _RE_DT.match(line)
        if m:
            dt = float(m.group(1))
            self._pending["delta_t"] = dt
            if _isbad(dt) or dt <= 0:
                self._diverge("deltaT", f"time step is {dt}")
            elif len(self.steps) > 20 and dt < DT_COLLAPSE * self._max_dt:
                self._diverge("deltaT", f"time step {dt:.3g} s collapsed from {self._max_dt:.3g} s")
            if len(self.steps) > 5:
                self._max_dt = max(self._max_dt, dt)
            return
        m = _RE_TIME.match(line)
        if m:
            step = Step(time=float(m.group(1)))
            for k, v in self._pending.items():
                setattr(step, k, v)
            self._pending = {}
            self.steps.append(step)
            return
        if not self.steps:
            return
        step = self.steps[-1]
        m = _RE_RES.match(line)
        if m:
            name, r0 = m.group(1), float(m.group(2))
            step.residuals.setdefault(name, r0)  # first solve of the step
            step.iterations[name] = step.iterations.get(name, 0) + int(m.group(4))
            if _isbad(r0) or _isbad(float(m.group(3))):
                self._diverge(f"{name} residual", f"{name} residual is {r0}")
            return
        m = _RE_CONT.match(line)
        if m:
            step.continuity = float(m.group(1))
            if _isbad(step.continuity):
                self._diverge("continuity error", f"continuity error is {step.continuity}")
            return
        m = _RE_EXEC.match(line)
        if m:
            step.execution_time = float(m.group(1))

    def write_table(self, path: Path) -> None:
        """Write one row per time step (CSV), replaced whole."""
        names = sorted({k for s in self.steps for k in s.residuals})
        tmp = path.with_suffix(path.suffix + ".tmp")
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(
                [
                    "time",
                    "delta_t",
                    "courant",
                    "interface_courant",
                    "granular_courant",
                    "continuity",
                    "execution_time",
                ]
                + [f"res_{n}" for n in names]
                + [f"iter_{n}" for n in names]
            )
            for s in self.steps:
                w.writerow(
                    [
                        s.time,
                        s.delta_t,
                        s.courant,
                        s.interface_courant,
                        s.granular_courant,
                        s.continuity,
                        s.execution_time,
                    ]
                    + [s.residuals.get(n, "") for n in names]
                    + [s.iterations.get(n, "") for n in names]
                )
        os.replace(tmp, path)


@dataclass
class RunResult:
    """Outcome of a solver run.

    Attributes
    ----------
    case
        The case directory.
    completed
        The solver reached its end time and printed ``End``.
    start_time, end_time
        Simulated times at start and at the end of this run [s].
    steps
        Time steps taken in this run.
    wall_seconds, cpu_seconds
        Wall and CPU time of the solver process.
    max_rss_mb
        Peak resident memory of the solver [MB] (None if unknown).
    n_procs
        MPI ranks it ran on (1: serial).
    """

    case: Path
    completed: bool
    start_time: float
    end_time: float
    steps: int
    wall_seconds: float
    cpu_seconds: float
    max_rss_mb: float | None
    n_procs: int = 1

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        d = dict(self.__dict__)
        d["case"] = str(self.case)
        return d


#: Fields a time directory must hold, whole, to restart from it
RESTART_FIELDS = ("U", "p_rgh", "alpha.granular", "phi", "uniform/time")
_FOOTER = b"// ************************************************************************* //"


def _written_whole(path: Path) -> bool:
    """Whether an OpenFOAM file ends with its footer (a killed write does not)."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            fh.seek(max(0, size - 200))
            return _FOOTER in fh.read()
    except OSError:
        return False


def _time_dirs(root: Path) -> list[Path]:
    out = []
    for p in Path(root).iterdir():
        try:
            float(p.name)
        except ValueError:
            continue
        if p.is_dir():
            out.append(p)
    return sorted(out, key=lambda p: float(p.name))


def _complete(tdir: Path) -> bool:
    if float(tdir.name) == 0.0:
        return (tdir / "U").exists() and (tdir / "alpha.granular").exists()
    # the restart fields, and every other file written whole: the solver
    # also reads some of the others (alphaPhi0 is READ_IF_PRESENT), and a
    # truncated one stops the restart with a fatal IO error
    if not all((tdir / f).is_file() for f in RESTART_FIELDS):
        return False
    return all(_written_whole(p) for p in tdir.rglob("*") if p.is_file())


def _complete_names(root: Path) -> set[str]:
    return {p.name for p in _time_dirs(root) if _complete(p)}


def _complete_on_every_rank(case: Path) -> set[str]:
    """Return the times complete in every processor directory (none: not decomposed)."""
    procs = processor_dirs(case)
    return set.intersection(*[_complete_names(pd) for pd in procs]) if procs else set()


def processor_dirs(case: Path) -> list[Path]:
    """Return the ``processorN`` directories of a decomposed case, in rank order."""
    procs = [p for p in Path(case).glob("processor*") if p.name[9:].isdigit()]
    return sorted(procs, key=lambda p: int(p.name[9:]))


def time_directories(case: Path) -> list[str]:
    """Complete time directories of a case, oldest first.

    A time directory is complete when the fields a restart needs are there
    and written whole. In a decomposed case a time counts when every
    processor holds it complete, or when it was reconstructed.
    """
    names = _complete_names(case) | _complete_on_every_rank(case)
    return sorted(names, key=float)


def prune_incomplete_times(case: Path) -> list[str]:
    """Remove time directories after the last complete one (a killed write).

    Returns the names removed. The solver restarts from the latest time
    directory it finds (``startFrom latestTime``), so a half-written one must
    not be left for it.
    """
    procs = processor_dirs(case)
    keep_root, keep_procs = _complete_names(case), _complete_on_every_rank(case)
    removed = []
    for root, keep in [(Path(case), keep_root), *[(pd, keep_procs) for pd in procs]]:
        for p in _time_dirs(root):
            if float(p.name) > 0 and p.name not in keep:
                shutil.rmtree(p)
                removed.append(str(p.relative_to(case)))
    return removed


def _control_value(case: Path, key: str, default: float = 0.0) -> float:
    text = (case / "system" / "controlDict").read_text()
    m = re.search(r"^\s*" + re.escape(key) + r"\s+([^;]+);", text, re.M)
    return float(m.group(1)) if m else default


ProgressCallback = Callable[[LogMonitor, float], None]


def _latest_root_time(case: Path) -> float:
    return max((float(n) for n in _complete_names(case)), default=0.0)


def _latest_processor_time(case: Path) -> float:
    return max((float(n) for n in _complete_on_every_rank(case)), default=-1.0)


def _all_local(hostfile: Path | None) -> bool:
    """Whether every host of an Open MPI hostfile is this machine (no hostfile: yes)."""
    if hostfile is None:
        return True
    import socket

    local = {"localhost", "127.0.0.1", socket.gethostname(), socket.getfqdn()}
    for line in Path(hostfile).read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if words and words[0] not in local:
            return False
    return True


def reconstruct(case: Path, of: OpenFOAM, *, latest_only: bool = False) -> None:
    """Merge the processor directories back into time directories (reconstructPar)."""
    from foamsilo.foam import run_utility

    args = ["-latestTime"] if latest_only else ["-newTimes"]
    run_utility(of, case, "reconstructPar", *args, log_name="reconstructPar")


def prepare_decomposition(case: Path, of: OpenFOAM, n_procs: int) -> None:
    """Make ``case`` ready to run on ``n_procs`` ranks (or serially for 1).

    A decomposed case with the right number of ranks is left as it is (a
    resumed parallel run goes on from the processors' latest time). Anything
    else is first reconstructed up to its latest time, so that a run can be
    resumed with another number of ranks, then decomposed afresh.
    """
    from foamsilo.foam import run_utility

    procs = processor_dirs(case)
    if procs and len(procs) == n_procs:
        return
    if procs:
        if _latest_processor_time(case) > _latest_root_time(case):
            reconstruct(case, of, latest_only=True)
        for pd in procs:
            shutil.rmtree(pd)
    if n_procs == 1:
        return
    from foamsilo.case import SCENE_FILE, decompose_dict
    from foamsilo.scene import load_scene_file

    # horizontal slices of equal cell counts (templates/system/decomposeParDict.j2)
    scene = load_scene_file(case / SCENE_FILE)
    (case / "system" / "decomposeParDict").write_text(decompose_dict(scene, n_procs))
    run_utility(of, case, "decomposePar", "-force", "-latestTime", log_name="decomposePar")


def run_solver(
    case: Path,
    of: OpenFOAM,
    solver: SolverBuild,
    *,
    progress: ProgressCallback | None = None,
    max_wall_seconds: float | None = None,
    n_procs: int = 1,
    hostfile: Path | None = None,
) -> RunResult:
    """Run siloFoam in ``case`` through PyFoam, serially or with MPI.

    The run starts from the latest complete time directory (a fresh case:
    0); time directories a killed run left half-written are removed first.
    With ``n_procs > 1`` the case is decomposed (scotch) unless it already
    is for that many ranks, and the solver runs under mpirun through
    PyFoam's parallel machinery; the processor directories are kept (see
    :func:`reconstruct`).

    Parameters
    ----------
    case
        A case written by :func:`foamsilo.case.create_case`.
    of
        OpenFOAM to run with.
    solver
        The solver build.
    progress
        Called after each time step with the monitor and the end time.
    max_wall_seconds
        Stop the solver after this much wall time (a run that crawls on with
        a shrinking step must not hang a sweep).
    n_procs
        MPI ranks (1: serial, no mpirun).
    hostfile
        Open MPI hostfile (one host name per line, one line per slot) for
        runs across machines; the case directory must be visible at the same
        path on every host.

    Raises
    ------
    DivergenceError
        The run diverged and was stopped; the case is kept.
    RunTimeLimitError
        The wall-time limit was reached; the case is kept.
    FoamError
        The solver failed (fatal error) for another reason.
    """
    from PyFoam.Execution.BasicRunner import BasicRunner

    case = Path(case).resolve()
    if n_procs < 1:
        raise FoamsiloError(f"n_procs = {n_procs}: must be >= 1")
    if hostfile is not None and not Path(hostfile).is_file():
        raise FoamsiloError(f"hostfile {hostfile}: no such file")
    prune_incomplete_times(case)
    prepare_decomposition(case, of, n_procs)
    end_time = _control_value(case, "endTime")
    monitor = LogMonitor(
        _control_value(case, "maxCo"),
        _control_value(case, "maxAlphaCo"),
        _control_value(case, "maxGranularCo"),
    )
    start_time = max(_latest_root_time(case), _latest_processor_time(case), 0.0)
    log = open(case / LOG_NAME, "a" if start_time > 0 else "w")  # noqa: SIM115

    from PyFoam.RunDictionary.SolutionDirectory import SolutionDirectory

    started = time.perf_counter()
    timed_out = []

    class _Runner(BasicRunner):
        def getSolutionDirectory(self, archive: str | None = None) -> SolutionDirectory:
            # the case already has case.foam; no second ParaView stub
            return SolutionDirectory(self.dir, archive=archive, paraviewLink=False, parallel=True)

        def __init__(self, **kw: Any) -> None:
            super().__init__(**kw)
            # 'exec' makes the solver (or mpirun) the process PyFoam signals,
            # not the shell that starts it (killing the shell leaves it running)
            if not self.run.cmdline.startswith("exec "):
                self.run.cmdline = "exec " + self.run.cmdline

        def lineHandle(self, line: str) -> None:
            log.write(line + "\n")
            n_before = len(monitor.steps)
            monitor.feed(line)
            if monitor.divergence is not None or (monitor.fatal and len(monitor.fatal) > 40):
                # serial: SIGKILL, stop now; mpirun: SIGINT, which it passes
                # on to the ranks (a killed mpirun leaves them running)
                self.run.interrupt(pass_int=parallel)
                return
            if max_wall_seconds and time.perf_counter() - started > max_wall_seconds:
                if not timed_out:
                    timed_out.append(monitor.current_time)
                    self.run.interrupt(pass_int=parallel)
                return
            if progress is not None and len(monitor.steps) != n_before:
                progress(monitor, end_time)

    parallel = n_procs > 1
    saved = dict(os.environ)
    env = of.runtime_env()  # before the clear: it starts from os.environ
    os.environ.clear()
    os.environ.update(env)
    if parallel and hostfile is None and n_procs > (os.cpu_count() or 1):
        os.environ.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    if parallel and _all_local(hostfile):
        # Open MPI refuses to start when it finds no usable remote shell, even
        # if every rank is local and it would never call one (other hosts do
        # need ssh: then the user's setting stands)
        os.environ.setdefault("OMPI_MCA_plm_rsh_agent", shutil.which("false") or "/bin/false")
    usage0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    interrupted: list[float] = []
    old_handler = None
    try:
        # 'exec' makes the solver the process PyFoam signals (not a shell);
        # PyFoam's own messages go to stderr so that --json stdout stays clean
        lam = None
        if parallel:
            from PyFoam.Execution.ParallelExecution import LAMMachine

            lam = LAMMachine(machines=str(hostfile) if hostfile else None, nr=n_procs)
        runner = _Runner(
            argv=[shlex.quote(str(solver.executable)), "-case", shlex.quote(str(case))],
            silent=True,
            noLog=True,
            writeState=False,
            lam=lam,
        )

        # Ctrl-C: the solver (same process group) stops by itself; a SIGINT
        # sent to this process alone is passed on. Either way Python only
        # notes it, so that the run ends as an interruption the case can be
        # resumed from, not as a KeyboardInterrupt in the middle of PyFoam.
        def _on_sigint(signum: int, frame: Any) -> None:
            interrupted.append(time.time())
            with contextlib.suppress(OSError):
                os.kill(runner.run.threadPid, signal.SIGINT)

        if threading.current_thread() is threading.main_thread():
            old_handler = signal.signal(signal.SIGINT, _on_sigint)
        with contextlib.redirect_stdout(sys.stderr):
            data = runner.start()
            runner.run.join()  # the solver process is reaped: its rusage is final
    finally:
        if old_handler is not None:
            signal.signal(signal.SIGINT, old_handler)
        os.environ.clear()
        os.environ.update(saved)
        log.close()
    wall = time.perf_counter() - t0
    usage1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (usage1.ru_utime - usage0.ru_utime) + (usage1.ru_stime - usage0.ru_stime)
    monitor.write_table(case / STEP_TABLE)
    rss = data.get("usedMemory")

    interrupted_run = interrupted or data.get("keyboardInterrupt")
    if interrupted_run and monitor.divergence is None and not timed_out:
        good = time_directories(case)
        raise RunInterruptedError(monitor.current_time, good[-1] if good else None, case)
    if timed_out and monitor.divergence is None:
        raise RunTimeLimitError(float(max_wall_seconds or 0), timed_out[0], end_time, case)
    if monitor.divergence is not None:
        d = monitor.divergence
        good = time_directories(case)
        raise DivergenceError(d.quantity, d.time, d.detail, good[-1] if good else None, case)
    if monitor.fatal or not monitor.end_seen:
        text = "\n".join(monitor.fatal) or "the solver ended without 'End'"
        raise FoamError(f"{solver.executable.name} -case {case}", 1, text, case)
    return RunResult(
        case=case,
        completed=True,
        start_time=start_time,
        end_time=monitor.current_time or start_time,
        steps=len(monitor.steps),
        wall_seconds=wall,
        cpu_seconds=cpu,
        max_rss_mb=float(rss) if rss else None,
        n_procs=n_procs,
    )


def ensure_not_running(case: Path) -> None:
    """Refuse to start a second solver in a case that another one is using."""
    lock = Path(case) / ".foamsilo.lock"
    if lock.exists():
        try:
            pid = int(lock.read_text().strip())
            os.kill(pid, 0)
        except (ValueError, ProcessLookupError, PermissionError):
            lock.unlink(missing_ok=True)
            return
        raise FoamsiloError(f"{case} is being run by process {pid}")
