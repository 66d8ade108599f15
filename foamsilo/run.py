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
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from foamsilo.errors import DivergenceError, FoamError, FoamsiloError, RunTimeLimitError
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
    """

    case: Path
    completed: bool
    start_time: float
    end_time: float
    steps: int
    wall_seconds: float
    cpu_seconds: float
    max_rss_mb: float | None

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        d = dict(self.__dict__)
        d["case"] = str(self.case)
        return d


def time_directories(case: Path) -> list[str]:
    """Time directories of a case with a complete U field, oldest first."""
    out = []
    for p in Path(case).iterdir():
        try:
            float(p.name)
        except ValueError:
            continue
        if p.is_dir() and (p / "U").exists() and (p / "alpha.granular").exists():
            out.append(p.name)
    return sorted(out, key=float)


def _control_value(case: Path, key: str, default: float = 0.0) -> float:
    text = (case / "system" / "controlDict").read_text()
    m = re.search(r"^\s*" + re.escape(key) + r"\s+([^;]+);", text, re.M)
    return float(m.group(1)) if m else default


ProgressCallback = Callable[[LogMonitor, float], None]


def run_solver(
    case: Path,
    of: OpenFOAM,
    solver: SolverBuild,
    *,
    progress: ProgressCallback | None = None,
    max_wall_seconds: float | None = None,
) -> RunResult:
    """Run siloFoam serially in ``case`` through PyFoam.

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
    end_time = _control_value(case, "endTime")
    monitor = LogMonitor(
        _control_value(case, "maxCo"),
        _control_value(case, "maxAlphaCo"),
        _control_value(case, "maxGranularCo"),
    )
    times = time_directories(case)
    start_time = float(times[-1]) if times else 0.0
    log = open(case / LOG_NAME, "a" if start_time > 0 else "w")  # noqa: SIM115

    from PyFoam.RunDictionary.SolutionDirectory import SolutionDirectory

    started = time.perf_counter()
    timed_out = []

    class _Runner(BasicRunner):
        def getSolutionDirectory(self, archive: str | None = None) -> SolutionDirectory:
            # the case already has case.foam; no second ParaView stub
            return SolutionDirectory(self.dir, archive=archive, paraviewLink=False, parallel=True)

        def lineHandle(self, line: str) -> None:
            log.write(line + "\n")
            n_before = len(monitor.steps)
            monitor.feed(line)
            if monitor.divergence is not None or (monitor.fatal and len(monitor.fatal) > 40):
                self.run.interrupt(pass_int=False)  # SIGKILL: stop now, keep the case
                return
            if max_wall_seconds and time.perf_counter() - started > max_wall_seconds:
                if not timed_out:
                    timed_out.append(monitor.current_time)
                    self.run.interrupt(pass_int=False)
                return
            if progress is not None and len(monitor.steps) != n_before:
                progress(monitor, end_time)

    saved = dict(os.environ)
    os.environ.clear()
    os.environ.update(of.runtime_env())
    usage0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        # 'exec' makes the solver the process PyFoam signals (not a shell);
        # PyFoam's own messages go to stderr so that --json stdout stays clean
        runner = _Runner(
            argv=["exec", shlex.quote(str(solver.executable)), "-case", shlex.quote(str(case))],
            silent=True,
            noLog=True,
            writeState=False,
        )
        with contextlib.redirect_stdout(sys.stderr):
            data = runner.start()
            runner.run.join()  # the solver process is reaped: its rusage is final
    finally:
        os.environ.clear()
        os.environ.update(saved)
        log.close()
    wall = time.perf_counter() - t0
    usage1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (usage1.ru_utime - usage0.ru_utime) + (usage1.ru_stime - usage0.ru_stime)
    monitor.write_table(case / STEP_TABLE)
    rss = data.get("usedMemory")

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
