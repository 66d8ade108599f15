"""Benchmarks: solver cost and accuracy, written as tables into ``docs/``.

``foamsilo bench solver`` runs the planar silo of Zhou et al. (sec. III.B)
at several resolutions, from fill to ``end_time``, and reports per run:
CPU seconds per simulated second, milliseconds per step, steps per
simulated second, cell-steps per CPU second, peak memory, the steady Q and
the mass balance.  In the same run it times one step of stock ``interFoam``
with a Newtonian fluid on the same mesh, so that figures taken on different
days (or machines) can be compared as ratios.
"""

from __future__ import annotations

import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from foamsilo import __version__
from foamsilo.case import create_case
from foamsilo.errors import FoamsiloError
from foamsilo.post import summarize
from foamsilo.run import run_solver
from foamsilo.scene import load_preset
from foamsilo.solver import ensure_solver
from foamsilo.toolchain import OpenFOAM, find_openfoam

REFERENCE_STEPS = 60


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


def machine_info() -> dict[str, Any]:
    """Where a benchmark ran."""
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "foamsilo": __version__,
        "date": time.strftime("%Y-%m-%d"),
    }


def _git_commit() -> str | None:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=Path(__file__).parent,
            timeout=10,
        )
        commit = out.stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            cwd=Path(__file__).parent,
            timeout=10,
        ).stdout.strip()
        return (commit + ("-dirty" if dirty else "")) or None
    except (OSError, subprocess.SubprocessError):
        return None


def _set_entry(path: Path, key: str, value: str) -> None:
    text = path.read_text()
    text, n = re.subn(
        r"^(\s*" + re.escape(key) + r"\s+)[^;]+;", r"\g<1>" + value + ";", text, count=1, flags=re.M
    )
    if n != 1:
        raise ValueError(f"{key} not in {path}")
    path.write_text(text)


def interfoam_ms_per_step(
    case: Path, of: OpenFOAM, delta_t: float, steps: int = REFERENCE_STEPS
) -> float:
    """Time one step of stock interFoam, Newtonian fluid, on ``case``'s mesh.

    The granular phase is replaced by a Newtonian fluid of the same density
    and kinematic viscosity 1e-6 m^2/s; the run starts from the initial fill
    with a fixed time step.  The first tenth of the steps is not counted.
    """
    ref = case.parent / f"{case.name}.interFoam"
    if ref.exists():
        shutil.rmtree(ref)
    ref.mkdir()
    for d in ("system", "constant"):
        shutil.copytree(case / d, ref / d)
    shutil.copytree(case / "0", ref / "0")
    tp = ref / "constant" / "transportProperties"
    text = re.sub(r"muICoeffs\s*\{[^}]*\}", "nu              1e-06;", tp.read_text())
    tp.write_text(re.sub(r"transportModel\s+muI;", "transportModel  Newtonian;", text))
    fs = ref / "system" / "fvSolution"
    fs.write_text(
        fs.read_text().replace(
            "solvers\n{",
            'solvers\n{\n    "pcorr.*"\n    {\n        solver PCG;\n        preconditioner DIC;\n'
            "        tolerance 1e-8;\n        relTol 0;\n    }\n",
            1,
        )
    )
    cd = ref / "system" / "controlDict"
    cd.write_text(re.sub(r"\nfunctions\s*\{.*\}\s*$", "\n", cd.read_text(), flags=re.S))
    for k, v in [
        ("application", "interFoam"),
        ("adjustTimeStep", "no"),
        ("deltaT", f"{delta_t:.6g}"),
        ("endTime", f"{delta_t * steps:.6g}"),
        ("writeControl", "timeStep"),
        ("writeInterval", str(steps)),
    ]:
        _set_entry(cd, k, v)
    proc = subprocess.run(
        [str(of.appbin / "interFoam"), "-case", str(ref)],
        env=of.runtime_env(),
        capture_output=True,
        text=True,
    )
    times = [float(x) for x in re.findall(r"^ExecutionTime = ([\d.eE+-]+) s", proc.stdout, re.M)]
    shutil.rmtree(ref, ignore_errors=True)
    if proc.returncode != 0 or len(times) < steps // 2:
        raise RuntimeError(f"interFoam reference failed:\n{proc.stdout[-2000:]}{proc.stderr}")
    skip = max(1, len(times) // 10)
    return 1000 * (times[-1] - times[skip - 1]) / (len(times) - skip)


def bench_solver(
    cells: list[int],
    end_time: float,
    work_dir: Path,
    overrides: list[str] | None = None,
    reference: bool = True,
    keep: bool = False,
) -> dict[str, Any]:
    """Run the solver benchmark on the planar silo.

    Parameters
    ----------
    cells
        Resolutions (cells across L).
    end_time
        Simulated time of each run [s].
    work_dir
        Where the cases are written.
    overrides
        Extra ``--set`` scene overrides (a lever to measure).
    reference
        Also time stock interFoam on the same mesh.
    keep
        Keep the cases.
    """
    of = find_openfoam()
    solver = ensure_solver(of=of)
    rows = []
    for n in cells:
        scene = load_preset(
            "zhou-planar",
            [
                f"mesh.cells_across={n}",
                f"run.end_time={end_time}",
                f"run.write_interval={end_time / 4}",
            ]
            + list(overrides or []),
        )
        case_dir = Path(work_dir) / f"planar-{n}"
        case = create_case(scene, case_dir, of, overwrite=True)
        result = run_solver(case.path, of, solver)
        summary = summarize(case.path, result.as_dict())
        ref_ms = None
        ms = 1000 * result.cpu_seconds / result.steps
        if reference:
            ref_ms = interfoam_ms_per_step(case.path, of, delta_t=end_time / result.steps)
        rows.append(
            SolverBenchRow(
                cells_across=n,
                cells=case.mesh.cells if case.mesh else 0,
                simulated_s=result.end_time - result.start_time,
                steps=result.steps,
                cpu_s=result.cpu_seconds,
                wall_s=result.wall_seconds,
                cpu_s_per_simulated_s=result.cpu_seconds / (result.end_time - result.start_time),
                ms_per_step=ms,
                steps_per_simulated_s=result.steps / (result.end_time - result.start_time),
                cell_steps_per_cpu_s=(case.mesh.cells if case.mesh else 0)
                * result.steps
                / result.cpu_seconds,
                peak_memory_mb=result.max_rss_mb,
                q_dimensionless=summary["Q_dimensionless"],
                q_from_volume_dimensionless=summary["Q_from_volume_dimensionless"],
                mass_balance_rel_error=summary["mass_balance_rel_error"],
                interfoam_ms_per_step=ref_ms,
                ratio_to_interfoam=ms / ref_ms if ref_ms else None,
            )
        )
        if not keep:
            shutil.rmtree(case.path, ignore_errors=True)
    return {
        "benchmark": "solver",
        "scene": "zhou-planar",
        "end_time_s": end_time,
        "overrides": list(overrides or []),
        "machine": machine_info(),
        "commit": _git_commit(),
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


def bench_gas(cells: int, end_time: float, work_dir: Path) -> dict[str, Any]:
    """Cost of a time step with the pore-pressure solve against the same case dry.

    The preset ``zhou-planar-gas`` (injection, Darcy) and the same scene with
    an open top (no pore pressure), same mesh, run one after the other.
    """
    of = find_openfoam()
    solver = ensure_solver(of=of)
    rows = {}
    for label, sets in (
        ("dry (open top)", ['gas.mode="open-top"', "gas.q_air_scaled="]),
        ("coupled (injection, Darcy)", []),
        ("coupled (injection, Darcy-Forchheimer)", ["gas.inertial=true"]),
    ):
        scene = load_preset(
            "zhou-planar-gas",
            [
                f"mesh.cells_across={cells}",
                f"run.end_time={end_time}",
                f"run.write_interval={end_time / 2}",
            ]
            + sets,
        )
        case = create_case(scene, Path(work_dir) / f"gas-{len(rows)}", of, overwrite=True)
        result = run_solver(case.path, of, solver)
        rows[label] = {
            "steps": result.steps,
            "cpu_s": result.cpu_seconds,
            "ms_per_step": 1000 * result.cpu_seconds / result.steps,
            "cells": case.mesh.cells if case.mesh else 0,
        }
        shutil.rmtree(case.path, ignore_errors=True)
    dry = rows["dry (open top)"]["ms_per_step"]
    for r in rows.values():
        r["ratio_to_dry"] = r["ms_per_step"] / dry
    return {
        "benchmark": "gas",
        "cells_across": cells,
        "end_time_s": end_time,
        "machine": machine_info(),
        "commit": _git_commit(),
        "rows": rows,
    }


def _cells_across_for(preset: str, sets: list[str], target: int) -> tuple[int, int]:
    """cells_across whose mesh is closest to ``target`` cells, and that count."""
    from foamsilo.errors import SceneError
    from foamsilo.mesh import cells_estimate

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


def bench_mesh(targets: list[int], work_dir: Path) -> dict[str, Any]:
    """Meshing time and memory of a 3D cylinder (Venier Test 1 meshed in 3D).

    Each size runs ``foamsilo mesh`` in a fresh process; wall time split into
    gmsh (geometry, mesh, .msh), gmshToFoam and checkMesh; peak memory is the
    largest resident set of that process and the utilities it ran.
    """
    import resource

    preset, sets = "venier-test1", ["mesh.representation='3d'"]
    rows = []
    for target in targets:
        n, est = _cells_across_for(preset, sets, target)
        out = work_dir / f"mesh-{n}"
        cmd = [sys.executable, "-m", "foamsilo", "mesh", preset, "-o", str(out), "--overwrite",
               "--json", "--set", f"mesh.cells_across={n}", "--set", sets[0]]  # fmt: skip
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
        stdout, _ = proc.communicate()
        wall = time.perf_counter() - t0
        payload = json.loads(stdout)
        if not payload.get("ok"):
            raise FoamsiloError(f"meshing {n} across failed: {payload.get('error')}")
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
        shutil.rmtree(out, ignore_errors=True)
    return {"benchmark": "mesh", "preset": preset, "machine": machine_info(),
            "commit": _git_commit(), "rows": rows}  # fmt: skip


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
    """Run siloFoam straight from a subprocess (no PyFoam): wall seconds and steps."""
    env = of.runtime_env()
    t0 = time.perf_counter()
    with open(case / "log.direct", "w") as log:
        proc = subprocess.run(
            [str(executable), "-case", str(case)], env=env, stdout=log, stderr=subprocess.STDOUT
        )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise FoamsiloError(f"direct siloFoam run failed in {case} (see log.direct)")
    steps = sum(1 for line in (case / "log.direct").open() if line.startswith("Time = "))
    return wall, steps


def bench_mpi(
    ranks: list[int], target_cells: int, end_time: float, work_dir: Path, repeats: int = 3
) -> dict[str, Any]:
    """MPI speed-up and the cost of the Python runner on a 3D cylindrical silo.

    The lab silo of Zhou et al. (Table I, L = 60 mm, D = 10 mm) meshed in 3D
    (O-grid hexahedra) at the resolution closest to ``target_cells``, from
    fill to ``end_time``, once per rank count through :func:`run_solver`
    (decomposition excluded: it is timed apart), and once serially by calling
    siloFoam directly, for the runner's overhead. Times are solver wall
    seconds per time step (the step count can differ by a step or two between
    decompositions: round-off).
    """
    from foamsilo.run import prepare_decomposition

    of = find_openfoam()
    solver = ensure_solver(of=of)
    preset = "zhou-cyl-bottom"
    sets = ["mesh.representation='3d'", f"run.end_time={end_time}"]
    sets.append(f"run.write_interval={end_time}")
    n, _ = _cells_across_for(preset, sets, target_cells)
    scene = load_preset(preset, [*sets, f"mesh.cells_across={n}"])
    base = create_case(scene, Path(work_dir) / "base", of, overwrite=True)
    rows = []
    for np_ in ranks:
        case = Path(work_dir) / f"np{np_}"
        shutil.rmtree(case, ignore_errors=True)
        shutil.copytree(base.path, case)
        t0 = time.perf_counter()
        prepare_decomposition(case, of, np_)
        t_dec = time.perf_counter() - t0
        res = run_solver(case, of, solver, n_procs=np_)
        rows.append(
            {
                "ranks": np_,
                "steps": res.steps,
                "wall_s": round(res.wall_seconds, 2),
                "ms_per_step": round(1000 * res.wall_seconds / res.steps, 2),
                "decompose_s": round(t_dec, 2),
            }
        )
        shutil.rmtree(case, ignore_errors=True)
    one = next((r for r in rows if r["ranks"] == 1), rows[0])
    for r in rows:
        r["speedup"] = round(one["ms_per_step"] / r["ms_per_step"] * one["ranks"], 3)
    # the Python runner against the solver alone, serial, same case,
    # alternated `repeats` times (single pairs differ by +-4% from run to run)
    direct_ms, runner_ms, d_steps, r_steps = [], [], 0, 0
    direct = Path(work_dir) / "direct"
    via = Path(work_dir) / "runner"
    for _ in range(repeats):
        shutil.rmtree(direct, ignore_errors=True)
        shutil.copytree(base.path, direct)
        d_wall, d_steps = _direct_run(direct, of, solver.executable)
        direct_ms.append(1000 * d_wall / d_steps)
        shutil.rmtree(via, ignore_errors=True)
        shutil.copytree(base.path, via)
        r_res = run_solver(via, of, solver)
        r_steps = r_res.steps
        runner_ms.append(1000 * r_res.wall_seconds / r_res.steps)
    med_d, med_r = statistics.median(direct_ms), statistics.median(runner_ms)
    overhead = {
        "repeats": repeats,
        "direct_steps": d_steps,
        "runner_steps": r_steps,
        "direct_ms_per_step": [round(x, 1) for x in direct_ms],
        "runner_ms_per_step": [round(x, 1) for x in runner_ms],
        "overhead": round(med_r / med_d - 1, 4),
    }
    for p in (direct, via, base.path):
        shutil.rmtree(p, ignore_errors=True)
    return {
        **_record("mpi", preset, n, base),
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


def bench_post(target_cells: int, n_times: int, work_dir: Path, ranks: int = 2) -> dict[str, Any]:
    """Cost of ``foamsilo post`` on a 3D silo with many written times.

    The lab silo of Zhou et al. in 3D at the resolution closest to
    ``target_cells``, run on ``ranks`` ranks for ``n_times`` written times
    (one every 0.2 ms: the solver shortens its step to hit each), then
    post-processed twice: straight from the processor directories, and after
    reconstructPar. The wall time of :func:`foamsilo.post.summarize` is the
    figure (Q(t) and the steady analysis, the free surface at every written
    time, the profile, the stagnant fraction, the pictures, the report).
    """
    import resource

    from foamsilo.foam import run_utility

    of = find_openfoam()
    solver = ensure_solver(of=of)
    preset = "zhou-cyl-bottom"
    interval = 2e-4
    end = round(n_times * interval, 10)
    sets = ["mesh.representation='3d'", f"run.end_time={end}", f"run.write_interval={interval}"]
    n, _ = _cells_across_for(preset, sets, target_cells)
    scene = load_preset(preset, [*sets, f"mesh.cells_across={n}"])
    case = create_case(scene, Path(work_dir) / "post", of, overwrite=True)
    res = run_solver(case.path, of, solver, n_procs=ranks)
    rows = []
    for label in ("decomposed", "reconstructed"):
        if label == "reconstructed":
            run_utility(of, case.path, "reconstructPar")
            for p in case.path.glob("processor*"):
                shutil.rmtree(p)
        t0 = time.perf_counter()
        s = summarize(case.path)
        wall = time.perf_counter() - t0
        if "error" in s["fields"]:
            raise FoamsiloError(f"bench post: fields not reduced: {s['fields']['error']}")
        surface_rows = len((case.path / "free_surface.csv").read_text().splitlines()) - 1
        times = len([p for p in (case.path / "processor0" if label == "decomposed"
                                 else case.path).iterdir() if _is_time(p.name)])  # fmt: skip
        rows.append({"read": s["fields"]["case_type"], "written_times": times,
                     "surface_rows": surface_rows, "post_wall_s": round(wall, 2)})  # fmt: skip
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    shutil.rmtree(case.path, ignore_errors=True)
    return {
        **_record("post", preset, n, case),
        "ranks": ranks,
        "solver_wall_s": round(res.wall_seconds, 1),
        "steps": res.steps,
        "rows": rows,
        "max_rss_mb": round(rss, 1),
    }


def _record(name: str, preset: str, cells_across: int, case: Any) -> dict[str, Any]:
    """Return the fields every 3D benchmark record starts with."""
    return {
        "benchmark": name,
        "preset": preset,
        "cells_across": cells_across,
        "cells": case.mesh.cells if case.mesh else 0,
        "machine": machine_info(),
        "commit": _git_commit(),
    }


def _is_time(name: str) -> bool:
    try:
        float(name)
    except ValueError:
        return False
    return True


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
        lines.append(f"| {r['read']} | {r['written_times']} | {r['surface_rows']} "
                     f"| {r['post_wall_s']:.1f} |")  # fmt: skip
    lines += ["", f"Peak memory of the benchmark process: {result['max_rss_mb']:.0f} MB."]
    return "\n".join(lines)
