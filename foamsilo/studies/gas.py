"""Reproductions of the seed papers' gas-coupled simulations: ``foamsilo validate``.

``zhou-gas`` reruns section III.B of Zhou et al. 2019 (the planar silo with
gas coupling): the open top and Q_air/sqrt(g L^3) from 0 (closed top) to
0.5, and writes Figs 4b, 5b and 6b with the analytical model (eq. 23, A = 1
and A = 0.68) and the agreement stated as numbers. ``gas-extremes`` runs the
stiff and extreme gas cases of the thin rectangular lab silo and reports
each outcome. The cases, and the paper's numbers they are set against, are
data: ``foamsilo/studies/validation.toml``. The reports are written from the
results only.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.analytic.exact import darcy_slit_pressure
from foamsilo.analytic.zhou import reduced_flow_rate
from foamsilo.case import write_whole
from foamsilo.errors import FoamsiloError
from foamsilo.jsonio import dumps
from foamsilo.pipeline import Backend
from foamsilo.studies.cases import (
    StudyCase,
    fmt,
    git_commit,
    machine_info,
    overrides,
    run_rows,
    study_table,
)


def eq23_planar(
    q_air_scaled: np.ndarray, q0_scaled: float, zeta: float, d_over_l: float, A: float
) -> np.ndarray:
    """Eq. 23 (Darcy) in the planar scaling of Zhou sec. III.B.

    With rho = rho_p (phi_o = 1) and kappa_v/eta_f = zeta/(rho sqrt(g/L)):
    N_v = Q0* L/(zeta D) and Qtilde = Q_air*/Q0*, * meaning over sqrt(g L^3).
    """
    nv = A * q0_scaled / (zeta * d_over_l)
    return q0_scaled * reduced_flow_rate(np.asarray(q_air_scaled) / q0_scaled, nv, 0.0)


def zhou_gas(
    cells: int,
    work_dir: Path,
    out_dir: Path,
    jobs: int = 2,
    end_time: float | None = None,
    backend: Backend | None = None,
) -> dict[str, Any]:
    """Run the sweep of Zhou sec. III.B and write figures and a report."""
    from foamsilo.scene import load_preset

    commit = git_commit()  # before the runs (git_commit)
    table = study_table("validation")["zhou-gas"]
    preset = table["preset"]
    base = [f"mesh.cells_across={cells}"] + ([f"run.end_time={end_time}"] if end_time else [])
    cases = [StudyCase("open top", preset, base + overrides(table["open_top"]))]
    for q in table["q_air_scaled"]:
        sets = overrides(table["closed_top"]) if q == 0 else [f"gas.q_air_scaled={q!r}"]
        cases.append(StudyCase(f"Q_air = {q:g}", preset, base + sets))
    t0 = time.perf_counter()
    rows = run_rows(cases, Path(work_dir), backend or jobs, None)
    wall = time.perf_counter() - t0
    failed = [r for r in rows if r["outcome"] != "steady"]
    if failed:
        raise FoamsiloError(
            "no steady discharge in "
            + "; ".join(f"{r['case_dir']} ({r['outcome']}: {r['detail']})" for r in failed)
            + " (run longer: --end-time)"
        )
    results = []
    for r in rows:
        s = _summary(Path(r["case_dir"]))
        s["sets"] = r["sets"]
        results.append(s)
    scene = load_preset(preset, base)
    return write_report(results, scene, cells, wall, jobs, Path(out_dir), table, commit)


def _summary(case: Path) -> dict[str, Any]:
    import json

    return dict(json.loads((case / "summary.json").read_text()))


def write_report(
    results: list[dict[str, Any]],
    scene: Any,
    cells: int,
    wall: float,
    jobs: int,
    out: Path,
    table: dict[str, Any],
    commit: str | None,
) -> dict[str, Any]:
    """Figures 4b, 5b, 6b and the Markdown report (``commit``: the one its cases ran at)."""
    from foamsilo.plots import finish, subplots

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
    qa = np.array(table["q_air_scaled"])
    qs = np.array([r["Q_dimensionless"] for r in coupled])
    model = {A: eq23_planar(qa, q0, zeta, dl, A) for A in (1.0, 0.68)}
    rel068 = (qs - model[0.68]) / model[0.68]
    rel1 = (qs - model[1.0]) / model[1.0]

    # Fig. 4b
    fig, ax = subplots()
    ax.plot(qa, qs, "ko", label=f"siloFoam, {cells} cells across")
    ax.axhline(q0, color="0.5", ls=":", label=f"open top, Q0 = {q0:.3f}")
    xx = np.linspace(0, 0.55, 100)
    ax.plot(xx, eq23_planar(xx, q0, zeta, dl, 1.0), "k--", label="eq. 23, A = 1")
    ax.plot(xx, eq23_planar(xx, q0, zeta, dl, 0.68), "r-", label="eq. 23, A = 0.68")
    ax.set_xlabel(r"$Q_{air}/\sqrt{gL^3}$")
    ax.set_ylabel(r"$Q/(\rho\sqrt{gL^3})$")
    ax.set_title("Zhou et al. Fig. 4b, reproduced")
    finish(fig, ax, out / "zhou-fig4b.png")

    # Fig. 5b: the Q_air = 0.5 case
    r5 = coupled[-1]
    pp = r5["pore_pressure"]
    L, D = scene.silo.width, scene.silo.orifice_width
    rho_g = scene.material.density * scene.gravity
    y = np.array(pp["y"])
    p = np.array(pp["pressure"])
    fig, ax = subplots()
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
    finish(fig, ax, out / "zhou-fig5b.png")

    # Fig. 6b
    xs = np.array([r["pore_pressure"]["fig6b_abscissa"] for r in coupled])
    zs = np.array([r["pore_pressure"]["zone_gradient_scaled"] for r in coupled])
    # mean gradient over the orifice: relative flux / (kappa/eta) / S_o, scaled
    orif = np.array(
        [
            r["pore_pressure"]["relative_gas_flux_measured"]
            * scene.air.viscosity
            / (scene.permeability * D * rho_g)
            for r in coupled
        ]
    )
    slope_zone = float(np.sum(xs * zs) / np.sum(xs * xs))
    slope_orifice = float(np.sum(xs * orif) / np.sum(xs * xs))
    fig, ax = subplots()
    ax.plot(xs, orif, "ks", mfc="none", label=f"mean over the orifice (slope {slope_orifice:.3f})")
    ax.plot(xs, zs, "rx", label=f"mean over the D/2 zone (slope {slope_zone:.3f})")
    xl = np.linspace(min(xs.min(), 0), xs.max() * 1.05, 50)
    ax.plot(xl, xl, "k--", lw=1, label="slope 1 (eq. 20)")
    ax.plot(xl, 0.68 * xl, "r-", lw=1, label="slope 0.68 (paper)")
    ax.set_xlabel(r"$\eta_f (Q_{air} - Q/\rho_p)/(\rho g \kappa_v S_o)$")
    ax.set_ylabel(r"$\langle \partial p^f/\partial z \rangle/(\rho g)$")
    ax.set_title("Zhou et al. Fig. 6b, reproduced")
    finish(fig, ax, out / "zhou-fig6b.png")

    report = {
        "machine": machine_info(),
        "commit": commit,
        "paper": table["paper"],
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
            }
            for r in results
        ],
    }
    write_whole(out / "zhou-gas-planar.json", dumps(report) + "\n")
    _markdown(report, scene, out)
    return report


def _markdown(rep: dict[str, Any], scene: Any, out: Path) -> None:
    rows = []
    for q, s, a1, a068, run in zip(
        rep["q_air_scaled"],
        rep["q_dimensionless"],
        rep["eq23_A1"],
        rep["eq23_A068"],
        rep["runs"][1:],
        strict=True,
    ):
        r = run["run"] or {}
        rows.append(
            f"| {q:g}{' (closed top)' if q == 0 else ''} | {s:.4f} | {a1:.4f} | {a068:.4f} "
            f"| {(s - a068) / a068:+.1%} | {r.get('cpu_seconds', math.nan):.0f} s |"
        )
    o = rep["runs"][0]["run"] or {}
    f5 = rep["fig5b"]
    paper = rep["paper"]
    m = rep["machine"]
    s = scene.silo
    L = s.width
    about = (
        f"planar silo L = {L:g} m, H = {s.height / L:g}L, fill {s.fill_height / L:g}L, "
        f"D = {s.orifice_width / L:g}L, d = L/{L / scene.material.grain_diameter:.0f}, "
        f"W = {(s.thickness or 0) / L:g}L, μ_w = {scene.material.wall_friction}, "
        f"ζ = {scene.gas.permeability_scaled}, ζ_∞ = {scene.gas.permeability_ratio:g}, "
        f"run to {scene.run.end_time / scene.time_scale:.3g} √(L/g)"
    )
    better = "A = 0.68" if rep["rms_rel_diff_A068"] < rep["rms_rel_diff_A1"] else "A = 1"
    text = f"""# Zhou et al. 2019, section III.B with gas coupling: Figs 4b, 5b, 6b

Reproduced with

```sh
foamsilo validate zhou-gas --cells {rep["cells_across"]} --jobs {rep["jobs"]}
```

(the preset `{scene.name}`: {about}; {rep["cells_across"]} cells across L;
{rep["jobs"]} cases at a time on {m["cpu"]} ({m["cores"]} cores), commit {rep["commit"]};
whole sweep {rep["wall_seconds"] / 60:.1f} min wall).

## Fig. 4b: discharge rate against the air flow

Open top (no coupling): Q₀/(ρ√(gL³)) = {rep["q0_dimensionless"]:.4f}
({o.get("cpu_seconds", math.nan):.0f} CPU-s). Eq. 23 in the planar scaling:
N_v = A Q₀* L/(ζD), Q̃ = Q_air*/Q₀* (ρ = ρ_p, so φ_o = 1).

| Q_air/√(gL³) | Q/(ρ√(gL³)) | eq. 23, A = 1 | eq. 23, A = 0.68 | vs A = 0.68 | CPU |
| --- | --- | --- | --- | --- | --- |
{chr(10).join(rows)}

**Agreement with eq. 23 (A = 0.68): rms {rep["rms_rel_diff_A068"]:.1%}, largest
{rep["max_abs_rel_diff_A068"]:.1%}** (with A = 1: rms {rep["rms_rel_diff_A1"]:.1%}); the
closer of the two here: {better} (the paper fitted A = {paper["zone_slope"]}).

![Fig. 4b](zhou-fig4b.png)

## Fig. 5b: mean pore pressure along the axis (Q_air/√(gL³) = {rep["q_air_scaled"][-1]:g})

Each tap averaged over the stationary regime while it is inside the granular
bed (more than L/4 below the free surface).

The lines are built as the paper builds them: near the orifice, eq. 20 at
the orifice, slope η_f(Q_air − Q/ρ)/(κ_v S_o); far from it, the same with the
silo section S_b = L, and an intercept fitted by least squares to the far
taps. Their ratio is L/D by construction; the measurements are the far
intercept (hence where the lines cross), the free fit of the far slope, and
the orifice gradient from the measured gas flux.

| quantity | siloFoam | paper ({paper["source"]}) |
| --- | --- | --- |
| near slope / ρg (eq. 20, from Q_air − Q/ρ) | {f5["gradient_near_scaled"]:.3f} \
| {paper["near_slope_scaled"]} |
| orifice gradient from the gas flux / ρg | {f5["gradient_orifice_measured_scaled"]:.3f} | – |
| far slope / ρg | {f5["gradient_far_scaled"]:.3f} | {paper["far_slope_scaled"]} |
| far slope, free least-squares fit / ρg | {f5["gradient_far_fit_scaled"]:.3f} | – |
| far intercept / (ρgL) (fitted) | {f5["far_intercept_scaled"]:.3f} \
| {paper["far_intercept_scaled"]} |
| ratio of the slopes | {f5["gradient_ratio"]:.2f} | L/D = {L / s.orifice_width:g} |
| change of slope | z = {f5["slope_change_over_D"]:.2f} D | z ≈ {paper["slope_change_over_D"]} D |

The exact Darcy solution for a uniform permeability (Darcy flow into a slot,
`foamsilo.analytic.exact.darcy_slit_pressure`, with the gas flux Q_air − Q/ρ)
is drawn for comparison.

![Fig. 5b](zhou-fig5b.png)

## Fig. 6b: mean pore-pressure gradient against the relative gas flux

Over the orifice the mean gradient follows eq. 20 with slope
{rep["fig6b_slope_orifice"]:.3f} (1 by flux conservation); over the zone of
radius D/2 above the orifice, **slope {rep["fig6b_slope_zone"]:.3f}** (the paper:
A = {paper["zone_slope"]}), over co-current (Q_air > Q/ρ) and counter-current (closed
top) flow.

![Fig. 6b](zhou-fig6b.png)
"""
    write_whole(out / "zhou-gas-planar.md", text)


def gas_extremes(
    cells: int,
    work_dir: Path,
    out_dir: Path,
    jobs: int = 2,
    limit: float = 900.0,
    backend: Backend | None = None,
) -> dict[str, Any]:
    """Stiff and extreme gas cases in the rectangular lab silo; report each outcome."""
    from foamsilo.scene import load_preset

    commit = git_commit()  # before the runs (git_commit)
    table = study_table("validation")["gas-extremes"]
    base = [f"mesh.cells_across={cells}"]
    cases = [
        StudyCase(c["label"], table["preset"], base + overrides(c["set"])) for c in table["cases"]
    ]
    t0 = time.perf_counter()
    rows = run_rows(cases, Path(work_dir), backend or jobs, limit)
    for c, r in zip(cases, rows, strict=True):
        scene = load_preset(c.preset, c.sets)
        if r.get("fill_height_end_m") is not None and r["fill_height_end_m"] < scene.emptied_height:
            r["emptied"] = True
        # Zhou eq. 3: air injected into a sealed silo can push out at most its
        # own volume of bulk grains, rho_b Q_air (the grains that leave and the
        # air that escapes through the orifice share Q_air)
        if scene.q_air_per_depth > 0:
            r["eq3_limit"] = scene.material.density * scene.q_air_per_depth
            if r.get("Q"):
                r["eq3_fraction"] = r["Q"] / r["eq3_limit"]
    rep = {
        "preset": table["preset"],
        "cells_across": cells,
        "jobs": jobs,
        "limit_s": limit,
        "rows": rows,
        "wall_seconds": time.perf_counter() - t0,
        "machine": machine_info(),
        "commit": commit,
    }
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_whole(out / "gas-extremes.json", dumps(rep) + "\n")
    write_whole(out / "gas-extremes.md", extremes_markdown(rep, load_preset(table["preset"])))
    return rep


def extremes_markdown(rep: dict[str, Any], scene: Any) -> str:
    """Return the gas-extremes report, from the results only."""
    lines = []
    for r in rep["rows"]:
        q = f"{1e3 * r['Q'] * r['thickness']:.2f}" if r.get("Q") else "–"
        eq3 = (
            f"{1e3 * r['eq3_limit'] * r['thickness']:.0f}: {r['eq3_fraction']:.3f}"
            f"{'' if r['eq3_fraction'] <= 1 else ' (above the bound)'}"
            if r.get("eq3_fraction") is not None
            else "–"
        )
        outcome = r["outcome"]
        if r.get("emptied"):
            outcome += " until the silo emptied" if outcome == "steady" else " (the silo emptied)"
        lines.append(
            f"| {r['label']} | {outcome} "
            f"| {q} | {eq3} | {fmt(r.get('t_reached'), '.3g')} / {r['end_time']:g} "
            f"| {r.get('steps', 0)} | {fmt(r.get('dt_min'), '.2e')} – "
            f"{fmt(r.get('dt_max'), '.2e')} "
            f"| {r['wall_s']:.0f} s |"
        )
    details = "\n".join(
        f"* **{r['label']}**: {r['detail']}" for r in rep["rows"] if r.get("detail")
    )
    s, m = scene.silo, rep["machine"]
    return f"""# Stiff and extreme gas cases

The thin rectangular lab silo (preset `{rep["preset"]}`: L = {s.width * 1e3:g} mm,
H = {s.height * 1e3:g} mm, D = {s.orifice_width * 1e3:g} mm, W = {(s.thickness or 0) * 1e3:g} mm,
wall friction {scene.material.wall_friction}), {rep["cells_across"]} cells across L, run to
{scene.run.end_time:g} s, each with a wall-time limit of {rep["limit_s"]:g} s. Q is the mass
flow of the real {(s.thickness or 0) * 1e3:g}-mm-thick silo. Reproduce with

```sh
foamsilo validate gas-extremes --cells {rep["cells_across"]} --jobs {rep["jobs"]}
```

| case | outcome | Q (g/s) | eq. 3: ρ_b Q_air (g/s): Q/ρ_b Q_air | t reached / end (s) \
| steps | Δt range (s) | wall |
| --- | --- | --- | --- | --- | --- | --- | --- |
{chr(10).join(lines)}

{details}

With air injected (a sealed top), Zhou et al.'s eq. 3 bounds the rate: the
injected air can push out at most its own volume of bulk grains, ρ_b Q_air
(impermeable grains reach it; the air that escapes through the orifice makes
up the difference). A rate above it is a defect. A run whose silo empties
gets its rate from the plateau before the end of the discharge (the window
ends where the rate leaves its plateau for good with the silo less than a
quarter full).

Whole suite: {rep["wall_seconds"] / 60:.1f} min wall, {rep["jobs"]} cases at a time on
{m["cpu"]} ({m["cores"]} cores), commit {rep["commit"]}. What the outcomes mean is discussed
in [docs/gas.md](../gas.md).
"""
