"""The ``foamsilo`` command line.

Every command takes ``--json``: a single JSON object on stdout and nothing
else.  Without it the output is for people.  Exit status: 0 success,
1 failure (or, for ``doctor``, something missing), 2 bad input (the message
names the field and what is allowed).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from foamsilo import __version__
from foamsilo.errors import (
    DivergenceError,
    FoamError,
    FoamsiloError,
    MeshError,
    RunInterruptedError,
    SceneError,
    ToolchainError,
)

DEFAULT_RUNS_DIR = Path("runs")


# ----------------------------------------------------------------------------- output


def _console() -> Any:
    from rich.console import Console

    return Console(stderr=False, highlight=False)


#: Where --json output goes: the stdout of the call; everything else printed
#: meanwhile (PyFoam, OpenFOAM utilities run in-process) goes to stderr
_JSON_OUT: list[Any] = []


def _emit(args: argparse.Namespace, payload: dict[str, Any], human: Callable[[], None]) -> None:
    if args.json:
        out = _JSON_OUT[-1] if _JSON_OUT else sys.stdout
        out.write(json.dumps(payload, indent=2, default=_json_default) + "\n")
    else:
        human()


def _json_default(o: Any) -> Any:
    if isinstance(o, Path):
        return str(o)
    if isinstance(o, float) and not math.isfinite(o):
        return None
    return str(o)


def _error_payload(exc: BaseException) -> dict[str, Any]:
    err: dict[str, Any] = {"type": type(exc).__name__, "message": str(exc)}
    if isinstance(exc, SceneError):
        err["field"] = exc.field
    if isinstance(exc, ToolchainError):
        err.update(component=exc.component, fix=exc.fix)
    if isinstance(exc, FoamError):
        err.update(command=exc.command, returncode=exc.returncode, output=exc.output[-4000:])
    if isinstance(exc, DivergenceError):
        err.update(
            quantity=exc.quantity,
            time=exc.time,
            last_good_time=exc.last_good_time,
            case_dir=str(exc.case_dir),
        )
    if isinstance(exc, RunInterruptedError):
        err.update(time=exc.time, last_good_time=exc.last_good_time, case_dir=str(exc.case_dir))
    if isinstance(exc, MeshError) and exc.geometry_file:
        err["geometry_file"] = str(exc.geometry_file)
    return {"ok": False, "error": err}


# ----------------------------------------------------------------------------- helpers


def _load(spec: str, overrides: list[str] | None) -> tuple[Any, str | None]:
    """Scene from a preset or file; also the file text to copy into the case."""
    from foamsilo.scene import load_scene

    scene = load_scene(spec, overrides)
    p = Path(spec)
    text = None
    if p.exists() and not overrides:
        text = p.read_text()
    return scene, text


def _progress_printer(quiet: bool) -> tuple[Callable[..., None] | None, Callable[[], None]]:
    """Make a progress callback on stderr (simulated time, dt, Courant, ETA)."""
    if quiet or not sys.stderr.isatty():
        return None, lambda: None
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    prog = Progress(
        TextColumn("[bold]siloFoam"),
        BarColumn(),
        TextColumn("t = {task.fields[t]:.4g} / {task.total:.4g} s"),
        TextColumn("dt {task.fields[dt]:.2e}"),
        TextColumn("Co {task.fields[co]:.2f} (grains {task.fields[gco]:.2f})"),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=True,
    )
    state: dict[str, Any] = {"task": None, "last": 0.0}

    def update(monitor: Any, end_time: float) -> None:
        now = time.monotonic()
        if now - state["last"] < 0.2:
            return
        state["last"] = now
        s = monitor.steps[-1]
        if state["task"] is None:
            prog.start()
            state["task"] = prog.add_task("run", total=end_time, t=0.0, dt=0.0, co=0.0, gco=0.0)
        prog.update(
            state["task"],
            completed=s.time,
            t=s.time,
            dt=s.delta_t,
            co=s.courant,
            gco=s.granular_courant,
        )

    def stop() -> None:
        if state["task"] is not None:
            prog.stop()

    return update, stop


def _is_case_dir(p: Path) -> bool:
    from foamsilo.case import METADATA_FILE

    return (p / METADATA_FILE).exists()


def _run_finished(case: Path) -> bool:
    from foamsilo.run import _control_value, time_directories

    times = time_directories(case)
    if not times:
        return False
    end = _control_value(case, "endTime")
    return float(times[-1]) >= end * (1 - 1e-9) and (case / "log.siloFoam").exists()


def _run_started(case: Path) -> str | None:
    """Latest complete time directory after 0 of an unfinished run, or None."""
    from foamsilo.run import time_directories

    later = [t for t in time_directories(case) if float(t) > 0]
    return later[-1] if later else None


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
            h = report["headers"]
            t.add_row(
                "headers + wmake",
                "ok" if h["found"] else "[red]missing",
                str(h["source_dir"] or ""),
            )
            s = report["solver"]
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
            con.print(f"[bold]{it['name']:<16}[/] {it['description']}")

    _emit(args, {"ok": True, "presets": items}, human)
    return 0


def cmd_new(args: argparse.Namespace) -> int:
    """Write a case (dictionaries, mesh, initial fill)."""
    from foamsilo.case import create_case
    from foamsilo.toolchain import find_openfoam

    scene, text = _load(args.scene, args.set)
    case = create_case(
        scene,
        Path(args.output),
        find_openfoam(),
        overwrite=args.overwrite,
        scene_text=text,
        dump_geometry=args.dump_geometry,
    )
    payload = {"ok": True, **case.as_dict()}

    def human() -> None:
        con = _console()
        con.print(
            f"wrote case [bold]{case.path}[/] ({case.representation}, "
            f"{case.mesh.cells if case.mesh else '?'} cells, {len(case.files)} files)"
        )
        con.print(f"run it: foamsilo run {case.path}")

    _emit(args, payload, human)
    return 0


def cmd_mesh(args: argparse.Namespace) -> int:
    """Mesh a scene and report checkMesh's verdict and figures."""
    from foamsilo.case import create_case
    from foamsilo.toolchain import find_openfoam

    scene, text = _load(args.scene, args.set)
    of = find_openfoam()
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

    con = _console()
    log = None if args.json else (lambda m: con.print(m))
    build = ensure_solver(force=not args.if_needed, log=log)
    payload = {
        "ok": True,
        "executable": str(build.executable),
        "library": str(build.library),
        **build.info,
    }
    _emit(args, payload, lambda: con.print(f"siloFoam: {build.executable}"))
    return 0


def _print_summary(summary: dict[str, Any], run: dict[str, Any] | None) -> None:
    from rich.table import Table

    con = _console()
    t = Table(
        title=f"{summary['scene']} ({summary['representation']}, "
        f"{summary['cells_across']} cells across L, {summary['cells']} cells)"
    )
    t.add_column("quantity")
    t.add_column("value", justify="right")
    if summary["steady"]:
        scale = summary["flow_rate_scale"]["name"]
        t.add_row("steady Q", f"{summary['Q']:.5g} {summary['Q_units']}")
        t.add_row(
            f"Q/({scale}), orifice flux",
            f"{summary['Q_dimensionless']:.4f} +- {summary['Q_std_dimensionless']:.4f}",
        )
        t.add_row(f"Q/({scale}), volume decrease", f"{summary['Q_from_volume_dimensionless']:.4f}")
        w = summary["steady_window_s"]
        t.add_row("steady window", f"{w[0]:.3g} - {w[1]:.3g} s")
        ref = summary.get("reference")
        if ref and ref.get("rel_diff") is not None:
            # planar: the paper's converged value and its spread; else an analytic law
            spread = f" +- {ref['spread']:.2f}" if "spread" in ref else ""
            t.add_row(
                ref.get("source", "reference"),
                f"{ref['Q_dimensionless']:.3f}{spread} ({ref['rel_diff']:+.1%})",
            )
        bev = summary.get("beverloo_2d")
        if bev:
            t.add_row(
                f"2D Beverloo, C = {bev['C']:.2f}",
                f"{bev['Q_dimensionless']:.4f} ({bev['rel_diff']:+.1%})",
            )
    else:
        t.add_row("steady", f"[red]no[/]: {summary['steady_reason']}")
    t.add_row("mass balance error", f"{summary['mass_balance_rel_error']:.1e}")
    if run:
        t.add_row(
            "solver wall / CPU time",
            f"{run['wall_seconds']:.1f} s / {run['cpu_seconds']:.1f} s ({run['steps']} steps)",
        )
    con.print(t)
    con.print(f"files: {summary['case_dir']}/discharge.csv, discharge.png, summary.json")


def cmd_run(args: argparse.Namespace) -> int:
    """Create (if needed), run and post-process a case."""
    from foamsilo.case import SCENE_FILE, create_case, read_metadata, scene_digest, write_whole
    from foamsilo.post import summarize
    from foamsilo.run import reconstruct, run_solver
    from foamsilo.scene import load_scene_file
    from foamsilo.solver import ensure_solver
    from foamsilo.toolchain import find_openfoam

    if args.np is not None and args.np < 1:
        raise SceneError("--np", f"{args.np} ranks: must be >= 1")
    if args.hostfile is not None and not args.hostfile.is_file():
        raise FoamsiloError(f"--hostfile {args.hostfile}: no such file")
    of = find_openfoam()
    spec = Path(args.scene)
    con = _console()
    say = (lambda m: None) if args.json or args.quiet else (lambda m: con.print(m))
    if spec.is_dir() and _is_case_dir(spec):
        if args.set:
            raise SceneError("--set", "cannot change an existing case; make a new one")
        case_dir = spec.resolve()
    else:
        scene, text = _load(args.scene, args.set)
        case_dir = Path(args.output or DEFAULT_RUNS_DIR / scene.name).resolve()
        reuse = False
        replace = args.overwrite
        if _is_case_dir(case_dir) and not args.overwrite:
            if read_metadata(case_dir).get("scene_digest") != scene_digest(scene):
                if not args.update:
                    raise FoamsiloError(
                        f"{case_dir} holds a case of a different scene "
                        "(use --update to replace it, --overwrite, or another -o)"
                    )
                say(f"{case_dir} holds an older version of the scene: replacing it")
                replace = True
            else:
                reuse = True
        if not reuse:
            say(f"writing case {case_dir}")
            create_case(scene, case_dir, of, overwrite=replace, scene_text=text)
        else:
            say(f"using existing case {case_dir}")
    run_info = None
    if _run_finished(case_dir) and not args.rerun:
        say("run already finished; post-processing")
    else:
        started = _run_started(case_dir)
        if started and not (args.resume or args.rerun):
            raise FoamsiloError(
                f"{case_dir} holds an interrupted run (latest complete time {started} s): "
                "--resume continues it, --overwrite starts over"
            )
        n_procs = args.np or load_scene_file(case_dir / SCENE_FILE).run.n_procs
        build = ensure_solver(of=of, log=say)
        if started:
            say(f"resuming from t = {started} s")
        update, stop = _progress_printer(args.quiet or args.json)
        try:
            result = run_solver(
                case_dir, of, build, progress=update, n_procs=n_procs, hostfile=args.hostfile
            )
        finally:
            stop()
        if args.reconstruct and n_procs > 1:
            say("reconstructing the processor directories")
            reconstruct(case_dir, of)
        run_info = result.as_dict()
        write_whole(case_dir / "run.json", json.dumps(run_info, indent=2))
    if run_info is None and (case_dir / "run.json").exists():
        run_info = json.loads((case_dir / "run.json").read_text())
    summary = summarize(case_dir, run_info)
    _emit(args, {"ok": True, **summary}, lambda: _print_summary(summary, run_info))
    return 0


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run a sweep file's cases under its CPU budget; resumable."""
    from foamsilo.sweep import load_sweep, run_sweep

    sweep = load_sweep(Path(args.sweep))
    say = (lambda m: None) if args.json or args.quiet else (lambda m: _console().print(m))
    rows = run_sweep(sweep, log=say)
    failed = [r for r in rows if r["status"] != "ok"]

    def human() -> None:
        from rich.table import Table

        # the columns that vary between cases
        keys = [
            k
            for k in (sweep.cases[0].overrides if sweep.cases else {})
            if len({repr(c.overrides.get(k)) for c in sweep.cases}) > 1
        ]
        tab = Table(title=f"sweep {sweep.name} ({sweep.output}/summary.csv)")
        for k in ["case", *keys, "status", "Q", "Q_dimensionless"]:
            tab.add_column(k)
        for r in rows:
            q = r.get("Q")
            qd = r.get("Q_dimensionless")
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


def cmd_post(args: argparse.Namespace) -> int:
    """Post-process a case: Q(t), steady Q, mass balance, plot."""
    from foamsilo.post import summarize

    case = Path(args.case).resolve()
    run_info = None
    if (case / "run.json").exists():
        run_info = json.loads((case / "run.json").read_text())
    summary = summarize(case, run_info)
    _emit(args, {"ok": True, **summary}, lambda: _print_summary(summary, run_info))
    return 0


def cmd_compare(args: argparse.Namespace) -> int:
    """Set a case's or sweep's steady rates on the analytic curves."""
    from foamsilo.compare import compare
    from foamsilo.report import sweep_report

    target = Path(args.target).resolve()
    result = compare(target)
    if result["kind"] == "sweep":
        result["report"] = str(sweep_report(target))

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


def _bench_out(args: argparse.Namespace, res: dict[str, Any], text: str, log_name: str) -> int:
    """Append a benchmark's record to its log, write its table, print it."""
    from foamsilo.bench import write_result

    if args.log:
        write_result(res, Path(args.log).with_name(log_name))
    if args.output:
        Path(args.output).write_text(text + "\n")
    _emit(args, {"ok": True, **res}, lambda: sys.stdout.write(text + "\n"))
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    """Run a benchmark and append its result to the log in docs/."""
    from foamsilo.bench import bench_solver, solver_table, write_result

    if args.suite == "report":
        from foamsilo.bench import read_log, solver_report

        text = solver_report(read_log(Path(args.log)))
        if args.output:
            Path(args.output).write_text(text + "\n")
        _emit(args, {"ok": True, "markdown": text}, lambda: sys.stdout.write(text + "\n"))
        return 0
    if args.suite == "validation":
        from foamsilo.suite import run_suite

        with tempfile.TemporaryDirectory(prefix="foamsilo-suite-") as tmp:
            work = Path(args.work_dir) if args.work_dir else Path(tmp)
            res = run_suite(args.quick, Path(args.output or "docs/validation"), work,
                            args.only or None, jobs=args.jobs)  # fmt: skip
        failed = [c for c in res["checks"] if not c["passed"]]

        def human_suite() -> None:
            con = _console()
            for c in res["checks"]:
                mark = "pass" if c["passed"] else "FAIL"
                con.print(f"{mark}  {c['entry']}: {c['name']} = {c['value']} "
                          f"(allowed [{c['low']:g}, {c['high']:g}])")  # fmt: skip
            stem = "suite-quick" if args.quick else "suite"
            con.print(f"report: {args.output or 'docs/validation'}/{stem}.md")

        _emit(args, {"ok": not failed, **res}, human_suite)
        return 1 if failed else 0
    if args.suite == "hopper":
        from foamsilo.hopper.figures import (
            plot_work_precision,
            work_precision,
            work_precision_markdown,
        )

        cells = (
            (25, 50, 100, 200, 400) if args.cells == ["32", "64"] else tuple(map(int, args.cells))
        )
        res = work_precision(cells=cells)
        from foamsilo.bench import _git_commit, machine_info

        res["commit"], res["machine"] = _git_commit(), machine_info()
        figure = Path(args.figure)
        figure.parent.mkdir(parents=True, exist_ok=True)
        plot_work_precision(res, figure)
        return _bench_out(args, res, work_precision_markdown(res), "hopper.jsonl")
    if args.suite == "post":
        from foamsilo.bench import bench_post, post_report

        default = args.cells == ["32", "64"]
        with tempfile.TemporaryDirectory(prefix="foamsilo-bench-") as tmp:
            work = Path(args.work_dir) if args.work_dir else Path(tmp)
            res = bench_post(65000 if default else int(args.cells[0]), args.times, work)
        return _bench_out(args, res, post_report(res), "post.jsonl")
    if args.suite in ("mesh", "mpi"):
        from foamsilo.bench import bench_mesh, bench_mpi, mesh_report, mpi_report

        default = args.cells == ["32", "64"]
        with tempfile.TemporaryDirectory(prefix="foamsilo-bench-") as tmp:
            work = Path(args.work_dir) if args.work_dir else Path(tmp)
            if args.suite == "mesh":
                targets = [64800, 1000000] if default else [int(c) for c in args.cells]
                res = bench_mesh(targets, work)
            else:
                end = args.end_time if args.end_time != 1.0 else 0.02
                target = 65000 if default else int(args.cells[0])
                res = bench_mpi([int(r) for r in args.ranks], target, end, work)
        text = (mesh_report if args.suite == "mesh" else mpi_report)(res)
        if args.log:
            write_result(res, Path(args.log).with_name(f"{args.suite}.jsonl"))
        if args.output:
            Path(args.output).write_text(text + "\n")
        _emit(args, {"ok": True, **res}, lambda: sys.stdout.write(text + "\n"))
        return 0
    cells = [int(c) for c in args.cells]
    if args.suite == "gas":
        from foamsilo.bench import bench_gas

        with tempfile.TemporaryDirectory(prefix="foamsilo-bench-") as tmp:
            res = bench_gas(cells[0], args.end_time, Path(tmp))
        if args.log:
            write_result(res, Path(args.log).with_name("gas.jsonl"))

        def human_gas() -> None:
            con = _console()
            for label, r in res["rows"].items():
                con.print(f"{label:>40}: {r['ms_per_step']:.2f} ms/step ({r['steps']} steps), "
                          f"ratio to dry {r['ratio_to_dry']:.2f}")  # fmt: skip

        _emit(args, {"ok": True, **res}, human_gas)
        return 0
    with tempfile.TemporaryDirectory(prefix="foamsilo-bench-") as tmp:
        work = Path(args.work_dir) if args.work_dir else Path(tmp)
        result = bench_solver(
            cells,
            args.end_time,
            work,
            overrides=args.set,
            reference=not args.no_reference,
            keep=args.work_dir is not None,
        )
    result["label"] = args.label
    if args.log:
        write_result(result, Path(args.log))

    def human() -> None:
        con = _console()
        m = result["machine"]
        con.print(
            f"solver benchmark ({args.label or 'current'}), {m['cpu']} x{m['cores']}, "
            f"commit {result['commit']}, end time {args.end_time} s"
        )
        con.print(solver_table(result))

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


def cmd_validate(args: argparse.Namespace) -> int:
    """Reproduce a seed paper's simulations and write the report into docs/."""
    from foamsilo.validation import gas_extremes, zhou_gas

    with tempfile.TemporaryDirectory(prefix="foamsilo-validate-") as tmp:
        work = Path(args.work_dir) if args.work_dir else Path(tmp)
        if args.suite == "gas-extremes":
            report = gas_extremes(args.cells, work, Path(args.output), jobs=args.jobs,
                                  limit=args.time_limit)  # fmt: skip
            _emit(args, {"ok": True, **report}, lambda: _console().print(
                "\n".join(f"{r['label']}: {r['outcome']}" for r in report["rows"])))  # fmt: skip
            return 0
        report = zhou_gas(args.cells, work, Path(args.output), jobs=args.jobs,
                          end_time=args.end_time)  # fmt: skip

    def human() -> None:
        _console().print(
            f"Zhou Fig. 4b: rms difference to eq. 23 (A = 0.68) "
            f"{report['rms_rel_diff_A068']:.1%}; Fig. 6b zone slope "
            f"{report['fig6b_slope_zone']:.3f}; report in {args.output}/zhou-gas-planar.md"
        )

    _emit(args, {"ok": True, **report}, human)
    return 0


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
    out = ["# Command-line reference", "", "Generated from `foamsilo/cli.py`: "
           "`foamsilo cli-reference > docs/cli.md`.", ""]  # fmt: skip
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sp in sub.choices.items():
        out += [f"## foamsilo {name}", "", "```text", sp.format_help().rstrip(), "```", ""]
        nested = [a for a in sp._actions if isinstance(a, argparse._SubParsersAction)]
        for group in nested:
            for form, fp in group.choices.items():
                out += [f"### foamsilo {name} {form}", "", "```text", fp.format_help().rstrip(),
                        "```", ""]  # fmt: skip
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


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser (also used to document the CLI)."""
    p = argparse.ArgumentParser(
        prog="foamsilo",
        description="OpenFOAM simulations of granular silo discharge, and their cross-checks.",
    )
    p.add_argument("--version", action="version", version=f"foamsilo {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def add(name: str, func: Callable[[argparse.Namespace], int], help_: str) -> Any:
        sp = sub.add_parser(name, help=help_, description=help_)
        sp.add_argument("--json", action="store_true", help="one JSON object on stdout")
        sp.set_defaults(func=func)
        return sp

    def scene_args(sp: Any) -> None:
        sp.add_argument("scene", help="preset name or scene TOML file")
        sp.add_argument(
            "--set",
            action="append",
            metavar="KEY=VALUE",
            default=[],
            help="override a scene value, e.g. mesh.cells_across=32 (repeatable)",
        )

    add("doctor", cmd_doctor, "report what OpenFOAM, headers, solver, gmsh and MPI are found")
    add("presets", cmd_presets, "list the named scenes of the papers")

    sp = add("new", cmd_new, "write a ready-to-run case for a scene")
    scene_args(sp)
    sp.add_argument("-o", "--output", required=True, help="case directory to write")
    sp.add_argument("--overwrite", action="store_true", help="replace an existing case")
    sp.add_argument(
        "--dump-geometry",
        type=Path,
        metavar="FILE",
        help="also write the gmsh geometry (.geo_unrolled, .brep)",
    )

    sp = add("mesh", cmd_mesh, "mesh a scene and report the checkMesh verdict")
    scene_args(sp)
    sp.add_argument("-o", "--output", help="keep the meshed case here")
    sp.add_argument("--overwrite", action="store_true", help="replace an existing case")
    sp.add_argument(
        "--dump-geometry", type=Path, metavar="FILE", help="write the gmsh geometry for inspection"
    )

    sp = add("run", cmd_run, "run a scene (or a case directory) and post-process it")
    sp.add_argument("scene", help="preset name, scene TOML file, or case directory")
    sp.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        default=[],
        help="override a scene value (repeatable)",
    )
    sp.add_argument("-o", "--output", help=f"case directory (default {DEFAULT_RUNS_DIR}/<name>)")
    sp.add_argument("--overwrite", action="store_true", help="replace an existing case")
    sp.add_argument(
        "--update",
        action="store_true",
        help="replace the case if it holds another scene; reuse it if it holds this one",
    )
    sp.add_argument(
        "--rerun", action="store_true", help="run the solver even if the case already finished"
    )
    sp.add_argument(
        "--resume",
        action="store_true",
        help="continue an interrupted run from its latest complete time directory",
    )
    sp.add_argument(
        "--np", type=int, default=None, help="MPI ranks (default: the scene's run.n_procs)"
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
    sp.add_argument("--quiet", action="store_true", help="no progress bar")

    sp = add("sweep", cmd_sweep, "run the cases of a sweep file under a CPU budget (resumable)")
    sp.add_argument("sweep", help="sweep TOML file (see foamsilo/sweep.py for the format)")
    sp.add_argument("--quiet", action="store_true", help="no per-case messages")

    sp = add("post", cmd_post, "post-process a case: Q(t), steady Q, fields, pictures, report")
    sp.add_argument("case", help="case directory")

    sp = add("compare", cmd_compare, "simulation points on the analytic curves, with errors")
    sp.add_argument("target", help="case directory, or a sweep's output directory")

    add("build-solver", cmd_build_solver, "build siloFoam and its mu(I) library").add_argument(
        "--if-needed", action="store_true", help="only if the sources changed"
    )
    add("scene-reference", cmd_scene_reference, "print the scene-file reference (Markdown)")
    add("cli-reference", cmd_cli_reference, "print this command-line reference (Markdown)")

    sp = add("validate", cmd_validate, "reproduce a seed paper's simulations (report in docs/)")
    sp.add_argument(
        "suite",
        choices=["zhou-gas", "gas-extremes"],
        help="zhou-gas: Zhou et al. 2019 sec. III.B, Figs 4b-6b; gas-extremes: stiff and "
        "extreme gas cases in the lab silo",
    )
    sp.add_argument("--time-limit", type=float, default=900.0, help="wall seconds per case")
    sp.add_argument("--cells", type=int, default=64, help="cells across L")
    sp.add_argument("--jobs", type=int, default=2, help="cases run at once")
    sp.add_argument("--end-time", type=float, help="simulated time per case [s]")
    sp.add_argument("-o", "--output", default="docs/validation", help="report directory")
    sp.add_argument("--work-dir", help="keep the cases here")

    from foamsilo.analytic.cli import register
    from foamsilo.hopper.cli import register as register_hopper

    def add_json(sp: Any) -> None:
        sp.add_argument("--json", action="store_true", help="one JSON object on stdout")
        sp.set_defaults(func=cmd_analytic)

    register(sub, add_json)
    register_hopper(sub, add_json)

    sp = add("bench", cmd_bench, "run a benchmark (solver: cost and accuracy on the planar silo)")
    sp.add_argument(
        "suite",
        nargs="?",
        default="validation",
        choices=["validation", "solver", "gas", "mesh", "mpi", "post", "hopper", "report"],
        help="validation (default): the validation suite (error against run time, Beverloo "
        "scaling, stiff and extreme cases; --quick: the reduced suite with its checks, exit 1 "
        "when a figure leaves its tolerance; report in --output, default docs/validation); "
        "solver: cost and accuracy; gas: pore-pressure cost against dry; mesh: meshing "
        "time and memory of a 3D cylinder (--cells: target cell counts, default 64800 "
        "1000000); mpi: speed-up over --ranks and the runner's overhead on a 3D silo "
        "(--cells: target cells, default 65000; --end-time default 0.02 s); post: cost of "
        "`foamsilo post` on a 3D silo of --cells (default 65000) with --times written times; "
        "hopper: error against wall time of the DG hopper solver, k = 0, 1, 2 over --cells "
        "(default 25 50 100 200 400), plot in --figure; "
        "report: tables from --log",
    )
    sp.add_argument("--ranks", nargs="+", default=["1", "2"], help="mpi: MPI rank counts")
    sp.add_argument("--times", type=int, default=100, help="post: written times")
    sp.add_argument("--quick", action="store_true", help="validation: the reduced suite")
    sp.add_argument("--only", nargs="+", help="validation: these entries only")
    sp.add_argument("--jobs", type=int, default=2, help="validation: cases run at once")
    sp.add_argument(
        "--figure",
        default="docs/hopper/hopper-work-precision.png",
        help="hopper: the work-precision plot",
    )
    sp.add_argument("-o", "--output", help="report: write the Markdown here")
    sp.add_argument("--cells", nargs="+", default=["32", "64"], help="cells across L")
    sp.add_argument("--end-time", type=float, default=1.0, help="simulated time per run [s]")
    sp.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        default=[],
        help="scene override applied to every run (a lever to measure)",
    )
    sp.add_argument("--label", default="", help="name of this configuration in the log")
    sp.add_argument(
        "--log",
        default="docs/benchmarks/solver.jsonl",
        help="JSON-lines log the result is appended to ('' for none)",
    )
    sp.add_argument("--no-reference", action="store_true", help="skip the interFoam reference")
    sp.add_argument("--work-dir", help="keep the cases here")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``foamsilo`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "json", False):
        # one JSON object on stdout, nothing else: stray prints go to stderr
        _JSON_OUT.append(sys.stdout)
        try:
            with contextlib.redirect_stdout(sys.stderr):
                return _call(args)
        finally:
            _JSON_OUT.pop()
    return _call(args)


def _call(args: argparse.Namespace) -> int:
    """Run the command; errors become exit codes (and a JSON error object with --json)."""
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        sys.stderr.write("interrupted\n")
        return 130
    except FoamsiloError as exc:
        code = (
            2 if isinstance(exc, SceneError) else 130 if isinstance(exc, RunInterruptedError) else 1
        )
        if getattr(args, "json", False):
            out = _JSON_OUT[-1] if _JSON_OUT else sys.stdout
            out.write(json.dumps(_error_payload(exc), indent=2, default=_json_default) + "\n")
        else:
            sys.stderr.write(f"foamsilo: error: {exc}\n")
        return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
