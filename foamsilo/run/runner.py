"""Run siloFoam on a case through PyFoam, serially or with MPI, with a divergence stop.

The solver runs under a :class:`PyFoam.Execution.BasicRunner.BasicRunner`
subclass; every log line goes to a :class:`~foamsilo.run.monitor.LogMonitor`,
which keeps one row per time step and decides whether the run diverged. A
diverged run is stopped at once and reported with
:class:`~foamsilo.errors.DivergenceError` (quantity, time, last good time
directory); the case is kept for inspection.

The command line (``siloFoam -case C`` or ``mpirun --n N ... siloFoam -case C
-parallel``) is built here and handed to PyFoam with its environment written
into it (:func:`foamsilo.process.shell_line`): ``os.environ`` is never edited,
and the solver dies with the foamsilo process that started it.
"""

from __future__ import annotations

import contextlib
import math
import os
import resource
import shutil
import signal
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from foamsilo.case import (
    SCENE_FILE,
    decompose_dict,
    processor_dirs,
    prune_incomplete_times,
    prune_times_past_step_rows,
)
from foamsilo.case.times import (
    latest_processor_time,
    latest_root_time,
    resumable_times,
    set_aside_nonfinite_times,
    time_directories,
)
from foamsilo.errors import (
    DivergenceError,
    FoamError,
    RunInterruptedError,
    RunTimeLimitError,
    UsageError,
)
from foamsilo.foam import decompose_par, dict_value, reconstruct_par
from foamsilo.process import cpu_model, shell_line
from foamsilo.run.monitor import LOG_NAME, STEP_TABLE, LogMonitor
from foamsilo.scene import load_scene_file
from foamsilo.solver import SolverBuild
from foamsilo.toolchain import OpenFOAM

ProgressCallback = Callable[[LogMonitor, float], None]


@dataclass
class StepRelease:
    """Step settings to put back once the run is past ``time``.

    A recovered run needs its smaller step or its extra iterations through
    the trouble it met, not to its end: the step cap (``controlDict``
    ``maxDeltaT``) and the outer iterations (``fvSolution`` PIMPLE
    ``nOuterCorrectors``) are written back while the solver runs (the
    recovery made the case modifiable at run time), and the solver reads them
    at its next step. ``released_at`` is the simulated time they were put back.
    """

    time: float
    max_delta_t: float
    outer_correctors: int | None = None
    released_at: float | None = None


def _stop_pyfoam_timers(thread: Any) -> None:
    """Cancel the PyFoam thread's re-arming timers for good.

    ``FoamThread`` polls for a stop file and the memory every 5 s with
    ``threading.Timer`` callbacks that start their successor; its own cancel
    at the end of the run misses a callback that is running at that moment,
    which then re-arms forever and, not being a daemon, keeps the interpreter
    from exiting (seen: pytest hung after its summary). Cancel, wait for a
    running callback, and cancel what it started.
    """
    for name in ("timer", "timer2"):
        for _ in range(5):
            t = getattr(thread, name, None)
            if t is None:
                break
            t.cancel()
            try:
                t.join(timeout=2.0)
            except RuntimeError:  # made by a callback, not started yet
                time.sleep(0.05)
                continue
            if getattr(thread, name, None) is t:
                break


@dataclass
class RunResult:
    """Outcome of a solver run.

    Attributes
    ----------
    case
        The case directory.
    completed
        The solver reached its end time (or ended the run, the silo emptied)
        and printed ``End``.
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
    emptied_at
        Simulated time at which the solver ended the run because the silo had
        emptied (``run.stop_when_empty``), before its end time; None otherwise.
    step_retakes
        The steps the solver took again with half the step because their outer
        iterations diverged (``run.max_step_retakes``): each one's start
        ``time``, ``detail``, failed ``delta_t`` and ``retake_delta_t``.
    share_retakes
        The steps the solver took again at the same step with half the
        stress's divergence share because their outer iterations grew or the
        last moved a grain too far (``numerics.outer_growth_limit``,
        ``numerics.outer_change_limit``): each one's start ``time``, ``growth``
        and ``change``, and ``failed`` (why) where that step failed and was taken as
        the whole share first took it.
    cpu
        The processor the solver ran on (its model name; ``""`` if unknown):
        what the CPU time was measured on.
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
    emptied_at: float | None = None
    step_retakes: list[dict[str, Any]] = field(default_factory=list)
    share_retakes: list[dict[str, float | str]] = field(default_factory=list)
    cpu: str = ""

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form (the ``run`` section of the summary)."""
        d = asdict(self)
        d["case"] = str(self.case)
        return d


def pyfoam_log_directory() -> Path:
    """Make PyFoam's log directory, safely against other runs starting at the same moment.

    PyFoam makes it on first use by a check and then ``os.makedirs``: two runs started
    together on a fresh machine race there, and the loser stops with a FileExistsError.

    Returns
    -------
    Path
        The directory (``/var/log/pyFoam`` for root, ``~/.pyFoam/log`` otherwise).
    """
    from PyFoam.Infrastructure.Hardcoded import logDirectory

    path = Path(logDirectory())
    path.mkdir(parents=True, exist_ok=True)
    return path


def modifiable_while_running(case: Path) -> None:
    """Let the solver read ``system/`` dictionaries changed while it runs.

    ``runTimeModifiable`` on, with no modification skew: OpenFOAM otherwise
    ignores a change made within 10 s of the last (for clocks skewed across
    NFS); the runner writes on the machine the solver reads.
    """
    from foamsilo.foam import edit_dict

    with edit_dict(case / "system" / "controlDict") as cd:
        cd["runTimeModifiable"] = True
        cd["OptimisationSwitches"] = {"fileModificationSkew": 0}


def outer_iterations(n: int) -> str:
    """Return ``"n outer iteration(s)"``, as the log, the terminal and the report say it."""
    return f"{n} outer iteration{'s' if n != 1 else ''}"


def _release_step_cap(control: Path, release: StepRelease, now: float, log: Any) -> None:
    from foamsilo.foam import edit_dict

    with edit_dict(control) as cd:
        cd["maxDeltaT"] = release.max_delta_t
    said = f"step cap put back to {release.max_delta_t:.3g} s"
    if release.outer_correctors is not None:
        with edit_dict(control.parent / "fvSolution") as sd:
            sd["PIMPLE"]["nOuterCorrectors"] = release.outer_correctors
        said += f", {outer_iterations(release.outer_correctors)} per step"
    release.released_at = now
    log.write(f"foamsilo: past t = {release.time:.6g} s: {said} at t = {now:.6g} s\n")


def _all_local(hostfile: Path | None) -> bool:
    """Whether every host of an Open MPI hostfile is this machine (no hostfile: yes)."""
    if hostfile is None:
        return True
    local = {"localhost", "127.0.0.1", socket.gethostname(), socket.getfqdn()}
    for line in Path(hostfile).read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if words and words[0] not in local:
            return False
    return True


def prepare_decomposition(case: Path, of: OpenFOAM, n_procs: int) -> None:
    """Make ``case`` ready to run on ``n_procs`` ranks (or serially for 1).

    A decomposed case with the right number of ranks is left as it is (a
    resumed parallel run goes on from the processors' latest time). Anything
    else is first reconstructed up to its latest time, so that a run can be
    resumed with another number of ranks, then decomposed afresh.
    """
    procs = processor_dirs(case)
    if procs and len(procs) == n_procs:
        return
    if procs:
        if latest_processor_time(case) > latest_root_time(case):
            reconstruct_par(of, case, latest_only=True)
        for pd in procs:
            shutil.rmtree(pd)
    if n_procs == 1:
        return
    # horizontal slices of equal cell counts (templates/system/decomposeParDict.j2)
    scene = load_scene_file(case / SCENE_FILE)
    (case / "system" / "decomposeParDict").write_text(decompose_dict(scene, n_procs))
    decompose_par(of, case)


def mpi_environment(of: OpenFOAM, n_procs: int, hostfile: Path | None) -> dict[str, str]:
    """Return the solver's environment: OpenFOAM's, plus what Open MPI needs on this machine."""
    env = of.runtime_env()
    if n_procs > 1:
        if hostfile is None and n_procs > (os.cpu_count() or 1):
            env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
        if _all_local(hostfile):
            # Open MPI refuses to start when it finds no usable remote shell, even
            # if every rank is local and it would never call one (other hosts do
            # need ssh: then the user's setting stands)
            env.setdefault("OMPI_MCA_plm_rsh_agent", shutil.which("false") or "/bin/false")
    return env


def solver_argv(executable: Path, case: Path, n_procs: int, hostfile: Path | None) -> list[str]:
    """Return the solver's command line: serial, or under mpirun."""
    argv = [str(executable), "-case", str(case)]
    if n_procs == 1:
        return argv
    mpirun = shutil.which("mpirun") or "mpirun"
    launcher = [mpirun, "--n", str(n_procs)]
    if hostfile is not None:
        launcher += ["--hostfile", str(hostfile)]
    return [*launcher, *argv, "-parallel"]


def run_solver(
    case: Path,
    of: OpenFOAM,
    solver: SolverBuild,
    *,
    progress: ProgressCallback | None = None,
    max_wall_seconds: float | None = None,
    n_procs: int = 1,
    hostfile: Path | None = None,
    append_log: bool = False,
    step_release: StepRelease | None = None,
) -> RunResult:
    """Run siloFoam in ``case`` through PyFoam, serially or with MPI.

    The run starts from the latest complete time directory (a fresh case:
    0); time directories a killed run left half-written are removed first.
    With ``n_procs > 1`` the case is decomposed unless it already is for that
    many ranks, and the solver runs under mpirun; the processor directories
    are kept (see :func:`foamsilo.foam.reconstruct_par`).

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
    append_log
        Append to the solver's log even when the run starts at t = 0 (a
        retry: the log keeps what went before).
    step_release
        A step cap to write back into ``controlDict`` once the simulated time
        reaches ``step_release.time`` (its ``released_at`` is set when done).

    Raises
    ------
    DivergenceError
        The run diverged and was stopped; the case is kept.
    RunTimeLimitError
        The wall-time limit was reached; the case is kept.
    RunInterruptedError
        Ctrl-C (SIGINT); the case is kept for ``--resume``.
    FoamError
        The solver failed (fatal error) for another reason.
    """
    from PyFoam.Execution.BasicRunner import BasicRunner
    from PyFoam.RunDictionary.SolutionDirectory import SolutionDirectory

    pyfoam_log_directory()
    case = Path(case).resolve()
    if n_procs < 1:
        raise UsageError("--np", f"{n_procs} ranks; allowed: an integer >= 1")
    if hostfile is not None and not Path(hostfile).is_file():
        raise UsageError("--hostfile", f"{hostfile}: no such file")
    prune_incomplete_times(case)
    # a time written just before a kill, its step's function-object rows not yet
    prune_times_past_step_rows(case)
    # a restart from NaN fields dies in a floating-point trap naming no file
    set_aside_nonfinite_times(case)
    prepare_decomposition(case, of, n_procs)
    control = case / "system" / "controlDict"
    end_time = float(dict_value(control, "endTime"))
    monitor = LogMonitor(
        float(dict_value(control, "maxCo", 0.0)),
        float(dict_value(control, "maxAlphaCo", 0.0)),
        float(dict_value(control, "maxGranularCo", 0.0)),
    )
    start_time = max(latest_root_time(case), latest_processor_time(case), 0.0)
    parallel = n_procs > 1
    line = shell_line(
        solver_argv(solver.executable, case, n_procs, hostfile),
        mpi_environment(of, n_procs, hostfile),
    )
    log = open(case / LOG_NAME, "a" if start_time > 0 or append_log else "w")  # noqa: SIM115
    started = time.perf_counter()
    timed_out: list[float | None] = []

    class _Runner(BasicRunner):
        def getSolutionDirectory(self, archive: str | None = None) -> SolutionDirectory:
            # the case already has case.foam; no second ParaView stub
            return SolutionDirectory(self.dir, archive=archive, paraviewLink=False, parallel=True)

        def __init__(self, **kw: Any) -> None:
            super().__init__(**kw)
            self.run.cmdline = line  # environment and launcher in the line itself

        def lineHandle(self, text: str) -> None:
            log.write(text + "\n")
            n_before = len(monitor.steps)
            monitor.feed(text)
            if monitor.divergence is not None or (monitor.fatal and len(monitor.fatal) > 40):
                # serial: SIGKILL, stop now; mpirun: SIGINT, which it passes
                # on to the ranks (a killed mpirun leaves them running)
                self.run.interrupt(pass_int=parallel)
                return
            now = monitor.current_time
            if step_release and step_release.released_at is None and now is not None \
                    and now >= step_release.time:  # fmt: skip
                _release_step_cap(control, step_release, now, log)
            if max_wall_seconds and time.perf_counter() - started > max_wall_seconds:
                if not timed_out:
                    timed_out.append(monitor.current_time)
                    self.run.interrupt(pass_int=parallel)
                return
            if progress is not None and len(monitor.steps) != n_before:
                progress(monitor, end_time)

    usage0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    interrupted: list[float] = []
    old_handler = None
    try:
        runner = _Runner(
            argv=[str(solver.executable), "-case", str(case)],
            silent=True,
            noLog=True,
            writeState=False,
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
        # PyFoam's own messages (the solver lines it read after a stop, "Killing
        # PID") go to the solver's log: not onto the user's terminal, and
        # --json stdout stays clean
        with contextlib.redirect_stdout(log):
            data = runner.start()
            runner.run.join()  # the solver process is reaped: its rusage is final
            _stop_pyfoam_timers(runner.run)
    finally:
        if old_handler is not None:
            signal.signal(signal.SIGINT, old_handler)
        log.close()
    wall = time.perf_counter() - t0
    usage1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (usage1.ru_utime - usage0.ru_utime) + (usage1.ru_stime - usage0.ru_stime)
    monitor.write_table(case / STEP_TABLE)
    rss = data.get("usedMemory")

    interrupted_run = interrupted or data.get("keyboardInterrupt")
    if interrupted_run and monitor.divergence is None and not timed_out:
        # the time --resume will go on from (a time written just before the
        # signal may have no row of its step yet)
        good = resumable_times(case)
        raise RunInterruptedError(monitor.current_time, good[-1] if good else None, case)
    if timed_out and monitor.divergence is None:
        raise RunTimeLimitError(float(max_wall_seconds or 0), timed_out[0], end_time, case)
    if monitor.divergence is not None:
        d = monitor.divergence
        good = time_directories(case)
        # the step before the one that blew up (its own step may be NaN); for
        # a collapsed step, the largest step of the run: the solver's retakes
        # halve the step of each failed step, and a run of them in consecutive
        # steps ends far below the step the run was taking (a recovery capping
        # at half of that never got through its discharge: docs/solver.md)
        steps = [s.delta_t for s in monitor.steps[-3:] if math.isfinite(s.delta_t)]
        dt = min(steps) if steps else None
        if d.quantity == "deltaT" and monitor.largest_step > 0:
            dt = monitor.largest_step
        # the solver's retakes spent within its window: the largest step that
        # failed there, the one the run was taking when its trouble began
        # (the steps since were halved by the retakes). The window ends where
        # the solver's does, at the start of the step it stopped in.
        window = float(dict_value(control, "retakeWindow", 0.0))
        end = monitor.diverged_step_start if monitor.diverged_step_start is not None else d.time
        failed = [
            float(r["delta_t"])
            for r in monitor.retakes
            if end is None or float(r["time"]) > end - window
        ]
        if failed and d.quantity in ("volume fraction", "Courant number"):
            dt = max(failed)
        raise DivergenceError(d.quantity, d.time, d.detail, good[-1] if good else None, case, dt)
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
        emptied_at=monitor.emptied_at,
        step_retakes=list(monitor.retakes),
        share_retakes=list(monitor.share_retakes),
        cpu=cpu_model(),
    )
