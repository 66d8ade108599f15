"""Benchmarks: ``foamsilo bench solver|gas|mesh|mpi|post|hopper|report``.

Speed and memory, measured on real runs and written as tables into
``docs/benchmarks/`` (a JSON-lines log per suite, a Markdown table from it).
Each suite's defaults (scenes, resolutions, times) are data,
``foamsilo/studies/bench.toml``; every case is made and run through the
pipeline. ``foamsilo bench solver`` also times one step of stock
``interFoam`` with a Newtonian fluid on the same mesh, so that figures taken
on different days (or machines) can be compared as ratios.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import statistics
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from foamsilo.case import read_metadata
from foamsilo.case.times import is_time_name
from foamsilo.errors import FoamsiloError, SceneError
from foamsilo.foam import edit_dict
from foamsilo.mesh import cells_estimate
from foamsilo.pipeline import CaseSpec, Say, prepare, reduce, run, run_case
from foamsilo.process import run_command
from foamsilo.run import ProgressCallback, prepare_decomposition
from foamsilo.scene import load_preset
from foamsilo.solver import ensure_solver
from foamsilo.studies.cases import git_commit, machine_info, overrides, study_table
from foamsilo.toolchain import OpenFOAM, find_openfoam


def _quiet(_: str) -> None:
    pass


REFERENCE_STEPS = 60


def defaults(suite: str) -> dict[str, Any]:
    """Return the defaults of a benchmark suite (``bench.toml``)."""
    return dict(study_table("bench")[suite])


@dataclass
class SolverBenchRow:
    """One benchmark run."""

    cells_across: int
    cells: int
    simulated_s: float
    steps: int
    cpu_s: float
    wall_s: float
    cpu_s_per_simulated_s: float
    ms_per_step: float
    steps_per_simulated_s: float
    cell_steps_per_cpu_s: float
    peak_memory_mb: float | None
    q_dimensionless: float | None
    q_from_volume_dimensionless: float | None
    mass_balance_rel_error: float
    interfoam_ms_per_step: float | None
    ratio_to_interfoam: float | None


def interfoam_ms_per_step(
    case: Path, of: OpenFOAM, delta_t: float, steps: int = REFERENCE_STEPS
) -> float:
    """Time one step of stock interFoam, Newtonian fluid, on ``case``'s mesh.

    The granular phase is replaced by a Newtonian fluid of the same density
    and kinematic viscosity 1e-6 m^2/s; the run starts from the initial fill
    with a fixed time step.  The first tenth of the steps is not counted.
    """
    from PyFoam.Basics.DataStructures import DictProxy

    ref = case.parent / f"{case.name}.interFoam"
    if ref.exists():
        shutil.rmtree(ref)
    ref.mkdir()
    for d in ("system", "constant", "0"):
        shutil.copytree(case / d, ref / d)
    with edit_dict(ref / "constant" / "transportProperties") as tp:
        for phase in tp["phases"]:
            block = tp[phase]
            if str(block.get("transportModel")) == "muI":
                block["transportModel"] = "Newtonian"
                del block["muICoeffs"]
                block["nu"] = 1e-06
    with edit_dict(ref / "system" / "fvSolution") as fs:
        pcorr = DictProxy()
        for k, v in (
            ("solver", "PCG"),
            ("preconditioner", "DIC"),
            ("tolerance", 1e-8),
            ("relTol", 0),
        ):
            pcorr[k] = v
        fs["solvers"]['"pcorr.*"'] = pcorr
    with edit_dict(ref / "system" / "controlDict") as cd:
        del cd["functions"]
        for k, v in (
            ("application", "interFoam"),
            ("adjustTimeStep", "no"),
            ("deltaT", delta_t),
            ("endTime", delta_t * steps),
            ("writeControl", "timeStep"),
            ("writeInterval", steps),
        ):
            cd[k] = v
    res = run_command([str(of.appbin / "interFoam"), "-case", str(ref)], env=of.runtime_env())
    times = [
        float(ln.split()[2]) for ln in res.output.splitlines() if ln.startswith("ExecutionTime = ")
    ]
    shutil.rmtree(ref, ignore_errors=True)
    if res.returncode != 0 or len(times) < steps // 2:
        raise FoamsiloError(f"interFoam reference failed:\n{res.output[-2000:]}")
    skip = max(1, len(times) // 10)
    return 1000 * (times[-1] - times[skip - 1]) / (len(times) - skip)


def _planar_spec(work: Path, name: str, preset: str, sets: list[str]) -> CaseSpec:
    return CaseSpec(Path(work) / name, preset, tuple(sets), overwrite=True, label=name)


def bench_solver(
    cells: list[int],
    end_time: float,
    work_dir: Path,
    extra: list[str] | None = None,
    reference: bool = True,
    keep: bool = False,
    say: Say = _quiet,
    progress: ProgressCallback | None = None,
) -> dict[str, Any]:
    """Run the solver benchmark on the planar silo (one run at a time, serial).

    Parameters
    ----------
    cells
        Resolutions (cells across L).
    end_time
        Simulated time of each run [s].
    work_dir
        Where the cases are written.
    extra
        Extra ``--set`` scene overrides (a lever to measure).
    reference
        Also time stock interFoam on the same mesh.
    keep
        Keep the cases.
    say
        Where one line per finished run goes (progress).
    progress
        The running case's progress (simulated time, ETA), as ``run_case`` takes it.
    """
    commit = git_commit()  # before the runs (git_commit)
    preset, base = defaults("solver")["preset"], overrides(defaults("solver").get("set"))
    of = find_openfoam()
    rows = []
    for n in cells:
        sets = [
            *base,
            f"mesh.cells_across={n}",
            f"run.end_time={end_time}",
            f"run.write_interval={end_time / 4}",
            *(extra or []),
        ]
        spec = _planar_spec(work_dir, f"planar-{n}", preset, sets)
        summary = run_case(spec, of=of, progress=progress)
        s = summary.as_json()
        r = s["run"]
        simulated = r["end_time"] - r["start_time"]
        ms = 1000 * r["cpu_seconds"] / r["steps"]
        ref_ms = None
        if reference:
            ref_ms = interfoam_ms_per_step(summary.case, of, delta_t=end_time / r["steps"])
        rows.append(
            SolverBenchRow(
                cells_across=n,
                cells=int(s["cells"] or 0),
                simulated_s=simulated,
                steps=r["steps"],
                cpu_s=r["cpu_seconds"],
                wall_s=r["wall_seconds"],
                cpu_s_per_simulated_s=r["cpu_seconds"] / simulated,
                ms_per_step=ms,
                steps_per_simulated_s=r["steps"] / simulated,
                cell_steps_per_cpu_s=int(s["cells"] or 0) * r["steps"] / r["cpu_seconds"],
                peak_memory_mb=r["max_rss_mb"],
                q_dimensionless=s["Q_dimensionless"],
                q_from_volume_dimensionless=s["Q_from_volume_dimensionless"],
                mass_balance_rel_error=s["mass_balance_rel_error"],
                interfoam_ms_per_step=ref_ms,
                ratio_to_interfoam=ms / ref_ms if ref_ms else None,
            )
        )
        say(f"{len(rows)}/{len(cells)} done: {n} across, {ms:.3g} ms per step")
        if not keep:
            shutil.rmtree(summary.case, ignore_errors=True)
    return {
        "benchmark": "solver",
        "scene": preset,
        "end_time_s": end_time,
        "overrides": list(extra or []),
        "machine": machine_info(),
        "commit": commit,
        "rows": [asdict(r) for r in rows],
    }


def solver_table(result: dict[str, Any]) -> str:
    """Markdown table of a solver benchmark."""

    def f(v: Any, fmt: str) -> str:
        return "-" if v is None else format(v, fmt)

    lines = [
        "| cells across | cells | steps | CPU-s / sim-s | ms / step | steps / sim-s "
        "| cell-steps / CPU-s | peak MB | Q/(ρ√(gL³)) | from volume | mass balance "
        "| interFoam ms / step | ratio |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in result["rows"]:
        lines.append(
            f"| {r['cells_across']} | {r['cells']} | {r['steps']} "
            f"| {f(r['cpu_s_per_simulated_s'], '.1f')} | {f(r['ms_per_step'], '.2f')} "
            f"| {f(r['steps_per_simulated_s'], '.0f')} | {f(r['cell_steps_per_cpu_s'], '.3g')} "
            f"| {f(r['peak_memory_mb'], '.0f')} | {f(r['q_dimensionless'], '.4f')} "
            f"| {f(r['q_from_volume_dimensionless'], '.4f')} "
            f"| {f(r['mass_balance_rel_error'], '.1e')} "
            f"| {f(r['interfoam_ms_per_step'], '.2f')} | {f(r['ratio_to_interfoam'], '.1f')} |"
        )
    return "\n".join(lines)


def write_result(result: dict[str, Any], path: Path) -> None:
    """Append a benchmark result to a JSON-lines log (whole lines only)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as fh:
        fh.write(json.dumps(result) + "\n")


def read_log(path: Path) -> list[dict[str, Any]]:
    """All results of a JSON-lines benchmark log, oldest first."""
    if not Path(path).exists():
        return []
    return [json.loads(ln) for ln in Path(path).read_text().splitlines() if ln.strip()]


def solver_report(results: list[dict[str, Any]]) -> str:
    """Markdown report of solver benchmark results: one table per configuration."""
    out = ["<!-- generated by `foamsilo bench report`; do not edit -->", ""]
    for r in results:
        m = r["machine"]
        cmd = "foamsilo bench solver --cells " + " ".join(
            str(row["cells_across"]) for row in r["rows"]
        )
        cmd += f" --end-time {r['end_time_s']:g}"
        cmd += "".join(f" --set {o}" for o in r.get("overrides", []))
        out += [
            f"### {r.get('label') or 'unlabelled'}",
            "",
            f"`{cmd}`  ",
            f"{m['date']}, commit {r.get('commit')}, {m['cpu']} ({m['cores']} cores), "
            f"one core per run, foamsilo {m['foamsilo']}",
            "",
            solver_table(r),
            "",
        ]
    return "\n".join(out)


def bench_gas(
    cells: int,
    end_time: float,
    work_dir: Path,
    say: Say = _quiet,
    progress: ProgressCallback | None = None,
) -> dict[str, Any]:
    """Cost of a time step with the pore-pressure solve against the same case dry.

    The cases of ``bench.toml`` [gas] (dry, Darcy, Darcy-Forchheimer), same
    mesh, run one after the other.
    """
    commit = git_commit()  # before the runs (git_commit)
    d = defaults("gas")
    of = find_openfoam()
    rows = {}
    for i, case in enumerate(d["cases"]):
        sets = [
            f"mesh.cells_across={cells}",
            f"run.end_time={end_time}",
            f"run.write_interval={end_time / 2}",
            *overrides(case["set"]),
        ]
        spec = _planar_spec(work_dir, f"gas-{i}", d["preset"], sets)
        summary = run_case(spec, of=of, progress=progress)
        r = summary.as_json()["run"]
        rows[case["label"]] = {
            "steps": r["steps"],
            "cpu_s": r["cpu_seconds"],
            "ms_per_step": 1000 * r["cpu_seconds"] / r["steps"],
            "cells": summary.reduction.cells or 0,
        }
        say(f"{i + 1}/{len(d['cases'])} done: {case['label']}")
        shutil.rmtree(summary.case, ignore_errors=True)
    dry = rows[d["cases"][0]["label"]]["ms_per_step"]
    for r in rows.values():
        r["ratio_to_dry"] = r["ms_per_step"] / dry
    return {
        "benchmark": "gas",
        "cells_across": cells,
        "end_time_s": end_time,
        "machine": machine_info(),
        "commit": commit,
        "rows": rows,
    }


def cells_across_for(preset: str, sets: list[str], target: int) -> tuple[int, int]:
    """cells_across whose mesh is closest to ``target`` cells, and that count."""
    best = (0, 0)
    for n in range(8, 1024):
        try:
            c = cells_estimate(load_preset(preset, [*sets, f"mesh.cells_across={n}"]))
        except SceneError:  # too coarse for the orifice
            continue
        if abs(c - target) < abs(best[1] - target) or best == (0, 0):
            best = (n, c)
        if c > 1.5 * target:
            break
    return best


def bench_mesh(targets: list[int], work_dir: Path, say: Say = _quiet) -> dict[str, Any]:
    """Meshing time and memory of a 3D cylinder (``bench.toml`` [mesh]).

    Each size runs the ``foamsilo mesh`` command in a fresh process (what a
    user runs); wall time split into gmsh (geometry, mesh, .msh), gmshToFoam
    and checkMesh; peak memory is the largest resident set of that process and
    the programs it ran.
    """
    commit = git_commit()  # before the runs (git_commit)
    d = defaults("mesh")
    preset, sets = d["preset"], overrides(d["set"])
    rows = []
    for target in targets:
        n, _ = cells_across_for(preset, sets, target)
        out = work_dir / f"mesh-{n}"
        argv = [
            sys.executable,
            "-m",
            "foamsilo",
            "mesh",
            preset,
            "-o",
            str(out),
            "--overwrite",
            "--json",
            "--set",
            f"mesh.cells_across={n}",
        ] + [a for s in sets for a in ("--set", s)]
        t0 = time.perf_counter()
        res = run_command(argv, env=dict(os.environ))
        wall = time.perf_counter() - t0
        payload = json.loads(res.output[: res.output.rindex("}") + 1]) if "}" in res.output else {}
        if not payload.get("ok"):
            raise FoamsiloError(
                f"meshing {n} across failed: {payload.get('error') or res.output[-500:]}"
            )
        children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        rows.append(
            {
                "cells_across": n,
                "cells": payload["cells"],
                "cell_kind": payload["cell_kind"],
                "wall_s": round(wall, 2),
                "timings_s": payload["timings_s"],
                "max_rss_mb_so_far": round(children, 1),
                "checkMesh": payload["checkMesh"],
            }
        )
        say(f"{len(rows)}/{len(targets)} done: {payload['cells']} cells in {wall:.3g} s")
        shutil.rmtree(out, ignore_errors=True)
    return {
        "benchmark": "mesh",
        "preset": preset,
        "machine": machine_info(),
        "commit": commit,
        "rows": rows,
    }


def mesh_report(result: dict[str, Any]) -> str:
    """Markdown table of a mesh benchmark."""
    m = result["machine"]
    lines = [
        f"Machine: {m['cpu']}, {m['cores']} cores; commit {result['commit']}.",
        "",
        "| cells | cells across | kind | gmsh [s] | gmshToFoam [s] | checkMesh [s] | total [s] "
        "| peak RSS [MB] | max non-orth [deg] | max skewness |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in result["rows"]:
        t = r["timings_s"]
        c = r["checkMesh"]
        lines.append(
            f"| {r['cells']:,} | {r['cells_across']} | {r['cell_kind']} | {t['gmsh']:.1f} "
            f"| {t['gmshToFoam']:.1f} | {t['checkMesh']:.1f} | {r['wall_s']:.1f} "
            f"| {r['max_rss_mb_so_far']:.0f} | {c['max_non_orthogonality']:.1f} "
            f"| {c['max_skewness']:.2f} |"
        )
    return "\n".join(lines)


def _direct_run(case: Path, of: OpenFOAM, executable: Path) -> tuple[float, int]:
    """Run siloFoam straight (no PyFoam, no pipeline): wall seconds and steps.

    The reference the runner's overhead is measured against.
    """
    t0 = time.perf_counter()
    res = run_command([str(executable), "-case", str(case)], env=of.runtime_env())
    wall = time.perf_counter() - t0
    (case / "log.direct").write_text(res.output)
    if res.returncode != 0:
        raise FoamsiloError(f"direct siloFoam run failed in {case} (see log.direct)")
    steps = sum(1 for line in res.output.splitlines() if line.startswith("Time = "))
    return wall, steps


def _copy_case(base: Path, dst: Path) -> Path:
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(base, dst, ignore=shutil.ignore_patterns(".foamsilo.lock"))
    return dst


def _run_steps(case: Path, of: OpenFOAM, n_procs: int) -> tuple[float, int]:
    res = run(case, of, n_procs=n_procs)
    assert res is not None
    return res.wall_seconds, res.steps


def bench_mpi(
    ranks: list[int],
    target_cells: int,
    end_time: float,
    work_dir: Path,
    repeats: int = 3,
    say: Say = _quiet,
) -> dict[str, Any]:
    """MPI speed-up and the cost of the Python runner on a 3D cylindrical silo.

    The lab silo of Zhou et al. (``bench.toml`` [mpi]) meshed in 3D at the
    resolution closest to ``target_cells``, from fill to ``end_time``, once per
    rank count through the pipeline (decomposition timed apart), and serially
    by calling siloFoam directly and through the pipeline, alternated
    ``repeats`` times, for the runner's overhead. Times are solver wall
    seconds per time step.
    """
    commit = git_commit()  # before the runs (git_commit)
    d = defaults("mpi")
    of = find_openfoam()
    solver = ensure_solver(of=of)
    preset = d["preset"]
    sets = [*overrides(d["set"]), f"run.end_time={end_time}", f"run.write_interval={end_time}"]
    n, _ = cells_across_for(preset, sets, target_cells)
    base = prepare(
        CaseSpec(work_dir / "base", preset, (*sets, f"mesh.cells_across={n}"), overwrite=True), of
    )
    rows = []
    for np_ in ranks:
        case = _copy_case(base, work_dir / f"np{np_}")
        t0 = time.perf_counter()
        prepare_decomposition(case, of, np_)
        t_dec = time.perf_counter() - t0
        wall, steps = _run_steps(case, of, np_)
        rows.append(
            {
                "ranks": np_,
                "steps": steps,
                "wall_s": round(wall, 2),
                "ms_per_step": round(1000 * wall / steps, 2),
                "decompose_s": round(t_dec, 2),
            }
        )
        say(f"{len(rows)}/{len(ranks)} rank counts done: {np_} ranks, {wall:.3g} s")
        shutil.rmtree(case, ignore_errors=True)
    one = next((r for r in rows if r["ranks"] == 1), rows[0])
    for r in rows:
        r["speedup"] = round(one["ms_per_step"] / r["ms_per_step"] * one["ranks"], 3)
    # single pairs differ by +-4% from run to run: alternate and take medians
    direct_ms, runner_ms, d_steps, r_steps = [], [], 0, 0
    for _ in range(repeats):
        d_wall, d_steps = _direct_run(_copy_case(base, work_dir / "direct"), of, solver.executable)
        direct_ms.append(1000 * d_wall / d_steps)
        r_wall, r_steps = _run_steps(_copy_case(base, work_dir / "runner"), of, 1)
        runner_ms.append(1000 * r_wall / r_steps)
        say(f"{len(runner_ms)}/{repeats} runner-overhead pairs done")
    med_d, med_r = statistics.median(direct_ms), statistics.median(runner_ms)
    overhead = {
        "repeats": repeats,
        "direct_steps": d_steps,
        "runner_steps": r_steps,
        "direct_ms_per_step": [round(x, 1) for x in direct_ms],
        "runner_ms_per_step": [round(x, 1) for x in runner_ms],
        "overhead": round(med_r / med_d - 1, 4),
    }
    cells = int(read_metadata(base).get("cells") or 0)
    for p in (work_dir / "direct", work_dir / "runner", base):
        shutil.rmtree(p, ignore_errors=True)
    return {
        **_record("mpi", preset, n, cells, commit),
        "end_time_s": end_time,
        "rows": rows,
        "runner": overhead,
    }


def _machine_3d(result: dict[str, Any]) -> str:
    """Return the opening of a 3D benchmark's table: machine, commit, case."""
    m = result["machine"]
    return (
        f"Machine: {m['cpu']}, {m['cores']} cores; commit {result['commit']}; "
        f"{result['preset']} in 3D, {result['cells']:,} cells ({result['cells_across']} across), "
    )


def mpi_report(result: dict[str, Any]) -> str:
    """Markdown tables of an MPI benchmark."""
    lines = [
        f"{_machine_3d(result)}0 to {result['end_time_s']} s.",
        "",
        "| ranks | steps | solver wall [s] | ms/step | speed-up | decomposePar [s] |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for r in result["rows"]:
        lines.append(
            f"| {r['ranks']} | {r['steps']} | {r['wall_s']:.1f} | {r['ms_per_step']:.1f} "
            f"| {r['speedup']:.2f} | {r['decompose_s']:.1f} |"
        )
    o = result["runner"]
    d, r = o["direct_ms_per_step"], o["runner_ms_per_step"]
    lines += [
        "",
        f"Serial, {o['repeats']} runs each, alternated (ms per step, {o['direct_steps']} steps):",
        "",
        "| serial run | ms/step, each run | median |",
        "| --- | --- | --- |",
        f"| siloFoam alone | {', '.join(f'{x:.1f}' for x in d)} | {statistics.median(d):.1f} |",
        f"| through foamsilo (PyFoam) | {', '.join(f'{x:.1f}' for x in r)} "
        f"| {statistics.median(r):.1f} |",
        "",
        f"Runner overhead per step (medians): {o['overhead']:+.1%}.",
    ]
    return "\n".join(lines)


def bench_post(
    target_cells: int,
    n_times: int,
    work_dir: Path,
    ranks: int = 2,
    interval: float = 2e-4,
    say: Say = _quiet,
    progress: ProgressCallback | None = None,
) -> dict[str, Any]:
    """Cost of ``foamsilo post`` on a 3D silo with many written times.

    The lab silo of Zhou et al. in 3D (``bench.toml`` [post]) at the
    resolution closest to ``target_cells``, run on ``ranks`` ranks for
    ``n_times`` written times (the solver shortens its step to hit each),
    then reduced twice: straight from the processor directories, and after
    reconstructPar. The figure is the wall time of :func:`foamsilo.pipeline.reduce`
    (Q(t) and the steady analysis, the free surface at every written time, the
    profile, the stagnant fraction, the pictures, the report).
    """
    from foamsilo.foam import reconstruct_par

    commit = git_commit()  # before the runs (git_commit)
    d = defaults("post")
    of = find_openfoam()
    preset = d["preset"]
    end = round(n_times * interval, 10)
    sets = [*overrides(d["set"]), f"run.end_time={end}", f"run.write_interval={interval}"]
    n, _ = cells_across_for(preset, sets, target_cells)
    case = prepare(
        CaseSpec(work_dir / "post", preset, (*sets, f"mesh.cells_across={n}"), overwrite=True), of
    )
    res = run(case, of, n_procs=ranks, progress=progress)
    assert res is not None
    say(f"solver done: {res.steps} steps on {ranks} ranks")
    rows = []
    for label in ("decomposed", "reconstructed"):
        if label == "reconstructed":
            reconstruct_par(of, case)
            for p in case.glob("processor*"):
                shutil.rmtree(p)
        t0 = time.perf_counter()
        s = reduce(case)
        wall = time.perf_counter() - t0
        fields = s.reduction.fields
        if fields is None:
            raise FoamsiloError(f"bench post: fields not reduced: {s.reduction.fields_error}")
        surface_rows = len((case / "free_surface.csv").read_text().splitlines()) - 1
        root = case / "processor0" if label == "decomposed" else case
        times = len([p for p in root.iterdir() if is_time_name(p.name)])
        rows.append(
            {
                "read": fields.case_type,
                "written_times": times,
                "surface_rows": surface_rows,
                "post_wall_s": round(wall, 2),
            }
        )
        say(f"{len(rows)}/2 reductions done: {label}, {wall:.3g} s")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    cells = int(read_metadata(case).get("cells") or 0)
    shutil.rmtree(case, ignore_errors=True)
    return {
        **_record("post", preset, n, cells, commit),
        "ranks": ranks,
        "solver_wall_s": round(res.wall_seconds, 1),
        "steps": res.steps,
        "rows": rows,
        "max_rss_mb": round(rss, 1),
    }


def _record(
    name: str, preset: str, cells_across: int, cells: int, commit: str | None
) -> dict[str, Any]:
    """Return the fields every 3D benchmark record starts with (``commit``: before its runs)."""
    return {
        "benchmark": name,
        "preset": preset,
        "cells_across": cells_across,
        "cells": cells,
        "machine": machine_info(),
        "commit": commit,
    }


def post_report(result: dict[str, Any]) -> str:
    """Markdown table of a post-processing benchmark."""
    lines = [
        f"{_machine_3d(result)}run on {result['ranks']} ranks ({result['steps']} steps, "
        f"{result['solver_wall_s']} s).",
        "",
        "| fields read from | written times (0 included) | free-surface rows | "
        "`foamsilo post` wall [s] |",
        "| --- | --- | --- | --- |",
    ]
    for r in result["rows"]:
        lines.append(
            f"| {r['read']} | {r['written_times']} | {r['surface_rows']} | {r['post_wall_s']:.1f} |"
        )
    lines += ["", f"Peak memory of the benchmark process: {result['max_rss_mb']:.0f} MB."]
    return "\n".join(lines)
