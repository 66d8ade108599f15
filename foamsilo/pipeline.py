"""The one pipeline: prepare (scene -> case), run (siloFoam), reduce (summary and report).

Every command, study and test that makes a case, runs it or reduces it goes
through here:

* :func:`prepare` turns a :class:`CaseSpec` into a case directory that can
  run: it writes a new case, reuses one that holds the same scene, replaces
  one on request, and rebuilds a lost mesh from the case's own scene;
* :func:`run` runs the solver on it under the case's lock, after checking
  the case's state (:mod:`foamsilo.case.lifecycle`), and records the outcome
  in ``run.json`` (finished, interrupted, diverged, failed, time-limit);
* :func:`reduce` reduces it (:mod:`foamsilo.post`), sets it on its analytic
  law (:mod:`foamsilo.compare`), writes ``summary.json`` and the report;
* :func:`run_case` is the three in a row, and :func:`run_many` runs many
  specs, each in its own worker process, under a CPU budget: resumable (a
  finished case is only reduced again, an interrupted one resumed), and a
  killed driver takes its workers and their solvers with it.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

from foamsilo.case import (
    RUN_RECORD,
    SCENE_FILE,
    CaseLock,
    CaseState,
    create_case,
    inspect,
    read_metadata,
    rebuild_mesh,
    require,
    reset_results,
    write_whole,
)
from foamsilo.compare import COMPARE_MD, RunPoint, compare_runs, references
from foamsilo.errors import (
    CaseStateError,
    DivergenceError,
    FoamError,
    FoamsiloError,
    InputError,
    RunInterruptedError,
    RunTimeLimitError,
    UsageError,
)
from foamsilo.foam import reconstruct_par
from foamsilo.jsonio import dumps, jsonable
from foamsilo.mesh import o_grid_floored
from foamsilo.mesh.layout import MIN_QUADRANT_CELLS
from foamsilo.post import reduce_case
from foamsilo.post.grid import GRID_RATIO, coarser_cells, companion_overrides, write_grid_file
from foamsilo.post.steady import START
from foamsilo.process import tied_to_parent
from foamsilo.report import case_report
from foamsilo.run import ProgressCallback, RunResult, StepRelease, outer_iterations, run_solver
from foamsilo.scene import (
    CELLS_ACROSS_MAX,
    Scene,
    format_override,
    is_scene_file,
    load_scene,
    load_scene_file,
    scene_digest,
)
from foamsilo.solver import ensure_solver
from foamsilo.summary import RunSummary, write_summary
from foamsilo.toolchain import OpenFOAM, find_openfoam

Say = Callable[[str], None]


def _quiet(_: str) -> None:
    pass


@dataclass(frozen=True)
class CaseSpec:
    """One case to prepare, run and reduce.

    Attributes
    ----------
    case_dir
        The case directory.
    scene
        Preset name or scene file; None: the case directory's own scene.
    overrides
        ``section.key=value`` changes to the scene.
    n_procs
        MPI ranks (None: the scene's ``run.n_procs``).
    hostfile
        Open MPI hostfile for runs across machines.
    resume
        Go on with an interrupted (or failed) run from its latest complete time.
    rerun
        Run again from t = 0 (the results of earlier runs are removed).
    overwrite
        Write the case afresh (only a foamsilo case is ever replaced).
    update
        Replace a case that holds another scene; reuse one that holds this one.
    reconstruct
        After a parallel run, merge the processor directories.
    max_wall_seconds
        Stop the solver after this much wall time.
    label
        A name for the case in tables and progress lines.
    """

    case_dir: Path
    scene: str | None = None
    overrides: tuple[str, ...] = ()
    n_procs: int | None = None
    hostfile: Path | None = None
    resume: bool = False
    rerun: bool = False
    overwrite: bool = False
    update: bool = False
    reconstruct: bool = False
    max_wall_seconds: float | None = None
    label: str = ""

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form (how a worker process receives it)."""
        out: dict[str, Any] = jsonable(asdict(self))
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CaseSpec:
        """Inverse of :meth:`as_dict`."""
        d = dict(data)
        d["case_dir"] = Path(d["case_dir"])
        d["overrides"] = tuple(d.get("overrides") or ())
        if d.get("hostfile"):
            d["hostfile"] = Path(d["hostfile"])
        return cls(**d)


# ----------------------------------------------------------------------------- prepare


def prepare(spec: CaseSpec, of: OpenFOAM, say: Say = _quiet) -> Path:
    """Make the case of ``spec`` ready to run; return its directory.

    Raises
    ------
    SceneError, UsageError
        Bad scene or path (nothing is written).
    CaseStateError
        The directory holds another scene (without ``update`` or
        ``overwrite``), a running case, or files that are not a case.
    """
    from foamsilo.case import check_case_path

    case_dir = check_case_path(spec.case_dir)
    status = inspect(case_dir)
    if status.state is CaseState.RUNNING:
        raise CaseStateError(case_dir, "running", status.advice())
    if spec.scene is None:  # a case directory
        if status.state is CaseState.NEW:
            require(status, set())
        if spec.overrides:
            raise UsageError("--set", "cannot change an existing case; make a new one")
        if spec.overwrite:
            own = (case_dir / SCENE_FILE).read_text()
            say(f"writing {case_dir} afresh from its {SCENE_FILE}")
            create_case(
                load_scene_file(case_dir / SCENE_FILE), case_dir, of, overwrite=True, scene_text=own
            )
            return case_dir
        return _ensure_mesh(case_dir, of, say)
    scene = load_scene(spec.scene, list(spec.overrides))
    text = None
    if is_scene_file(spec.scene) and not spec.overrides:
        text = Path(spec.scene).read_text()
    if status.state is CaseState.NEW:
        say(f"writing case {case_dir}")
        create_case(scene, case_dir, of, scene_text=text)
        return case_dir
    same = read_metadata(case_dir).get("scene_digest") == scene_digest(scene)
    if spec.overwrite or (spec.update and not same):
        if not same:
            say(f"{case_dir} holds another version of the scene: replacing it")
        create_case(scene, case_dir, of, overwrite=True, scene_text=text)
        return case_dir
    if not same:
        raise CaseStateError(
            case_dir,
            status.state.value,
            f"{case_dir} holds a case of another scene ({status.state.value}): --update "
            "replaces it, --overwrite writes it afresh, or choose another -o",
        )
    say(f"using existing case {case_dir}")
    return _ensure_mesh(case_dir, of, say)


def _ensure_mesh(case_dir: Path, of: OpenFOAM, say: Say) -> Path:
    if inspect(case_dir).mesh_missing:
        say(f"{case_dir}: constant/polyMesh is missing: meshing again from {SCENE_FILE}")
        with CaseLock(case_dir):
            rebuild_mesh(case_dir, of)
    return case_dir


# ----------------------------------------------------------------------------- run


def _record(case_dir: Path, status: str, **data: Any) -> None:
    write_whole(case_dir / RUN_RECORD, dumps({"status": status, **data}) + "\n")


#: A recovery caps the step at this fraction of the step the run diverged with
RECOVERY_STEP_FACTOR = 0.5
#: A recovery from a start-up divergence (within the steady window's start-up,
#: ``foamsilo.post.steady.START`` discharge times) iterates each step this
#: many times (PIMPLE outer correctors) instead: the wedges' start-up blow-up
#: is the mu(I) viscosity's Picard iteration not converging, not too long a
#: step; later in a discharge the raised iterations blow up themselves
#: (docs/solver.md)
RECOVERY_OUTER_CORRECTORS = 8
#: The scene's own step cap is put back once the run is this many discharge
#: times sqrt(D/g) past the time it diverged at: the trouble met so far is a
#: start-up transient (docs/solver.md), over once the flow through the orifice
#: is established; kept to the end it made a recovered run several times dearer
RELEASE_AFTER = 1.0


def _recover(
    case_dir: Path,
    exc: DivergenceError,
    k: int,
    scene: Scene,
    say: Say,
    iterations_failed: bool = False,
    start_up_released: float | None = None,
) -> dict[str, Any]:
    """Set a diverged case back to its latest complete time with more care per step.

    The time directory of the step that blew up (if it was a write time) is
    removed. A run that diverged in its start-up, iterating each step more
    than once but fewer than ``RECOVERY_OUTER_CORRECTORS`` times, goes on
    with that many (``fvSolution`` PIMPLE ``nOuterCorrectors``); any other
    has its step capped at
    ``RECOVERY_STEP_FACTOR`` times the step it was taking (``maxDeltaT``),
    with the scene's own iterations back where the raised ones diverged
    (``iterations_failed``: they did so earlier in this run, and are not
    raised again). A restart that goes back to before ``start_up_released``
    (where an earlier recovery's start-up iterations were put back, the
    start-up passed) raises them again as well. A scene with one evaluation of
    the viscosity per step (planar) keeps it: made a Picard iteration, it
    diverges within the step at high viscosity contrast (D/d = 5, measured).
    ``controlDict`` is made modifiable at run time (with no modification
    skew) so that both can be put back while the solver runs. The recovery is
    said, appended to the solver's log, and returned for ``run.json``.
    """
    from foamsilo.case.times import remove_times_from
    from foamsilo.foam import dict_value, edit_dict
    from foamsilo.run import modifiable_while_running

    control = case_dir / "system" / "controlDict"
    solution = case_dir / "system" / "fvSolution"
    cap = float(dict_value(control, "maxDeltaT"))
    outer = int(dict_value(solution, "PIMPLE")["nOuterCorrectors"])
    step = exc.delta_t if exc.delta_t else cap
    # raised iterations that diverge, in whatever quantity, are no cure here
    blew_up = outer > scene.outer_correctors
    start_up = exc.time is None or exc.time <= START * scene.discharge_time_scale
    if 1 < outer < RECOVERY_OUTER_CORRECTORS and start_up and not iterations_failed:
        new_cap, new_outer = cap, RECOVERY_OUTER_CORRECTORS
        how = f"{outer_iterations(new_outer)} per step (was {outer})"
    else:
        new_cap, new_outer = RECOVERY_STEP_FACTOR * min(step, cap), outer
        if blew_up:
            new_outer = scene.outer_correctors  # the iterations themselves blew up
        how = f"the step capped at {new_cap:.3g} s" + (
            f" and {outer_iterations(new_outer)} per step (was {outer})"
            if new_outer != outer
            else ""
        )
    if exc.time is not None:
        remove_times_from(case_dir, exc.time)
    restart = inspect(case_dir).latest_time or "0"
    # a restart back into the start-up repeats the start-up's cure, if an
    # earlier recovery's raised iterations got the run through it
    again = (
        start_up_released is not None
        and float(restart) < start_up_released
        and new_outer < RECOVERY_OUTER_CORRECTORS
        and not (iterations_failed or blew_up)
    )
    if again:
        new_outer = RECOVERY_OUTER_CORRECTORS
        how += f" and {outer_iterations(new_outer)} per step (the start-up's)"
    with edit_dict(control) as cd:
        cd["maxDeltaT"] = new_cap
        cd["deltaT"] = min(float(cd["deltaT"]), new_cap)
    modifiable_while_running(case_dir)
    if new_outer != outer:
        with edit_dict(solution) as sd:
            sd["PIMPLE"]["nOuterCorrectors"] = new_outer
    line = (
        f"foamsilo: recovery {k} of {scene.run.max_recoveries}: {exc.quantity} diverged at "
        f"t = {exc.time} s with steps of {step:.3g} s; restarting from t = {restart} s with "
        f"{how}"
    )
    _say_and_log(case_dir, line, say)
    return {
        "quantity": exc.quantity,
        "time": exc.time,
        "detail": exc.detail,
        "delta_t": step,
        "restart_time": float(restart),
        "max_delta_t": new_cap,
        "outer_correctors": new_outer,
        "iterations_blew_up": blew_up,
        "start_up_again": again,
    }


def _say_and_log(case_dir: Path, line: str, say: Say) -> None:
    """Say a ``foamsilo:`` line and append it to the solver's log."""
    from foamsilo.run import LOG_NAME

    say(line.removeprefix("foamsilo: "))
    with open(case_dir / LOG_NAME, "a") as log:
        log.write(line + "\n")


def _plan_release(
    record: dict[str, Any], scene: Scene, released_before: bool, case_dir: Path, say: Say
) -> StepRelease | None:
    """Plan to put the scene's step cap and iterations back (None: kept to the end).

    A run that diverged again after they were put back keeps its recovery's
    settings to the end (with the start-up's iterations, where a restart back
    into the start-up raised them again: the thin lateral 3D silo failed
    within 0.01-0.04 s each time they went back to the scene's).
    """
    if released_before:
        line = (
            "foamsilo: it diverged after its step settings were put back: the recovery's "
            "are kept to the end"
        )
        _say_and_log(case_dir, line, say)
        record["release_time"] = None
        return None
    diverged_at = record["time"] if record["time"] is not None else record["restart_time"]
    at = diverged_at + RELEASE_AFTER * scene.discharge_time_scale
    record["release_time"] = at
    return StepRelease(at, scene.delta_t_max, scene.outer_correctors)


def _note_release(recoveries: list[dict[str, Any]], release: StepRelease | None) -> None:
    if recoveries and release is not None:
        recoveries[-1]["released_at"] = release.released_at


def _error_record(exc: BaseException) -> dict[str, Any]:
    out: dict[str, Any] = {"type": type(exc).__name__, "message": str(exc)}
    for k in ("quantity", "time", "last_good_time"):
        if hasattr(exc, k):
            out[k] = getattr(exc, k)
    return out


def run(
    case_dir: Path,
    of: OpenFOAM,
    *,
    n_procs: int | None = None,
    hostfile: Path | None = None,
    resume: bool = False,
    rerun: bool = False,
    reconstruct: bool = False,
    progress: ProgressCallback | None = None,
    max_wall_seconds: float | None = None,
    say: Say = _quiet,
) -> RunResult | None:
    """Run the solver on a case, if its state calls for it; None when it had finished.

    A finished case is not run again unless ``rerun``; an interrupted or
    failed one only with ``resume`` (from its latest complete time) or
    ``rerun`` (from t = 0); a running one never. The outcome is recorded in
    ``run.json``.

    Raises
    ------
    CaseStateError
        The state does not allow the run (the message says what would).
    DivergenceError, RunTimeLimitError, RunInterruptedError, FoamError
        From the solver run (recorded in ``run.json``, the case kept).
    """
    case_dir = Path(case_dir).resolve()
    status = inspect(case_dir)
    if status.state is CaseState.FINISHED and not rerun:
        say("run already finished; reducing it again")
        return None
    if status.state in (CaseState.INTERRUPTED, CaseState.FAILED) and not (resume or rerun):
        raise CaseStateError(case_dir, status.state.value, status.advice())
    require(
        status, {CaseState.PREPARED, CaseState.INTERRUPTED, CaseState.FAILED, CaseState.FINISHED}
    )
    scene = load_scene_file(case_dir / SCENE_FILE)
    ranks = n_procs or scene.run.n_procs
    if ranks < 1:
        raise UsageError("--np", f"{ranks} ranks; allowed: an integer >= 1")
    solver = ensure_solver(of=of, log=say)
    with CaseLock(case_dir) as lock:
        if lock.stale is not None:
            say(f"a stale lock of {lock.stale.describe()} was cleared: that process is gone")
        if rerun and status.state is not CaseState.PREPARED:
            reset_results(case_dir)
            say("starting again from t = 0")
        elif status.latest_time:
            say(f"resuming from t = {status.latest_time} s")
        _record(case_dir, "running", n_procs=ranks, pid=os.getpid())
        recoveries: list[dict[str, Any]] = []
        release: StepRelease | None = None
        released_before = False
        # what every attempt cost: a recovered run's figures cover its last attempt only
        wall0, cpu0 = time.perf_counter(), _children_cpu()

        def spent() -> dict[str, float]:
            return {
                "wall_seconds_all_attempts": time.perf_counter() - wall0,
                "cpu_seconds_all_attempts": _children_cpu() - cpu0,
            }

        while True:
            try:
                # the wall-time limit is the whole run's, recoveries included
                left = None
                if max_wall_seconds is not None:
                    left = max(max_wall_seconds - (time.perf_counter() - wall0), 1.0)
                result = run_solver(
                    case_dir, of, solver, progress=progress, n_procs=ranks, hostfile=hostfile,
                    max_wall_seconds=left, append_log=bool(recoveries), step_release=release,
                )  # fmt: skip
                _note_release(recoveries, release)
                break
            except DivergenceError as exc:
                _note_release(recoveries, release)
                released_before = released_before or bool(
                    release and release.released_at is not None
                )
                if len(recoveries) >= scene.run.max_recoveries:
                    exc.recoveries = recoveries
                    _record(case_dir, "diverged", n_procs=ranks, error=_error_record(exc),
                            recoveries=recoveries, **spent())  # fmt: skip
                    raise
                failed = any(r.get("iterations_blew_up") for r in recoveries)
                # where an earlier recovery's start-up iterations were put back
                start_up = [
                    r["release_time"]
                    for r in recoveries
                    if r["outer_correctors"] == RECOVERY_OUTER_CORRECTORS
                    and r.get("released_at") is not None
                ]
                recoveries.append(
                    _recover(case_dir, exc, len(recoveries) + 1, scene, say, failed,
                             start_up[0] if start_up else None)
                )  # fmt: skip
                recoveries[-1]["after_wall_seconds"] = time.perf_counter() - wall0
                release = _plan_release(recoveries[-1], scene, released_before, case_dir, say)
            except RunInterruptedError as exc:
                _record(case_dir, "interrupted", n_procs=ranks, error=_error_record(exc),
                        recoveries=recoveries, **spent())  # fmt: skip
                raise
            except RunTimeLimitError as exc:
                # said as the whole run's limit, not as what the last attempt had left
                whole = RunTimeLimitError(max_wall_seconds or exc.limit, exc.time, exc.end_time,
                                          case_dir, len(recoveries))  # fmt: skip
                _record(case_dir, "time-limit", n_procs=ranks, error=_error_record(whole),
                        recoveries=recoveries, **spent())  # fmt: skip
                raise whole from None
            except (FoamError, FoamsiloError) as exc:
                _record(case_dir, "failed", n_procs=ranks, error=_error_record(exc),
                        recoveries=recoveries, **spent())  # fmt: skip
                raise
            except KeyboardInterrupt:
                _record(case_dir, "interrupted", n_procs=ranks, recoveries=recoveries, **spent())
                raise
        if reconstruct and ranks > 1:
            say("reconstructing the processor directories")
            reconstruct_par(of, case_dir)
        # a run with no recovery: its one attempt's figures are the run's
        _record(case_dir, "finished", **result.as_dict(), recoveries=recoveries,
                **(spent() if recoveries else {}))  # fmt: skip
    return result


def _children_cpu() -> float:
    """CPU seconds (user + system) of this process's finished children."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


# ----------------------------------------------------------------------------- reduce


def reduce(case_dir: Path) -> RunSummary:
    """Reduce a case: ``summary.json``, ``compare.*``, the pictures and ``report.md``.

    Raises
    ------
    CaseStateError
        The case is running, or was never run.
    FoamsiloError
        Its output is missing or damaged.
    """
    case_dir = Path(case_dir).resolve()
    status = inspect(case_dir)
    if status.state is CaseState.RUNNING:
        raise CaseStateError(case_dir, "running", status.advice() + "; reduce it when it ends")
    if status.state is CaseState.NEW:
        require(status, set())
    red = reduce_case(case_dir)
    record = status.last_run
    run_info = {k: v for k, v in record.items() if k not in ("status", "pid")} if record else None
    if record and record.get("status") != "finished":
        run_info = {"status": record.get("status"), **(run_info or {})}
    summary = RunSummary(red, references(red.scene), None, run_info)
    st = red.steady
    try:
        point = RunPoint(
            case_dir,
            red.scene,
            st.steady,
            st.q if st.steady else None,
            st.q_std if st.steady else None,
            st.reason,
        )
        summary.comparison = compare_runs([point], case_dir)
    except FoamsiloError as exc:  # no law for this geometry, or no steady rate
        (case_dir / COMPARE_MD).unlink(missing_ok=True)
        summary.comparison = {"error": str(exc)}
    write_summary(summary)
    case_report(summary)
    return summary


# ----------------------------------------------------------------------------- one case


def run_case(
    spec: CaseSpec,
    *,
    of: OpenFOAM | None = None,
    progress: ProgressCallback | None = None,
    say: Say = _quiet,
) -> RunSummary:
    """Prepare, run and reduce one case."""
    of = of or find_openfoam()
    case_dir = prepare(spec, of, say)
    run(
        case_dir,
        of,
        n_procs=spec.n_procs,
        hostfile=spec.hostfile,
        resume=spec.resume,
        rerun=spec.rerun,
        reconstruct=spec.reconstruct,
        progress=progress,
        max_wall_seconds=spec.max_wall_seconds,
        say=say,
    )
    return reduce(case_dir)


# ----------------------------------------------------------------------------- many cases


@dataclass
class Outcome:
    """What one case of :func:`run_many` gave.

    Attributes
    ----------
    spec
        The case.
    status
        ``ok``, or the type of the error that stopped it (``DivergenceError``...).
    summary
        Its ``summary.json`` content (a reduced case), else None.
    error
        The error (type, message, and what it names), else None.
    wall_s
        Wall time of the worker.
    """

    spec: CaseSpec
    status: str
    summary: dict[str, Any] | None = None
    error: dict[str, Any] | None = None
    wall_s: float = 0.0

    @property
    def ok(self) -> bool:
        """Whether the case was run (or found finished) and reduced."""
        return self.status == "ok"


def error_payload(exc: BaseException) -> dict[str, Any]:
    """Return the error as the JSON outputs carry it: type, message, and what it names."""
    from foamsilo.errors import MeshError, SceneError, ToolchainError

    err: dict[str, Any] = {"type": type(exc).__name__, "message": str(exc)}
    if isinstance(exc, (SceneError, UsageError)):
        err["field"] = exc.field
    if isinstance(exc, ToolchainError):
        err.update(component=exc.component, fix=exc.fix)
    if isinstance(exc, FoamError):
        err.update(command=exc.command, returncode=exc.returncode, output=exc.output[-4000:])
    if isinstance(exc, (DivergenceError, RunInterruptedError, RunTimeLimitError)):
        err.update(time=exc.time, case_dir=str(exc.case_dir))
    if isinstance(exc, (DivergenceError, RunInterruptedError)):
        err["last_good_time"] = exc.last_good_time
    if isinstance(exc, DivergenceError):
        err["quantity"] = exc.quantity
    if isinstance(exc, CaseStateError):
        err.update(state=exc.state, case_dir=str(exc.case_dir))
    if isinstance(exc, MeshError) and exc.geometry_file:
        err["geometry_file"] = str(exc.geometry_file)
    return err


def _worker_main() -> int:
    """``python -m foamsilo.pipeline``: one :class:`CaseSpec` (JSON, stdin) -> Outcome (stdout)."""
    out = sys.stdout
    spec = CaseSpec.from_dict(json.loads(sys.stdin.read()))
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(sys.stderr):  # PyFoam prints
        try:
            # a first build of the solver is no part of the case's wall time
            ensure_solver()
            t0 = time.perf_counter()
            summary = run_case(spec)
            outcome = Outcome(spec, "ok", summary.as_json())
        except KeyboardInterrupt:
            outcome = Outcome(spec, "RunInterruptedError", error={"message": "interrupted"})
        except (FoamsiloError, OSError) as exc:
            outcome = Outcome(spec, type(exc).__name__, error=error_payload(exc))
    outcome.wall_s = time.perf_counter() - t0
    out.write(dumps(asdict(outcome)) + "\n")
    return 0


def _run_worker(spec: CaseSpec, procs: list[subprocess.Popen[str]], reap: bool = True) -> Outcome:
    """Run one spec in a worker process (tied to this one: it dies with it).

    With ``reap`` false the finished worker is left for the caller to wait
    for (it stays in ``procs``): until then its CPU time is not in this
    process's children's usage, from which a run of this process measures its
    solver's.
    """
    import tempfile

    argv = tied_to_parent([sys.executable, "-m", "foamsilo.pipeline"])
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as errors:
        proc = subprocess.Popen(
            argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=errors, text=True
        )
        procs.append(proc)
        assert proc.stdin is not None and proc.stdout is not None
        with contextlib.suppress(BrokenPipeError):
            proc.stdin.write(json.dumps(spec.as_dict()))
            proc.stdin.close()
        out = proc.stdout.read()  # to the worker's end; no wait(), which would reap it
        proc.stdout.close()
        if reap:
            proc.wait()
        errors.seek(0)
        err = errors.read()
    try:
        data = json.loads(out)
        return Outcome(
            replace(spec),
            data["status"],
            data.get("summary"),
            data.get("error"),
            data.get("wall_s", 0.0),
        )
    except (ValueError, KeyError):
        # an unreaped worker's status is read when its caller waits for it
        status = proc.wait() if reap else "not read yet"
        message = f"the worker ended with status {status}: {err[-2000:]}"
        return Outcome(
            spec,
            "crash",
            error={"type": "crash", "message": message},
            wall_s=time.perf_counter() - t0,
        )


@dataclass
class Budget:
    """How many cores many cases may use at once.

    Attributes
    ----------
    cores
        Cores to use (default: all of this machine's).
    ranks_per_case
        MPI ranks of each case.
    """

    cores: int = field(default_factory=lambda: os.cpu_count() or 1)
    ranks_per_case: int = 1

    def __post_init__(self) -> None:
        if self.ranks_per_case < 1:
            raise InputError(f"ranks per case: got {self.ranks_per_case}; allowed: >= 1")
        if self.cores < self.ranks_per_case:
            raise InputError(
                f"CPU budget: got {self.cores} cores; allowed: >= the ranks per case "
                f"({self.ranks_per_case})"
            )

    @property
    def cases_at_once(self) -> int:
        """How many cases run at the same time (cases x ranks <= cores)."""
        return max(1, self.cores // self.ranks_per_case)


class Backend(Protocol):
    """Where many cases run: this machine (:class:`LocalBackend`) or a cluster.

    The Slurm backend (:class:`foamsilo.slurm.SlurmBackend`) runs the same
    worker in batch jobs; sweeps and studies take either.
    """

    def run(
        self, specs: list[CaseSpec], on_done: Callable[[Outcome], None] | None = None
    ) -> list[Outcome]:
        """Prepare, run and reduce the cases; one outcome each, in order."""
        ...


@dataclass
class LocalBackend:
    """Many cases on this machine, in worker processes under a CPU budget."""

    budget: Budget = field(default_factory=Budget)

    def run(
        self, specs: list[CaseSpec], on_done: Callable[[Outcome], None] | None = None
    ) -> list[Outcome]:
        """See :func:`run_many`."""
        return run_many(specs, self.budget, on_done)


def case_ranks(spec: CaseSpec) -> int:
    """Return the MPI ranks a case runs on: the spec's, else its scene's ``run.n_procs``."""
    if spec.n_procs is not None:
        return spec.n_procs
    if spec.scene is None:
        return load_scene_file(Path(spec.case_dir) / SCENE_FILE).run.n_procs
    return load_scene(spec.scene, list(spec.overrides)).run.n_procs


def run_many(
    specs: list[CaseSpec],
    budget: Budget | None = None,
    on_done: Callable[[Outcome], None] | None = None,
    keep: list[subprocess.Popen[str]] | None = None,
) -> list[Outcome]:
    """Prepare, run and reduce many cases, ``budget.cases_at_once`` at a time.

    Each case runs in its own worker process (``python -m foamsilo.pipeline``)
    tied to this one. Returns one :class:`Outcome` per spec, in order;
    ``on_done`` is called as each finishes. With ``keep`` the finished
    workers are added to it unreaped, for the caller to wait for: a case run
    in this process beside them (:func:`grid_study`) measures its solver's
    CPU time from this process's children's usage, which a reaped worker's
    would enter.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C: the workers stop their solvers (resumable), this waits for
        them, then raises.
    """
    budget = budget or Budget()
    results: dict[int, Outcome] = {}
    procs: list[subprocess.Popen[str]] = keep if keep is not None else []
    pool = ThreadPoolExecutor(max_workers=budget.cases_at_once)
    try:
        futures = {pool.submit(_run_worker, s, procs, keep is None): i
                   for i, s in enumerate(specs)}  # fmt: skip
        for fut in as_completed(futures):
            i = futures[fut]
            results[i] = fut.result()
            if on_done is not None:
                on_done(results[i])
    except KeyboardInterrupt:
        for p in procs:  # a SIGINT sent to this process alone is passed on
            with contextlib.suppress(OSError):
                if p.poll() is None:
                    p.send_signal(signal.SIGINT)
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    finally:
        pool.shutdown(wait=True)
    return [results[i] for i in range(len(specs))]


# ----------------------------------------------------------------------------- grid study


def _check_grid_family(source: str, overrides: list[str], scene: Scene, ratio: float) -> None:
    """Refuse a grid study whose three grids are not one refinement family.

    A 3D O-grid whose counts sit at their floors on a coarse grid is finer
    there than its cells across say: its rate is closer to the fine grid's
    than the family's would be, the observed order comes out high and the
    GCI too small. Checked before anything is run.

    Raises
    ------
    InputError
        One of the three grids holds its O-grid at a floor; the message
        gives the fewest cells across from which the study is one family.
    """

    def floored_at(n: int) -> list[int]:
        fine = (
            scene
            if n == scene.cells_across
            else load_scene(source, [*overrides, format_override("mesh.cells_across", n)])
        )
        grids = [
            (m, load_scene(source, [*overrides, *companion_overrides(fine, m)]))
            for m in coarser_cells(n, ratio)
        ]
        return [m for m, sc in [*grids, (n, fine)] if o_grid_floored(sc)]

    bad = floored_at(scene.cells_across)
    if not bad:
        return
    upper = CELLS_ACROSS_MAX
    least = next((n for n in range(scene.cells_across + 1, upper + 1) if not floored_at(n)), None)
    allowed = f">= {least}" if least else f"none up to {upper}"
    raise InputError(
        f"mesh.cells_across = {scene.cells_across}: a grid study's grids at "
        f"{', '.join(map(str, bad))} across hold counts of the 3D O-grid at their floors "
        f"({MIN_QUADRANT_CELLS} cells on a quarter circle, cells no wider in angle than "
        "those beside a lateral orifice, 2 radially), finer there than "
        f"their cells across say, so the three are not one refinement family and their "
        f"GCI would be too small; allowed for this scene: {allowed} "
        "(docs/post.md, 'The uncertainty of Q')"
    )


def grid_study(
    spec: CaseSpec,
    *,
    budget: Budget | None = None,
    ratio: float = GRID_RATIO,
    of: OpenFOAM | None = None,
    progress: ProgressCallback | None = None,
    say: Say = _quiet,
) -> RunSummary:
    """Run a case and its scene on two coarser grids; its summary gets the grid error.

    The companions (cells across divided by ``ratio`` and ``ratio**2``) are
    cases of their own in ``<case>.grid/<N>-across`` (kept; found finished,
    they are only reduced again). They run beside the case, under what the
    budget leaves it; their steady rates go into the case's ``grid.json``
    and the case is reduced again, so that ``summary.json`` carries the grid
    convergence and ``Q_uncertainty`` combines it with the time-averaging
    error (:mod:`foamsilo.post.grid`). A companion that fails leaves the
    grid error unknown (said in the summary), not the case unreduced.

    Raises
    ------
    FoamsiloError
        The grids cannot be coarsened (too few cells across); the case's own
        errors as :func:`run_case` raises them.
    """
    import threading

    budget = budget or Budget()
    case_dir = Path(spec.case_dir).resolve()
    if spec.scene is None:
        source = str(case_dir / SCENE_FILE)
        scene = load_scene_file(source, list(spec.overrides))
    else:
        source = spec.scene
        scene = load_scene(spec.scene, list(spec.overrides))
    cells = coarser_cells(scene.cells_across, ratio)
    _check_grid_family(source, list(spec.overrides), scene, ratio)
    home = case_dir.parent / f"{case_dir.name}.grid"
    companions = [
        CaseSpec(
            home / f"{n}-across",
            source,
            (*spec.overrides, *companion_overrides(scene, n)),
            n_procs=spec.n_procs,
            rerun=spec.rerun,
            overwrite=spec.overwrite,
            update=not spec.overwrite,
            max_wall_seconds=spec.max_wall_seconds,
            label=f"{n} across",
        )
        for n in cells
    ]
    ranks = spec.n_procs or scene.run.n_procs
    side = Budget(cores=max(ranks, budget.cores - ranks), ranks_per_case=ranks)

    def done(o: Outcome) -> None:
        q = (o.summary or {}).get("Q")
        say(f"grid study: {o.spec.label}: " + (f"steady Q = {q:.5g}" if q else o.status))

    found: list[Outcome] = []
    failure: list[BaseException] = []
    # the companions' workers, reaped only once the case has run: its solver's
    # CPU time is this process's children's usage over the run, which a
    # companion reaped meanwhile would enter
    workers: list[subprocess.Popen[str]] = []

    def companions_run() -> None:
        try:
            found.extend(run_many(companions, side, on_done=done, keep=workers))
        except BaseException as exc:  # reported with the study, not lost in the thread
            failure.append(exc)

    # daemon: a case stopped by Ctrl-C or an error ends the process, and its
    # workers (tied to it) with it
    worker = threading.Thread(target=companions_run, daemon=True)
    worker.start()
    run_case(spec, of=of, progress=progress, say=say)
    worker.join()
    for p in workers:
        p.wait()
    if failure:
        raise failure[0]
    values = [(o.summary or {}).get("Q") if o.ok else None for o in found]
    write_grid_file(case_dir, [*cells, scene.cells_across], [*values, None],
                    [c.case_dir for c in companions])  # fmt: skip
    return reduce(case_dir)


if __name__ == "__main__":  # pragma: no cover - the worker entry point
    sys.exit(_worker_main())


__all__ = [
    "Backend",
    "Budget",
    "LocalBackend",
    "CaseSpec",
    "Outcome",
    "RunSummary",
    "case_ranks",
    "error_payload",
    "grid_study",
    "prepare",
    "reduce",
    "run",
    "run_case",
    "run_many",
]
