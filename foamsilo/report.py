"""Markdown reports a user opens: one per case, one per sweep.

``report.md`` sits beside the figures it shows (relative links), so a case
or sweep directory can be copied, zipped or opened in any Markdown viewer
(GitHub, VS Code, pandoc to HTML) as it is.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.case import write_whole
from foamsilo.run import outer_iterations
from foamsilo.summary import RunSummary

REPORT_MD = "report.md"
DISCHARGE_PNG = "discharge.png"


def _fmt(v: Any, spec: str = ".4g") -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


def plot_discharge(summary: RunSummary, path: Path) -> Path:
    """Q against t/sqrt(L/g), with the steady window and the references that apply.

    The references are the ones ``compare`` sets the case against
    (:func:`foamsilo.compare.references`), drawn as a line or as a band.
    """
    from foamsilo.plots import finish, subplots

    red = summary.reduction
    d, st, scene = red.discharge, red.steady, red.scene
    _, scale = scene.flow_rate_scale
    planar = scene.representation == "planar"
    T = scene.time_scale
    fig, ax = subplots(size=(7, 4.2))
    ax.plot(d.time / T, d.mass_flow / scale, lw=1.2, color="C0", label="simulation, orifice flux")
    if st.steady:
        ax.axvspan(st.t_start / T, st.t_end / T, color="C0", alpha=0.08, label="steady window")
        ax.axhline(st.q / scale, color="C0", ls="--", lw=1, label=f"steady Q = {st.q / scale:.4f}")
        span = [st.t_start / T, st.t_end / T]
        u = red.uncertainty or {}
        if u.get("grid_known") and math.isfinite(u["combined"]):  # 95%: time and grid
            lo, hi = (st.q - u["combined"]) / scale, (st.q + u["combined"]) / scale
            band = f"95% band, time averaging and grid (± {u['relative']:.1%})"
            ax.fill_between(span, lo, hi, facecolor="none", edgecolor="C4", hatch="///",
                            lw=1.0, label=band)  # fmt: skip
        if math.isfinite(st.q_error):  # the error of the time average, 2 standard errors
            lo, hi = (st.q - 2 * st.q_error) / scale, (st.q + 2 * st.q_error) / scale
            band = f"± 2 standard errors of the mean ({2 * st.q_error / st.q:.2%})"
            ax.fill_between(span, lo, hi, color="C0", alpha=0.25, label=band)
    for k, ref in enumerate(summary.references):
        colour = f"C{k + 1}"
        if ref.spread > 0:
            ax.axhspan(
                (ref.q - ref.spread) / scale,
                (ref.q + ref.spread) / scale,
                color=colour,
                alpha=0.15,
                label=ref.label,
            )
        else:
            ax.axhline(ref.q / scale, color=colour, ls=":", lw=1.5, label=ref.label)
    ax.set_xlabel(r"$t/\sqrt{L/g}$")
    ax.set_ylabel(r"$Q/(\rho\sqrt{gL^3})$" if planar else r"$Q/(\rho\sqrt{g}D^{5/2})$")
    ax.set_title(f"{scene.name}: {scene.cells_across} cells across L", fontsize=10)
    top = max([float(np.max(d.mass_flow / scale))] + [r.q / scale for r in summary.references])
    ax.set_ylim(0, 1.2 * top)
    return finish(fig, ax, path)


def _uncertainty_line(s: dict[str, Any], units: str) -> str:
    """Return the rate's 95% band in words: time averaging, and the grid where studied."""
    u = s.get("Q_uncertainty") or {}
    grid = s.get("grid")
    if u.get("grid_known") and grid:
        c = grid["convergence"]
        cells = " / ".join(str(n) for n in grid["cells"])
        values = " / ".join(f"{v:.5g}" for v in grid["values"])
        order = f"observed order {c['order']:.2f}, " if c.get("order") is not None else ""
        if c.get("order_used") is not None and c["order_used"] < c["order"]:
            order += f"taken as the scheme's {c['order_used']:g}, "
        elif c.get("order_used") is not None and c["order_used"] > c["order"]:
            order += f"not yet asymptotic, taken as {c['order_used']:g} (Eca & Hoekstra 2014), "
        ext = (f"extrapolated {c['extrapolated']:.5g} {units}, "
               if c.get("extrapolated") is not None else "")  # fmt: skip
        return (
            f"* uncertainty (95%): **± {u['combined']:.2g} {units} ({u['relative']:.1%})**: "
            f"time averaging ± {u['time']:.2g} (2 standard errors), grid ± {u['grid']:.2g} "
            f"(GCI of {cells} cells across: Q = {values}, {c['kind']}, {order}{ext}"
            "Celik et al. 2008);"
        )
    why = grid["reason"] if grid else "no grid study (`foamsilo run ... --grid-error`)"
    return (
        f"* uncertainty (95%): time averaging ± {_fmt(u.get('time'), '.2g')} {units}; "
        f"the grid error is not known: {why};"
    )


def case_report(summary: RunSummary) -> Path:
    """Write ``discharge.png`` and ``report.md`` for a reduced case; return the report's path."""
    case = summary.case
    plot_discharge(summary, case / DISCHARGE_PNG)
    s = summary.as_json()
    scene = summary.reduction.scene
    sil, mat = scene.silo, scene.material
    run = s.get("run") or {}
    units = s.get("Q_units", "")
    out = [
        f"# {scene.name}: discharge report",
        "",
        f"Case `{case.name}/`, {s.get('representation')} mesh of {_fmt(s.get('cells'))} cells "
        f"({s.get('cells_across')} across L, {s.get('cells_across_orifice')} across D"
        f"{', graded away from the orifice' if s.get('graded') else ''}), "
        f"{s['simulated_time_s']:.4g} s simulated.",
        "",
        "## Scene",
        "",
        "| silo | L [m] | H [m] | fill [m] | D [m] | grains d [m] | rho [kg/m^3] | gas |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
        f"| {sil.shape}, {sil.orifice_position} orifice | {sil.width:g} | {sil.height:g} "
        f"| {sil.fill_height:g} | {sil.orifice_width:g} | {mat.grain_diameter:g} "
        f"| {mat.density:g} | {scene.gas.mode} |",
        "",
        "## Discharge rate",
        "",
    ]
    if s.get("steady"):
        w = s["steady_window_s"]
        out += [
            f"* steady Q = **{s['Q']:.5g} {units}**, standard error of the time average "
            f"{_fmt(s.get('Q_time_error'), '.2g')} (batch means), fluctuation {s['Q_std']:.2g} "
            f"(Q* = {s['Q_dimensionless']:.4f}, scale {s['flow_rate_scale']['name']}), "
            f"mean of the instantaneous rate over t = {w[0]:.3g} to {w[1]:.3g} s;",
            f"* from the decrease of the granular volume: {s['Q_from_volume']:.5g} {units} "
            f"({s['flux_vs_volume_rel_diff']:.2%} from the orifice flux);",
            f"* drift over the window {s['drift']:+.1%}, largest excursion {s['excursion']:.1%};",
        ]
        out.append(_uncertainty_line(s, units))
        ref = s.get("reference")
        if ref and ref.get("rel_diff") is not None:
            out.append(f"* against {ref['source']}: {ref['rel_diff']:+.1%};")
    else:
        out.append(f"* **no steady regime**: {s.get('steady_reason')}")
    for w in s.get("warnings") or []:
        out.append(f"* **warning**: {w};")
    out += [
        f"* grains conserved to {s['mass_balance_rel_error']:.1e} of the initial volume.",
        "",
        "![Q(t)](discharge.png)",
        "",
    ]
    f = s.get("fields") or {}
    if "error" in f:
        out += ["## Fields", "", f"Field output could not be reduced: {f['error']}", ""]
    elif f:
        fs = f["free_surface_m"]
        out += [
            "## Fields",
            "",
            f"At t = {f['time_s']:g} s (read {f['case_type']}):",
            "",
            f"* free surface: {fs['axis_m']:.4g} m on the axis, {fs['wall_m']:.4g} m at the "
            f"wall, {fs['mean_m']:.4g} m mean;",
            f"* grains at the viscosity cap (stagnant or moving as a rigid block): "
            f"{f['stagnant_fraction']:.1%} of the granular volume;",
            f"* velocity across the silo at y = {f['profile_height_m']:.4g} m (0.15 H): largest "
            f"downward speed {_fmt(f['profile_max_downward_m_s'], '.3g')} m/s, mass flow "
            f"through the line {_fmt(f['profile_mass_flow'], '.5g')} {units}.",
            "",
            "![where the flow is: the silo and the orifice region](orifice.png)",
            "",
            "![mid-plane fields](fields.png)",
            "",
            "![velocity profile](profile_U.png) ![free surface](free_surface.png)",
            "",
        ]
    pp = s.get("pore_pressure")
    if pp:
        out += [
            "## Pore pressure",
            "",
            f"* gradient near the orifice (eq. 20): {pp['gradient_near']:.4g} Pa/m; far from "
            f"it: {pp['gradient_far']:.4g} Pa/m (theory), {pp['gradient_far_fit']:.4g} Pa/m "
            "(least squares over the taps above 1.5 D);",
            f"* the two lines cross at {pp['slope_change_over_D']:.2f} D above the orifice;",
            f"* relative gas flux Q_air - Q/rho = {pp['relative_gas_flux']:.4g}, measured "
            f"through the orifice {pp['relative_gas_flux_measured']:.4g}.",
            "",
        ]
        taps = pp.get("taps") or []
        if taps:
            out += ["| tap height [m] | mean pore pressure [Pa] |", "| --- | --- |"]
            out += [f"| {t['y']:.4g} | {_fmt(t['pressure'], '.5g')} |" for t in taps]
            out.append("")
        if (case / "pore_pressure.png").exists():
            out += ["![pore pressure along the axis](pore_pressure.png)", ""]
    if (case / "compare.md").exists():
        out += ["## Against the analytic law", "", (case / "compare.md").read_text(), ""]
    if run:
        out += [
            "## Run",
            "",
            f"{_fmt(run.get('steps'))} time steps, {_fmt(run.get('wall_seconds'), '.1f')} s wall, "
            f"{_fmt(run.get('cpu_seconds'), '.1f')} s CPU on {run.get('n_procs', 1)} rank(s)"
            + (f" of {run['cpu']}." if run.get("cpu") else "."),
            "",
            f"Scheme: {outer_iterations(scene.outer_correctors)} per step, the granular "
            f"stress's share of a pressure change {scene.stress_pressure_coupling} in the "
            f"projection, the {scene.numerics.open_boundary_acceleration}'s acceleration on "
            "the open boundaries (docs/solver.md).",
            "",
        ]
        if run.get("emptied_at") is not None:
            out += [
                f"The silo emptied: the run ended at t = {_fmt(run['emptied_at'], '.4g')} s "
                f"(of {_fmt(scene.run.end_time, 'g')} s), with less than half a width of "
                "grains left (`run.stop_when_empty`).",
                "",
            ]
        for k, r in enumerate(run.get("recoveries") or [], start=1):
            out.append(
                f"* recovery {k}: {r['quantity']} diverged at t = {_fmt(r['time'], '.6g')} s "
                f"(steps of {_fmt(r['delta_t'], '.3g')} s); restarted from t = "
                f"{_fmt(r['restart_time'], '.6g')} s with the step capped at "
                f"{_fmt(r['max_delta_t'], '.3g')} s"
                + (
                    f", {outer_iterations(r['outer_correctors'])} per step"
                    if r.get("outer_correctors")
                    else ""
                )
                + _release_said(r)
            )
        retakes = run.get("step_retakes") or []
        if retakes:
            out += [
                f"The solver took {len(retakes)} step(s) again from their start with half the "
                "step, their outer iterations having diverged (`run.max_step_retakes`; "
                "docs/solver.md):",
                "",
            ]
            out += [
                f"* t = {_fmt(r['time'], '.6g')} s, step {_fmt(r['delta_t'], '.3g')} s taken "
                f"again with {_fmt(r['retake_delta_t'], '.3g')} s: {r['detail']}"
                for r in retakes
            ]
            out.append("")
        share_retakes = run.get("share_retakes") or []
        if share_retakes:
            growth = max(r["growth"] for r in share_retakes)
            change = max(r.get("change", 0.0) for r in share_retakes)
            out += [
                f"The solver took {len(share_retakes)} step(s) again at the same step with half "
                "the stress's divergence share, their outer iterations growing (by up to "
                f"{_fmt(growth, '.3g')} times; `numerics.outer_growth_limit`) or the last moving "
                f"a grain too far (up to {_fmt(100 * change, '.3g')}% of the fastest grain's "
                "speed; `numerics.outer_change_limit`; docs/solver.md).",
                "",
            ]
            failed = [r for r in share_retakes if r.get("failed")]
            if failed:
                out += [
                    f"{len(failed)} of them failed at half the share and were taken as the whole "
                    f"share first took them (first at t = {_fmt(failed[0]['time'], '.6g')} s: "
                    f"{failed[0]['failed']}).",
                    "",
                ]
        if run.get("recoveries"):
            out += [
                "",
                "With the attempts before the last: "
                f"{_fmt(run.get('wall_seconds_all_attempts'), '.1f')} s wall, "
                f"{_fmt(run.get('cpu_seconds_all_attempts'), '.1f')} s CPU.",
                "",
            ]
    path = case / REPORT_MD
    write_whole(path, "\n".join(out))
    return path


def sweep_report(output: Path) -> Path:
    """Write ``report.md`` for a sweep output directory (table, comparison, case links)."""
    output = Path(output).resolve()
    table = json.loads((output / "summary.json").read_text())
    rows = table["cases"]
    fixed = {"case", "directory", "status", "error"}
    keys = [k for k in rows[0] if k not in fixed] if rows else []
    out = [
        f"# Sweep report: {output.name}",
        "",
        f"Base scene `{table['base']}`, {len(rows)} cases "
        f"({sum(r['status'] == 'ok' for r in rows)} finished). Table: `summary.csv`.",
        "",
        "| case | " + " | ".join(keys) + " | status | report |",
        "| --- | " + " | ".join("---" for _ in keys) + " | --- | --- |",
    ]
    for r in rows:
        d = Path(r["directory"])
        link = f"[{d.name}]({d}/{REPORT_MD})" if (d / REPORT_MD).exists() else "-"
        vals = [_fmt(r.get(k)) for k in keys]
        out.append(f"| {r['case']} | " + " | ".join(vals) + f" | {r['status']} | {link} |")
    out.append("")
    if (output / "compare.md").exists():
        out += ["## Against the analytic laws", "", (output / "compare.md").read_text(), ""]
        out += ["![simulation points on the analytic curves](compare.png)", ""]
    path = output / REPORT_MD
    write_whole(path, "\n".join(out))
    return path


def _release_said(recovery: dict[str, Any]) -> str:
    """How a recovery's step cap ended: put back at a time, or kept to the end."""
    if recovery.get("released_at") is not None:
        return f", put back to the scene's settings at t = {_fmt(recovery['released_at'], '.6g')} s"
    if "release_time" in recovery and recovery["release_time"] is None:
        return ", kept to the end (it diverged again after its settings were put back)"
    return ""
