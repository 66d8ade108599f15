"""The ``foamsilo`` command line.

Every command takes ``--json``: a single strict JSON object on stdout (no
NaN) and nothing else, on success and on error, argument errors included.
Without it the output is for people. Exit status: 0 success, 1 failure (or,
for ``doctor``, something missing), 2 bad input (the message names the field
or option and what is allowed), 130 interrupted.

Each command does its work through :mod:`foamsilo.pipeline` (cases) or the
studies (:mod:`foamsilo.studies`); this module parses, prints and maps
errors to exit codes.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, NoReturn

from foamsilo import __version__
from foamsilo.errors import (
    FoamsiloError,
    InputError,
    RunInterruptedError,
    ToolchainError,
    UsageError,
)
from foamsilo.jsonio import dumps

DEFAULT_RUNS_DIR = Path("runs")


# ----------------------------------------------------------------------------- output


def _console(stderr: bool = False) -> Any:
    from rich.console import Console

    if stderr:
        # one console for messages and progress bars: a message printed while
        # a bar is live goes above it (the console finds sys.stderr per write)
        if not _STDERR:
            _STDERR.append(Console(stderr=True, highlight=False))
        return _STDERR[0]
    return Console(stderr=stderr, highlight=False)


_STDERR: list[Any] = []


#: Where --json output goes: the stdout of the call; everything else printed
#: meanwhile (PyFoam, OpenFOAM utilities run in-process) goes to stderr
_JSON_OUT: list[Any] = []


def _emit(args: argparse.Namespace, payload: dict[str, Any], human: Callable[[], object]) -> None:
    if getattr(args, "json", False):
        out = _JSON_OUT[-1] if _JSON_OUT else sys.stdout
        out.write(dumps(payload) + "\n")
    else:
        human()


def _say(args: argparse.Namespace) -> Callable[[str], None]:
    """Messages for people on stderr (none under --json or --quiet)."""
    if getattr(args, "json", False) or getattr(args, "quiet", False):
        return lambda m: None
    con = _console(stderr=True)
    return lambda m: con.print(m, markup=False)


@contextlib.contextmanager
def _progress(args: argparse.Namespace) -> Iterator[Callable[..., None] | None]:
    """Return a progress bar on a terminal (simulated time, dt, Courant, steps retaken, ETA).

    None where there is no terminal.
    """
    if getattr(args, "json", False) or getattr(args, "quiet", False) or not sys.stderr.isatty():
        yield None
        return
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    prog = Progress(
        TextColumn("[bold]siloFoam"),
        BarColumn(),
        TextColumn("t = {task.fields[t]:.4g} / {task.total:.4g} s"),
        TextColumn("dt {task.fields[dt]:.2e}"),
        TextColumn("Co {task.fields[co]:.2f} (grains {task.fields[gco]:.2f})"),
        TextColumn("{task.fields[retaken]}"),
        TimeRemainingColumn(),
        console=_console(stderr=True),
        transient=True,
        # no redirection of sys.stdout/stderr: the bar starts inside the run,
        # where the runner has sent stdout to the solver's log, and would
        # "restore" that (closed) log as stdout when it stops
        redirect_stdout=False,
        redirect_stderr=False,
    )
    state: dict[str, Any] = {"task": None, "last": 0.0}

    def update(monitor: Any, end_time: float) -> None:
        now = time.monotonic()
        if now - state["last"] < 0.2:
            return
        if not monitor.steps:  # the first step, taken again
            return
        state["last"] = now
        s = monitor.steps[-1]
        n = len(monitor.retakes)
        if state["task"] is None:
            prog.start()
            state["task"] = prog.add_task(
                "run", total=end_time, t=0.0, dt=0.0, co=0.0, gco=0.0, retaken=""
            )
        prog.update(
            state["task"],
            completed=s.time,
            t=s.time,
            dt=s.delta_t,
            co=s.courant,
            gco=s.granular_courant,
            retaken=f"{n} step{'s' if n != 1 else ''} retaken" if n else "",
        )

    try:
        yield update
    finally:
        if state["task"] is not None:
            prog.stop()


# ----------------------------------------------------------------------------- commands


def cmd_doctor(args: argparse.Namespace) -> int:
    """Report OpenFOAM, headers, solver build, gmsh and MPI."""
    from foamsilo.solver import find_solver
    from foamsilo.toolchain import SETUP_COMMAND, find_openfoam, gmsh_version, mpi_info

    report: dict[str, Any] = {"foamsilo_version": __version__}
    missing: list[dict[str, str]] = []
    of = None
    try:
        of = find_openfoam()
        report["openfoam"] = {
            "found": True,
            "version": of.version,
            "source": of.source,
            "project_dir": str(of.project_dir),
            "bin": str(of.appbin),
        }
    except ToolchainError as exc:
        report["openfoam"] = {"found": False, "fix": exc.fix}
        missing.append({"component": "openfoam", "fix": exc.fix})
    if of is not None:
        report["headers"] = {
            "found": of.has_headers,
            "source_dir": str(of.source_dir) if of.source_dir else None,
        }
        if not of.has_headers:
            missing.append({"component": "headers", "fix": SETUP_COMMAND})
        build = find_solver(of) if of.has_headers else None
        report["solver"] = {
            "found": build is not None,
            "executable": str(build.executable) if build else None,
            "library": str(build.library) if build else None,
            "source_hash": build.source_hash if build else None,
        }
        if build is None:
            missing.append({"component": "solver", "fix": "foamsilo build-solver"})
    gv = gmsh_version()
    report["gmsh"] = {"found": gv is not None, "version": gv}
    if gv is None:
        missing.append({"component": "gmsh", "fix": SETUP_COMMAND})
    mpi = mpi_info()
    report["mpi"] = {"found": mpi["mpirun"] is not None, **mpi}
    if mpi["mpirun"] is None:
        missing.append({"component": "mpi", "fix": SETUP_COMMAND})
    report["ok"] = not missing
    report["missing"] = missing

    def human() -> None:
        from rich.table import Table

        t = Table(title=f"foamsilo {__version__} doctor")
        for col in ("component", "status", "details"):
            t.add_column(col)
        ofr = report["openfoam"]
        t.add_row(
            "OpenFOAM",
            "ok" if ofr["found"] else "[red]missing",
            f"{ofr.get('version', '')} ({ofr.get('source', '')}) {ofr.get('bin', '')}",
        )
        if "headers" in report:
            h, s = report["headers"], report["solver"]
            t.add_row(
                "headers + wmake",
                "ok" if h["found"] else "[red]missing",
                str(h["source_dir"] or ""),
            )
            t.add_row(
                "siloFoam build", "ok" if s["found"] else "[red]missing", str(s["executable"] or "")
            )
        t.add_row("gmsh", "ok" if gv else "[red]missing", str(gv or ""))
        t.add_row(
            "MPI",
            "ok" if mpi["mpirun"] else "[red]missing",
            f"{mpi['version'] or ''} {mpi['mpirun'] or ''}",
        )
        con = _console()
        con.print(t)
        for m in missing:
            con.print(f"[red]missing {m['component']}[/]: run [bold]{m['fix']}[/]")

    _emit(args, report, human)
    return 0 if not missing else 1


def cmd_presets(args: argparse.Namespace) -> int:
    """List the named scenes of the papers."""
    from foamsilo.scene import preset_data, preset_names

    items = [
        {"name": n, "description": preset_data(n).get("description", "")} for n in preset_names()
    ]

    def human() -> None:
        con = _console()
        for it in items:
            con.print(f"[bold]{it['name']:<22}[/] {it['description']}")

    _emit(args, {"ok": True, "presets": items}, human)
    return 0


def _scene_text(spec: str, overrides: list[str]) -> str | None:
    from foamsilo.scene import is_scene_file

    return Path(spec).read_text() if is_scene_file(spec) and not overrides else None


def cmd_new(args: argparse.Namespace) -> int:
    """Write a case (dictionaries, mesh, initial fill)."""
    from foamsilo.case import create_case
    from foamsilo.scene import load_scene
    from foamsilo.toolchain import find_openfoam

    scene = load_scene(args.scene, args.set)
    case = create_case(
        scene,
        Path(args.output),
        find_openfoam(),
        overwrite=args.overwrite,
        scene_text=_scene_text(args.scene, args.set),
        dump_geometry=args.dump_geometry,
    )

    def human() -> None:
        con = _console()
        con.print(
            f"wrote case [bold]{case.path}[/] ({case.representation}, "
            f"{case.mesh.cells if case.mesh else '?'} cells, {len(case.files)} files)"
        )
        con.print(f"run it: foamsilo run {case.path}")

    _emit(args, {"ok": True, **case.as_dict()}, human)
    return 0


def cmd_mesh(args: argparse.Namespace) -> int:
    """Mesh a scene and report checkMesh's verdict and figures."""
    from foamsilo.case import create_case
    from foamsilo.scene import load_scene
    from foamsilo.toolchain import find_openfoam

    scene = load_scene(args.scene, args.set)
    of = find_openfoam()
    text = _scene_text(args.scene, args.set)
    if args.output:
        case = create_case(
            scene,
            Path(args.output),
            of,
            overwrite=args.overwrite,
            scene_text=text,
            dump_geometry=args.dump_geometry,
        )
    else:
        with tempfile.TemporaryDirectory(prefix="foamsilo-mesh-") as tmp:
            case = create_case(
                scene, Path(tmp) / scene.name, of, scene_text=text, dump_geometry=args.dump_geometry
            )
    assert case.mesh is not None
    payload = {"ok": True, "scene": scene.name, **case.mesh.as_dict()}
    if not args.output:
        payload.pop("msh_file", None)

    def human() -> None:
        m = case.mesh
        assert m is not None
        c = m.check
        _console().print(
            f"{scene.name}: {m.representation}, {m.cells} cells ({m.cell_kind}), checkMesh "
            f"{'OK' if c.ok else 'FAILED'}: max non-orthogonality {c.max_non_orthogonality:.3g} "
            f"deg, max skewness {c.max_skewness:.3g}, max aspect ratio "
            f"{c.max_aspect_ratio:.3g} ({m.seconds:.2f} s)"
        )

    _emit(args, payload, human)
    return 0


def cmd_build_solver(args: argparse.Namespace) -> int:
    """Build (or rebuild) siloFoam and the mu(I) library."""
    from foamsilo.solver import ensure_solver

    build = ensure_solver(force=not args.if_needed, log=_say(args))
    payload = {
        "ok": True,
        "executable": str(build.executable),
        "library": str(build.library),
        **build.info,
    }
    _emit(args, payload, lambda: _console().print(f"siloFoam: {build.executable}"))
    return 0


def _print_summary(s: dict[str, Any]) -> None:
    from rich.table import Table

    con = _console()
    t = Table(
        title=f"{s['scene']} ({s['representation']}, {s['cells_across']} cells across L, "
        f"{s.get('cells_across_orifice')} across D{', graded' if s.get('graded') else ''}, "
        f"{s['cells']} cells)"
    )
    t.add_column("quantity")
    t.add_column("value", justify="right")
    if s["steady"]:
        scale = s["flow_rate_scale"]["name"]
        t.add_row("steady Q", f"{s['Q']:.5g} {s['Q_units']}")
        t.add_row(
            f"Q/({scale}), orifice flux",
            f"{s['Q_dimensionless']:.4f} +- {s['Q_std_dimensionless']:.4f}",
        )
        t.add_row(f"Q/({scale}), volume decrease", f"{s['Q_from_volume_dimensionless']:.4f}")
        u = s.get("Q_uncertainty") or {}
        if u.get("grid_known"):
            t.add_row("uncertainty (95%), time and grid",
                      f"+- {u['combined']:.2g} {s['Q_units']} ({u['relative']:.1%})")  # fmt: skip
        elif u:
            t.add_row("uncertainty (95%), time only",
                      f"+- {u['time']:.2g} {s['Q_units']} (grid: --grid-error)")  # fmt: skip
        w = s["steady_window_s"]
        t.add_row("steady window", f"{w[0]:.3g} - {w[1]:.3g} s")
        ref = s.get("reference")
        if ref and ref.get("rel_diff") is not None:
            spread = f" +- {ref['spread']:.2f}" if "spread" in ref else ""
            t.add_row(
                ref.get("source", "reference"),
                f"{ref['Q_dimensionless']:.3f}{spread} ({ref['rel_diff']:+.1%})",
            )
        bev = s.get("beverloo_2d")
        if bev and bev.get("rel_diff") is not None:
            t.add_row(
                f"2D Beverloo, C = {bev['C']:.2f}",
                f"{bev['Q_dimensionless']:.4f} ({bev['rel_diff']:+.1%})",
            )
    else:
        t.add_row("steady", f"[red]no[/]: {s['steady_reason']}")
    t.add_row("mass balance error", f"{s['mass_balance_rel_error']:.1e}")
    run = s.get("run")
    if run and "wall_seconds" in run:
        t.add_row(
            "solver wall / CPU time",
            f"{run['wall_seconds']:.1f} s / {run['cpu_seconds']:.1f} s ({run['steps']} steps)",
        )
    con.print(t)
    for w in s.get("warnings") or []:
        con.print(f"[yellow]warning[/]: {w}")
    con.print(f"files: {s['case_dir']}/discharge.csv, discharge.png, summary.json, report.md")


def cmd_run(args: argparse.Namespace) -> int:
    """Create (if needed), run and reduce a case."""
    from foamsilo.case import is_case
    from foamsilo.pipeline import CaseSpec, grid_study, run_case
    from foamsilo.scene import load_scene

    if args.np is not None and args.np < 1:
        raise UsageError("--np", f"{args.np} ranks; allowed: an integer >= 1")
    if args.hostfile is not None and not args.hostfile.is_file():
        raise UsageError("--hostfile", f"{args.hostfile}: no such file")
    if args.resume and args.rerun:
        raise UsageError(
            "--rerun",
            "--resume goes on from the latest time, --rerun starts over: give one of them",
        )
    target = Path(args.scene)
    if target.is_dir() and is_case(target) and not args.output:
        spec = CaseSpec(target, None, tuple(args.set))
    elif target.is_dir() and not target.suffix == ".toml" and not args.output:
        raise UsageError(
            "scene",
            f"{target} is a directory but not a foamsilo case "
            "(no foamsilo.json); give a preset, a scene file or a case",
        )
    else:
        scene = load_scene(args.scene, args.set)
        spec = CaseSpec(
            Path(args.output or DEFAULT_RUNS_DIR / scene.name), args.scene, tuple(args.set)
        )
    from dataclasses import replace

    spec = replace(
        spec,
        n_procs=args.np,
        hostfile=args.hostfile,
        resume=args.resume,
        rerun=args.rerun,
        overwrite=args.overwrite,
        update=args.update,
        reconstruct=args.reconstruct,
    )
    if args.slurm:
        return _run_on_slurm(args, spec)
    with _progress(args) as progress:
        if args.grid_error:
            summary = grid_study(spec, progress=progress, say=_say(args))
        else:
            summary = run_case(spec, progress=progress, say=_say(args))
    s = summary.as_json()
    _emit(args, {"ok": True, **s}, lambda: _print_summary(s))
    return 0


def _slurm_options(
    args: argparse.Namespace, base: Any = None, time_limit: str | None = None
) -> Any:
    """Return the Slurm options of the command line, over ``base`` (a sweep file's)."""
    from foamsilo.slurm import SlurmOptions

    return (base or SlurmOptions()).merged(
        partition=args.partition,
        account=args.account,
        time_limit=time_limit or getattr(args, "time_limit", None),
        sbatch=tuple(args.sbatch or ()),
        poll_seconds=args.poll,
    )


def _run_on_slurm(args: argparse.Namespace, spec: Any) -> int:
    """``run --slurm``: the case as one batch job, followed to its end."""
    from dataclasses import replace

    from foamsilo.slurm import SlurmBackend

    for flag, given in (("--grid-error", args.grid_error), ("--hostfile", args.hostfile)):
        if given:
            raise UsageError(flag, "not with --slurm (a job runs on the nodes Slurm gives it)")
    # a job that is submitted again goes on from the case's latest complete time
    spec = replace(spec, resume=not (spec.rerun or spec.overwrite))
    backend = SlurmBackend(_slurm_options(args), say=_say(args))
    (outcome,) = backend.run([spec])
    if outcome.ok and outcome.summary is not None:
        s = outcome.summary
        _emit(args, {"ok": True, **s}, lambda: _print_summary(s))
        return 0
    err = outcome.error or {"type": outcome.status, "message": outcome.status}
    _emit(args, {"ok": False, "error": err},
          lambda: _console(stderr=True).print(f"[red]error[/]: {err.get('message')}"))  # fmt: skip
    return 1


def cmd_post(args: argparse.Namespace) -> int:
    """Reduce a case: Q(t), steady Q, mass balance, fields, pictures, report."""
    from foamsilo.pipeline import reduce

    s = reduce(_case_dir(args.case)).as_json()
    _emit(args, {"ok": True, **s}, lambda: _print_summary(s))
    return 0


def _case_dir(path: str) -> Path:
    from foamsilo.case import is_case

    p = Path(path)
    if not p.exists():
        raise UsageError("case", f"{p}: no such directory")
    if not is_case(p):
        raise UsageError("case", f"{p} is not a foamsilo case (no foamsilo.json)")
    return p.resolve()


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run a sweep file's cases under its CPU budget; resumable."""
    from foamsilo.sweep import load_sweep, run_sweep

    sweep = load_sweep(Path(args.sweep))
    backend: Any = None
    if args.backend == "slurm":
        from foamsilo.slurm import SlurmBackend

        backend = SlurmBackend(_slurm_options(args, sweep.slurm), say=_say(args))
    elif sys.stderr.isatty():
        from foamsilo.pipeline import LocalBackend

        _say(args)(f"up to {sweep.cases_at_once} cases at once (CPU budget {sweep.cpu_budget})")
        backend = LocalBackend(sweep.budget)
    if backend is not None:
        backend = _cases_progress(args, backend)
    rows = run_sweep(sweep, log=_say(args), backend=backend)
    failed = [r for r in rows if r["status"] != "ok"]

    def human() -> None:
        from rich.table import Table

        keys = [
            k
            for k in (sweep.cases[0].overrides if sweep.cases else {})
            if len({repr(c.overrides.get(k)) for c in sweep.cases}) > 1
        ]
        tab = Table(title=f"sweep {sweep.name} ({sweep.output}/summary.csv)")
        for k in ["case", *keys, "status", "Q", "Q_dimensionless"]:
            tab.add_column(k)
        for r in rows:
            q, qd = r.get("Q"), r.get("Q_dimensionless")
            tab.add_row(
                str(r["case"]),
                *[str(r.get(k)) for k in keys],
                r["status"],
                f"{q:.5g}" if isinstance(q, float) else "-",
                f"{qd:.4f}" if isinstance(qd, float) else "-",
            )
        _console().print(tab)

    _emit(args, {"ok": not failed, "output": str(sweep.output), "cases": rows}, human)
    return 0 if not failed else 1


def cmd_compare(args: argparse.Namespace) -> int:
    """Set a case's or sweep's steady rates on the analytic curves."""
    from foamsilo.compare import compare
    from foamsilo.report import sweep_report

    target = Path(args.target)
    if not target.is_dir():
        raise UsageError("target", f"{target}: no such directory")
    result = compare(target.resolve())
    if result["kind"] == "sweep":
        result["report"] = str(sweep_report(target.resolve()))

    def human() -> None:
        con = _console()
        for p in result["points"]:
            con.print(
                f"{Path(p['case']).name}: Q = {p['q']:.5g} {p['units']}, {p['law']} "
                f"{p['q_law']:.5g} ({p['rel_error']:+.1%})"
            )
        for sk in result["skipped"]:
            con.print(f"{Path(sk['case']).name}: not compared ({sk['reason']})")
        con.print(f"rms {result['rms_rel_error']:.1%}; table and plot in {target}/compare.md")

    _emit(args, {"ok": True, **result}, human)
    return 0


def cmd_analytic(args: argparse.Namespace) -> int:
    """Evaluate an analytic law (``foamsilo analytic FORM ...``)."""
    payload = args.analytic(args)

    def human() -> None:
        con = _console()
        for k, v in payload.items():
            if isinstance(v, list) and len(v) > 8:
                v = f"[{len(v)} values: {v[0]:.6g} ... {v[-1]:.6g}]" if v else "[]"
            elif isinstance(v, float):
                v = f"{v:.6g}"
            con.print(f"{k:>20}: {v}")

    _emit(args, {"ok": True, **payload}, human)
    return 0


class _CasesProgress:
    """A backend shown on a terminal: cases done / total, the running ones' time, an ETA.

    Wraps the backend the cases run on (this machine's or Slurm's); a thread
    reads each unfinished case's solver log (its latest ``Time =``) every
    second. The bar's fill counts the running cases' fractions, so that the
    ETA moves with the simulated time, not only when a case ends.
    """

    def __init__(self, inner: Any, console: Any) -> None:
        self.inner = inner
        self.console = console

    def run(self, specs: list[Any], on_done: Callable[[Any], None] | None = None) -> list[Any]:
        import threading

        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        from foamsilo.case import SCENE_FILE, is_case
        from foamsilo.run import log_time
        from foamsilo.scene import load_scene, load_scene_file

        def end_time(spec: Any) -> float:
            if spec.scene is None:
                return float(load_scene_file(Path(spec.case_dir) / SCENE_FILE).run.end_time)
            return float(load_scene(spec.scene, list(spec.overrides)).run.end_time)

        ends = [end_time(s) for s in specs]
        finished: set[int] = set()
        by_dir = {Path(s.case_dir): i for i, s in enumerate(specs)}
        where = Path(specs[0].case_dir).parent.name if specs else ""
        prog = Progress(
            TextColumn(f"[bold]{where}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("cases"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            TextColumn("{task.fields[running]}"),
            console=self.console,
            transient=True,
        )
        task = prog.add_task(where, total=len(specs), running="")
        stop = threading.Event()

        def refresh() -> None:
            parts, fraction = [], 0.0
            for i, s in enumerate(specs):
                d = Path(s.case_dir)
                if i in finished or not d.is_dir() or not is_case(d):
                    continue
                t = log_time(d)
                if t is None:
                    continue
                fraction += min(t / ends[i], 1.0) if ends[i] > 0 else 0.0
                parts.append(f"{t:.3g}/{ends[i]:.3g} s")
            running = f"running: {', '.join(parts[:4])}" + (" ..." if len(parts) > 4 else "")
            prog.update(task, completed=len(finished) + fraction,
                        running=running if parts else "")  # fmt: skip

        def poll() -> None:
            while not stop.wait(1.0):
                refresh()

        def done(o: Any) -> None:
            finished.add(by_dir[Path(o.spec.case_dir)])
            refresh()
            if on_done is not None:
                on_done(o)

        watcher = threading.Thread(target=poll, daemon=True)
        with prog:
            watcher.start()
            try:
                return list(self.inner.run(specs, on_done=done))
            finally:
                stop.set()
                watcher.join()


def _cases_progress(args: argparse.Namespace, jobs: Any) -> Any:
    """Return ``jobs`` (cases at a time, or a backend) shown as a progress bar on a terminal.

    Under ``--json`` or ``--quiet``, or off a terminal, ``jobs`` itself: the
    commands then print one line per finished case (or nothing).
    """
    if getattr(args, "json", False) or getattr(args, "quiet", False) or not sys.stderr.isatty():
        return jobs
    from foamsilo.studies.cases import backend_of

    return _CasesProgress(backend_of(jobs), _console(stderr=True))


def _progress_backend(args: argparse.Namespace, jobs: int) -> Any:
    """Return the progress display of ``jobs`` cases at a time on a terminal, else None."""
    shown = _cases_progress(args, jobs)
    return None if isinstance(shown, int) else shown


def _row_printer(args: argparse.Namespace) -> Callable[[dict[str, Any]], None]:
    say = _say(args)

    def on_row(r: dict[str, Any]) -> None:
        q = r.get("Q")
        say(
            f"{r['label']}: {r['outcome']}"
            + (f", Q = {q:.5g}" if isinstance(q, float) else "")
            + f" ({r['wall_s']:.0f} s)"
        )

    return on_row


@contextlib.contextmanager
def _work_dir(args: argparse.Namespace, prefix: str) -> Iterator[Path]:
    """Yield the study's work directory: ``--work-dir``, or a temporary one.

    A temporary one is removed afterwards, but for the cases that failed or
    were interrupted: those are kept for inspection (the reports name them),
    and stderr says where.
    """
    if args.work_dir:
        yield Path(args.work_dir)
        return
    tmp = Path(tempfile.mkdtemp(prefix=prefix))
    try:
        yield tmp
    finally:
        kept = _remove_all_but_failed(tmp)
        if kept:
            _console(stderr=True).print(
                f"foamsilo: kept for inspection (failed or interrupted): "
                f"{', '.join(str(k) for k in kept)}"
            )


def _remove_all_but_failed(work: Path) -> list[Path]:
    """Remove ``work`` but for its failed or interrupted cases; return those."""
    import shutil

    from foamsilo.case.lifecycle import CaseState, inspect

    keep = [
        meta.parent
        for meta in sorted(work.rglob("foamsilo.json"))
        if inspect(meta.parent).state in (CaseState.FAILED, CaseState.INTERRUPTED)
    ]
    if not keep:
        shutil.rmtree(work, ignore_errors=True)
        return []
    for entry in work.iterdir():
        if not any(k == entry or entry in k.parents for k in keep):
            if entry.is_dir():
                shutil.rmtree(entry, ignore_errors=True)
            else:
                entry.unlink(missing_ok=True)
    return keep


def cmd_validate(args: argparse.Namespace) -> int:
    """Reproduce a seed paper's simulations and write the report into docs/."""
    from foamsilo.studies.gas import gas_extremes, zhou_gas

    runs = {"jobs": args.jobs, "backend": _progress_backend(args, args.jobs)}
    with _work_dir(args, "foamsilo-validate-") as work:
        where = (args.cells, work, Path(args.output))
        if args.suite == "gas-extremes":
            report = gas_extremes(*where, limit=args.time_limit, **runs)
            _emit(
                args,
                {"ok": True, **report},
                lambda: _console().print(
                    "\n".join(f"{r['label']}: {r['outcome']}" for r in report["rows"])
                ),
            )
            return 0
        report = zhou_gas(*where, end_time=args.end_time, **runs)

    def human() -> None:
        _console().print(
            f"Zhou Fig. 4b: rms difference to eq. 23 (A = 0.68) "
            f"{report['rms_rel_diff_A068']:.1%}; Fig. 6b zone slope "
            f"{report['fig6b_slope_zone']:.3f}; report in {args.output}/zhou-gas-planar.md"
        )

    _emit(args, {"ok": True, **report}, human)
    return 0


# ----------------------------------------------------------------------------- bench


def _bench_log(args: argparse.Namespace, result: dict[str, Any], name: str) -> None:
    from foamsilo.studies.bench import write_result

    if args.log:
        write_result(result, Path(args.log) / f"{name}.jsonl")


def _bench_out(args: argparse.Namespace, res: dict[str, Any], text: str, name: str) -> int:
    """Append a benchmark's record to its log, write its table, print it."""
    _bench_log(args, res, name)
    if args.output:
        Path(args.output).write_text(text + "\n")
    _emit(args, {"ok": True, **res}, lambda: sys.stdout.write(text + "\n"))
    return 0


def cmd_bench_validation(args: argparse.Namespace) -> int:
    """Return the validation suite (checks with tolerances; exit 1 when one fails)."""
    from foamsilo.studies.suite import longest_wall_limit, rewrite_report, run_suite

    if args.report_only:
        res = rewrite_report(args.quick, Path(args.output))
    else:
        jobs: Any = args.jobs
        if args.backend == "slurm":
            from foamsilo.slurm import SlurmBackend

            if not args.work_dir:
                raise UsageError(
                    "--work-dir", "required with --backend slurm: a directory the nodes share"
                )
            # the job's limit: the longest wall limit of a case (a preset's own
            # can exceed --time-limit), and time to mesh and reduce
            minutes = str(int(math.ceil(longest_wall_limit(args.time_limit) / 60.0)) + 10)
            jobs = SlurmBackend(_slurm_options(args, time_limit=minutes), say=_say(args))
        with _work_dir(args, "foamsilo-suite-") as work:
            res = run_suite(
                args.quick,
                Path(args.output),
                work,
                args.only or None,
                jobs=_cases_progress(args, jobs),
                limit=args.time_limit,
                on_row=_row_printer(args),
                values=args.values,
            )
    failed = [c for c in res["checks"] if not c["passed"]]

    def human() -> None:
        con = _console()
        for c in res["checks"]:
            mark = "pass" if c["passed"] else "FAIL"
            con.print(
                f"{mark}  {c['entry']}: {c['name']} = {c['value']} "
                f"(allowed [{c['low']:g}, {c['high']:g}])",
                markup=False,
            )
        con.print(f"report: {args.output}/{'suite-quick' if args.quick else 'suite'}.md")

    _emit(args, {"ok": not failed, **res}, human)
    return 1 if failed else 0


def cmd_bench_verification(args: argparse.Namespace) -> int:
    """Return the code verification (exact profiles; exit 1 when a check fails)."""
    from foamsilo.studies.verify import report_stem, run_verification

    say = (
        (lambda _: None)
        if args.quiet or args.json
        else (lambda m: _console().print(m, markup=False))
    )
    with _work_dir(args, "foamsilo-verify-") as work:
        res = run_verification(
            args.quick, Path(args.output), work, args.only or None, say=say, sets=args.set
        )
    failed = [c for c in res["checks"] if not c["passed"]]

    def human() -> None:
        con = _console()
        for c in res["checks"]:
            mark = "pass" if c["passed"] else "FAIL"
            value = "none" if c["value"] is None else f"{c['value']:.3g}"
            con.print(f"{mark}  {c['entry']}: {c['name']} = {value} (bound {c['bound']})",
                      markup=False)  # fmt: skip
        con.print(f"report: {args.output}/{report_stem(args.quick, args.set)}.md")

    _emit(args, {"ok": not failed, **res}, human)
    return 1 if failed else 0


def cmd_bench_solver(args: argparse.Namespace) -> int:
    """Cost and accuracy of the solver on the planar silo."""
    from foamsilo.studies.bench import bench_solver, solver_table

    with _work_dir(args, "foamsilo-bench-") as work, _progress(args) as progress:
        result = bench_solver(
            args.cells,
            args.end_time,
            work,
            extra=args.set,
            reference=not args.no_reference,
            keep=args.work_dir is not None,
            say=_say(args),
            progress=progress,
        )
    result["label"] = args.label
    _bench_log(args, result, "solver")

    def human() -> None:
        m = result["machine"]
        _console().print(
            f"solver benchmark ({args.label or 'current'}), {m['cpu']} x{m['cores']}, "
            f"commit {result['commit']}, end time {args.end_time} s"
        )
        _console().print(solver_table(result))

    _emit(args, {"ok": True, **result}, human)
    return 0


def cmd_bench_gas(args: argparse.Namespace) -> int:
    """Cost of the pore-pressure solve against the same scene dry."""
    from foamsilo.studies.bench import bench_gas

    with _work_dir(args, "foamsilo-bench-") as work, _progress(args) as progress:
        res = bench_gas(args.cells, args.end_time, work, say=_say(args), progress=progress)
    _bench_log(args, res, "gas")

    def human() -> None:
        for label, r in res["rows"].items():
            _console().print(
                f"{label:>40}: {r['ms_per_step']:.2f} ms/step ({r['steps']} steps), "
                f"ratio to dry {r['ratio_to_dry']:.2f}"
            )

    _emit(args, {"ok": True, **res}, human)
    return 0


def cmd_bench_mesh(args: argparse.Namespace) -> int:
    """Meshing time and memory of a 3D cylinder."""
    from foamsilo.studies.bench import bench_mesh, mesh_report

    with _work_dir(args, "foamsilo-bench-") as work:
        res = bench_mesh(args.cells, work, say=_say(args))
    return _bench_out(args, res, mesh_report(res), "mesh")


def cmd_bench_mpi(args: argparse.Namespace) -> int:
    """MPI speed-up and the runner's overhead on a 3D silo."""
    from foamsilo.studies.bench import bench_mpi, mpi_report

    with _work_dir(args, "foamsilo-bench-") as work:
        res = bench_mpi(
            args.ranks, args.cells, args.end_time, work, repeats=args.repeats, say=_say(args)
        )
    return _bench_out(args, res, mpi_report(res), "mpi")


def cmd_bench_post(args: argparse.Namespace) -> int:
    """Cost of `foamsilo post` on a 3D silo with many written times."""
    from foamsilo.studies.bench import bench_post, post_report

    with _work_dir(args, "foamsilo-bench-") as work, _progress(args) as progress:
        res = bench_post(args.cells, args.times, work, ranks=args.ranks,
                         interval=args.write_interval, say=_say(args),
                         progress=progress)  # fmt: skip
    return _bench_out(args, res, post_report(res), "post")


def cmd_bench_hopper(args: argparse.Namespace) -> int:
    """Error against wall time of the DG hopper solver, k = 0, 1, 2."""
    from foamsilo.hopper.figures import plot_work_precision, work_precision, work_precision_markdown
    from foamsilo.studies.cases import git_commit, machine_info

    commit = git_commit()  # before the runs (git_commit)
    res = work_precision(cells=tuple(args.cells))
    res["commit"], res["machine"] = commit, machine_info()
    figure = Path(args.figure)
    figure.parent.mkdir(parents=True, exist_ok=True)
    plot_work_precision(res, figure)
    return _bench_out(args, res, work_precision_markdown(res), "hopper")


def cmd_bench_report(args: argparse.Namespace) -> int:
    """Return the solver benchmark's tables, from its log."""
    from foamsilo.studies.bench import read_log, solver_report

    text = solver_report(read_log(Path(args.log) / "solver.jsonl"))
    if args.output:
        Path(args.output).write_text(text + "\n")
    _emit(args, {"ok": True, "markdown": text}, lambda: sys.stdout.write(text + "\n"))
    return 0


# ----------------------------------------------------------------------------- references


def cli_reference_markdown() -> str:
    """Return the command-line reference (Markdown), generated from the parser."""
    import os

    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal: fix the width
    try:
        return _cli_reference(build_parser())
    finally:
        if saved is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = saved


def _cli_reference(parser: argparse.ArgumentParser) -> str:
    out = [
        "# Command-line reference",
        "",
        "Generated from `foamsilo/cli.py`: `foamsilo cli-reference > docs/cli.md`.",
        "",
    ]
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sp in sub.choices.items():
        out += [f"## foamsilo {name}", "", "```text", sp.format_help().rstrip(), "```", ""]
        nested = [a for a in sp._actions if isinstance(a, argparse._SubParsersAction)]
        for group in nested:
            for form, fp in group.choices.items():
                out += [
                    f"### foamsilo {name} {form}",
                    "",
                    "```text",
                    fp.format_help().rstrip(),
                    "```",
                    "",
                ]
    return "\n".join(out)


def cmd_cli_reference(args: argparse.Namespace) -> int:
    """Print the command-line reference (Markdown)."""
    text = cli_reference_markdown()
    _emit(args, {"ok": True, "markdown": text}, lambda: sys.stdout.write(text + "\n"))
    return 0


def cmd_scene_reference(args: argparse.Namespace) -> int:
    """Print the scene-file reference (Markdown)."""
    from foamsilo.scene import reference_markdown

    text = reference_markdown()
    _emit(args, {"ok": True, "markdown": text}, lambda: sys.stdout.write(text + "\n"))
    return 0


# ----------------------------------------------------------------------------- parser


class _Parser(argparse.ArgumentParser):
    """argparse, with usage errors raised (so that --json can report them as JSON)."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(self.prog, message)


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser (also used to document the CLI)."""
    from foamsilo.studies.bench import defaults

    p = _Parser(
        prog="foamsilo",
        description="OpenFOAM simulations of granular silo discharge, and their cross-checks.",
    )
    p.add_argument("--version", action="version", version=f"foamsilo {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)

    def add(parent: Any, name: str, func: Callable[[argparse.Namespace], int], help_: str) -> Any:
        sp = parent.add_parser(name, help=help_, description=help_)
        sp.add_argument("--json", action="store_true", help="one JSON object on stdout")
        sp.set_defaults(func=func)
        return sp

    def slurm_args(sp: Any, time_limit: bool = True) -> None:
        g = sp.add_argument_group("Slurm (with --slurm or --backend slurm)")
        g.add_argument("--partition", help="sbatch --partition")
        g.add_argument("--account", help="sbatch --account")
        if time_limit:
            g.add_argument("--time-limit", help="sbatch --time per job (MM, HH:MM:SS, D-HH)")
        g.add_argument(
            "--sbatch",
            action="append",
            metavar="OPTION",
            help="a further #SBATCH option, e.g. --sbatch=--qos=short (repeatable)",
        )
        g.add_argument(
            "--poll", type=float, default=None, help="seconds between reads of the queue (5)"
        )

    def scene_args(sp: Any) -> None:
        sp.add_argument("scene", help="preset name or scene TOML file")
        sp.add_argument(
            "--set",
            action="append",
            metavar="KEY=VALUE",
            default=[],
            help="override a scene value, e.g. mesh.cells_across=32 (repeatable)",
        )

    add(sub, "doctor", cmd_doctor, "report what OpenFOAM, headers, solver, gmsh and MPI are found")
    add(sub, "presets", cmd_presets, "list the named scenes of the papers")

    sp = add(sub, "new", cmd_new, "write a ready-to-run case for a scene")
    scene_args(sp)
    sp.add_argument("-o", "--output", required=True, help="case directory to write")
    sp.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an existing foamsilo case (never a directory that is not one)",
    )
    sp.add_argument(
        "--dump-geometry",
        type=Path,
        metavar="FILE",
        help="also write the gmsh geometry (.geo_unrolled, .brep)",
    )

    sp = add(sub, "mesh", cmd_mesh, "mesh a scene and report the checkMesh verdict")
    scene_args(sp)
    sp.add_argument("-o", "--output", help="keep the meshed case here")
    sp.add_argument("--overwrite", action="store_true", help="replace an existing foamsilo case")
    sp.add_argument(
        "--dump-geometry", type=Path, metavar="FILE", help="write the gmsh geometry for inspection"
    )

    sp = add(sub, "run", cmd_run, "run a scene (or a case directory) and reduce it")
    sp.add_argument("scene", help="preset name, scene TOML file, or case directory")
    sp.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        default=[],
        help="override a scene value (repeatable)",
    )
    sp.add_argument("-o", "--output", help=f"case directory (default {DEFAULT_RUNS_DIR}/<name>)")
    sp.add_argument(
        "--overwrite",
        action="store_true",
        help="write the case afresh (from the scene, or a case's own scene.toml)",
    )
    sp.add_argument(
        "--update",
        action="store_true",
        help="replace the case if it holds another scene; reuse it if it holds this one",
    )
    sp.add_argument(
        "--rerun",
        action="store_true",
        help="run again from t = 0 (the results of earlier runs are removed)",
    )
    sp.add_argument(
        "--resume",
        action="store_true",
        help="continue an interrupted or failed run from its latest complete time",
    )
    sp.add_argument(
        "--np", type=int, default=None, help="MPI ranks (default: the scene's run.n_procs)"
    )
    sp.add_argument(
        "--grid-error",
        action="store_true",
        help="also run the scene on two coarser grids (cells across / 1.5 and / 2.25, in "
        "<case>.grid/) and give Q's uncertainty with its grid error (GCI)",
    )
    sp.add_argument(
        "--hostfile",
        type=Path,
        default=None,
        help="Open MPI hostfile (one host per line and slot) for runs across machines",
    )
    sp.add_argument(
        "--reconstruct",
        action="store_true",
        help="after a parallel run, merge the processor directories (reconstructPar)",
    )
    sp.add_argument("--quiet", action="store_true", help="no progress bar, no messages")
    sp.add_argument(
        "--slurm",
        action="store_true",
        help="run the case as a Slurm batch job (--ntasks = its ranks) and follow it",
    )
    slurm_args(sp)

    sp = add(sub, "sweep", cmd_sweep, "run the cases of a sweep file here or on Slurm (resumable)")
    sp.add_argument("sweep", help="sweep TOML file (see foamsilo/sweep.py for the format)")
    sp.add_argument("--quiet", action="store_true", help="no per-case messages")
    sp.add_argument(
        "--backend",
        choices=["local", "slurm"],
        default="local",
        help="local: worker processes under the sweep's CPU budget; slurm: one batch job "
        "per case (options from the sweep's [slurm] table and the command line)",
    )
    slurm_args(sp)

    sp = add(sub, "post", cmd_post, "reduce a case: Q(t), steady Q, fields, pictures, report")
    sp.add_argument("case", help="case directory")

    sp = add(sub, "compare", cmd_compare, "simulation points on the analytic curves, with errors")
    sp.add_argument("target", help="case directory, or a sweep's output directory")

    add(sub, "build-solver", cmd_build_solver, "build siloFoam and its mu(I) library").add_argument(
        "--if-needed", action="store_true", help="only if the sources changed"
    )
    add(sub, "scene-reference", cmd_scene_reference, "print the scene-file reference (Markdown)")
    add(sub, "cli-reference", cmd_cli_reference, "print this command-line reference (Markdown)")

    sp = add(
        sub, "validate", cmd_validate, "reproduce a seed paper's simulations (report in docs/)"
    )
    sp.add_argument(
        "suite",
        choices=["zhou-gas", "gas-extremes"],
        help="zhou-gas: Zhou et al. 2019 sec. III.B, Figs 4b-6b; gas-extremes: stiff "
        "and extreme gas cases in the lab silo",
    )
    sp.add_argument("--time-limit", type=float, default=900.0, help="wall seconds per case")
    sp.add_argument("--cells", type=int, default=64, help="cells across L")
    sp.add_argument("--jobs", type=int, default=2, help="cases run at once")
    sp.add_argument("--end-time", type=float, help="simulated time per case [s]")
    sp.add_argument("-o", "--output", default="docs/validation", help="report directory")
    sp.add_argument("--work-dir", help="keep the cases here")
    sp.add_argument("--quiet", action="store_true", help="no per-case messages")

    from foamsilo.analytic.cli import register
    from foamsilo.hopper.cli import register as register_hopper

    def add_json(sp: Any) -> None:
        sp.add_argument("--json", action="store_true", help="one JSON object on stdout")
        sp.set_defaults(func=cmd_analytic)

    register(sub, add_json)
    register_hopper(sub, add_json)

    bench = sub.add_parser(
        "bench",
        help="benchmarks and the validation suite",
        description="Benchmarks (speed, memory, error against run time) and "
        "the validation suite; results are written into docs/.",
    )
    forms = bench.add_subparsers(dest="suite", required=True, metavar="SUITE", parser_class=_Parser)

    def logged(sp: Any, default_log: str = "docs/benchmarks") -> None:
        sp.add_argument(
            "--log",
            default=default_log,
            help="directory of the JSON-lines logs the result is appended to ('' for none)",
        )
        sp.add_argument("--work-dir", help="keep the cases here")
        sp.add_argument("--quiet", action="store_true", help="no per-case messages")

    sp = add(
        forms,
        "validation",
        cmd_bench_validation,
        "the validation suite: error against run time, Beverloo scaling, the gas-assisted "
        "lab silo, stiff and extreme cases; checks with tolerances (exit 1 if one fails); "
        "issue 18's cost targets and the presets' default grids judged on its rows",
    )
    sp.add_argument("--quick", action="store_true", help="the reduced suite (bash scripts/test)")
    sp.add_argument(
        "--only",
        nargs="+",
        metavar="ENTRY",
        help="these entries only, or a part of one merged into the report in -o: "
        "work-precision/SERIES, presets/PRESET, 'time-step/LABEL' (one scene of "
        "suite.toml's [[time-step.cases]], quoted)",
    )
    sp.add_argument(
        "--values",
        nargs="+",
        type=float,
        metavar="N",
        help="with --only work-precision/NAME: these of its resolutions only (listed in "
        "suite.toml), their rows put into the series of the report in -o",
    )
    sp.add_argument("--jobs", type=int, default=2, help="cases run at once")
    sp.add_argument(
        "--time-limit",
        type=float,
        default=900.0,
        help="wall seconds per case (a preset's own longer limit in suite.toml applies to it)",
    )
    sp.add_argument("-o", "--output", default="docs/validation", help="report directory")
    sp.add_argument("--work-dir", help="keep the cases here")
    sp.add_argument("--quiet", action="store_true", help="no per-case messages")
    sp.add_argument(
        "--report-only",
        action="store_true",
        help="write the report again from the suite's JSON in the report directory (no runs)",
    )
    sp.add_argument(
        "--backend",
        choices=["local", "slurm"],
        default="local",
        help="local: --jobs cases at a time here; slurm: one batch job per case (with "
        "--work-dir on a shared filesystem; each job's --time is the longest case limit + 10 min)",
    )
    slurm_args(sp, time_limit=False)

    sp = add(
        forms,
        "verification",
        cmd_bench_verification,
        "code verification of the solver: steady layers down an inclined plane (the mu(I) "
        "Bagnold profile, plain and regularised, the Newtonian film at the cap) and pipe "
        "flow on the axisymmetric "
        "wedge, against their exact profiles, with the observed order of accuracy (exit 1 "
        "if a check fails)",
    )
    sp.add_argument("--quick", action="store_true", help="one grid per entry (quick_cells)")
    sp.add_argument("--only", nargs="+", metavar="ENTRY", help="these entries only")
    sp.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        default=[],
        help="scene override applied to every case (a lever to measure; report "
        "verification-set.md)",
    )
    sp.add_argument("-o", "--output", default="docs/validation", help="report directory")
    sp.add_argument("--work-dir", help="keep the cases here")
    sp.add_argument("--quiet", action="store_true", help="no per-case messages")

    d = defaults("solver")
    sp = add(forms, "solver", cmd_bench_solver, "cost and accuracy of the solver (planar silo)")
    sp.add_argument("--cells", nargs="+", type=int, default=d["cells"], help="cells across L")
    sp.add_argument("--end-time", type=float, default=d["end_time"], help="simulated time [s]")
    sp.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        default=[],
        help="scene override applied to every run (a lever to measure)",
    )
    sp.add_argument("--label", default="", help="name of this configuration in the log")
    sp.add_argument("--no-reference", action="store_true", help="skip the interFoam reference")
    logged(sp)

    d = defaults("gas")
    sp = add(forms, "gas", cmd_bench_gas, "cost of the pore-pressure solve against dry")
    sp.add_argument("--cells", type=int, default=d["cells"], help="cells across L")
    sp.add_argument("--end-time", type=float, default=d["end_time"], help="simulated time [s]")
    logged(sp)

    d = defaults("mesh")
    sp = add(forms, "mesh", cmd_bench_mesh, "meshing time and memory of a 3D cylinder")
    sp.add_argument("--cells", nargs="+", type=int, default=d["cells"], help="target cell counts")
    sp.add_argument("-o", "--output", help="write the Markdown table here")
    logged(sp)

    d = defaults("mpi")
    sp = add(forms, "mpi", cmd_bench_mpi, "MPI speed-up and the runner's overhead on a 3D silo")
    sp.add_argument("--ranks", nargs="+", type=int, default=d["ranks"], help="MPI rank counts")
    sp.add_argument("--cells", type=int, default=d["cells"], help="target cell count")
    sp.add_argument("--end-time", type=float, default=d["end_time"], help="simulated time [s]")
    sp.add_argument(
        "--repeats",
        type=int,
        default=d["repeats"],
        help="serial runs, direct and through the runner, alternated",
    )
    sp.add_argument("-o", "--output", help="write the Markdown tables here")
    logged(sp)

    d = defaults("post")
    sp = add(forms, "post", cmd_bench_post, "cost of `foamsilo post` on a 3D silo")
    sp.add_argument("--cells", type=int, default=d["cells"], help="target cell count")
    sp.add_argument("--times", type=int, default=d["times"], help="written times")
    sp.add_argument(
        "--write-interval",
        type=float,
        default=d["write_interval"],
        help="interval between written times [s]",
    )
    sp.add_argument("--ranks", type=int, default=d["ranks"], help="MPI ranks of the run")
    sp.add_argument("-o", "--output", help="write the Markdown table here")
    logged(sp)

    d = defaults("hopper")
    sp = add(forms, "hopper", cmd_bench_hopper, "error against wall time of the DG hopper solver")
    sp.add_argument("--cells", nargs="+", type=int, default=d["cells"], help="cells N")
    sp.add_argument("--figure", default=d["figure"], help="the work-precision plot")
    sp.add_argument("-o", "--output", help="write the Markdown table here")
    logged(sp)

    sp = add(forms, "report", cmd_bench_report, "the solver benchmark's tables, from its log")
    sp.add_argument("-o", "--output", help="write the Markdown here")
    sp.add_argument("--log", default="docs/benchmarks", help="directory of the logs")
    return p


# ----------------------------------------------------------------------------- main


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``foamsilo`` console script."""
    argv = list(sys.argv[1:] if argv is None else argv)
    json_mode = "--json" in argv
    if json_mode:
        # one JSON object on stdout, nothing else: stray prints go to stderr
        _JSON_OUT.append(sys.stdout)
        try:
            with contextlib.redirect_stdout(sys.stderr):
                return _call(argv, json_mode)
        finally:
            _JSON_OUT.pop()
    return _call(argv, json_mode)


def _report_error(exc: BaseException, json_mode: bool, internal: bool = False) -> None:
    from foamsilo.pipeline import error_payload

    if json_mode:
        out = _JSON_OUT[-1] if _JSON_OUT else sys.stdout
        out.write(dumps({"ok": False, "error": error_payload(exc)}) + "\n")
    if internal:
        traceback.print_exc(file=sys.stderr)
    if not json_mode or internal:
        sys.stderr.write(f"foamsilo: {'internal ' if internal else ''}error: {exc}\n")


def _call(argv: list[str], json_mode: bool) -> int:
    """Parse and run the command; every error becomes an exit code and a message (or JSON)."""
    try:
        args = build_parser().parse_args(argv)
        return int(args.func(args))
    except SystemExit as exc:  # --help and --version
        return int(exc.code or 0)
    except KeyboardInterrupt:
        _report_error(FoamsiloError("interrupted (Ctrl-C)"), json_mode)
        return 130
    except FoamsiloError as exc:
        _report_error(exc, json_mode)
        if isinstance(exc, InputError):
            return 2
        from foamsilo.slurm import JobsLeftQueuedError

        return 130 if isinstance(exc, (RunInterruptedError, JobsLeftQueuedError)) else 1
    except OSError as exc:  # a file or directory the system refused: say which
        where = f" ({exc.filename})" if exc.filename else ""
        _report_error(FoamsiloError(f"{exc.strerror or exc}{where}"), json_mode)
        return 1
    except Exception as exc:  # noqa: BLE001 -- a bug: still one JSON object, and the trace
        _report_error(exc, json_mode, internal=True)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
