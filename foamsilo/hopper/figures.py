"""The paper's figures and the work-precision study (``foamsilo hopper figures``, ``bench hopper``).

* Fig. 9: the admissible transitions theta_w for an upper cone Theta_w
  (delta = 32.1 deg, mu = tan 11.7 deg): the characteristic bound of the
  paper, the largest psi of the upper radial field, and at
  Theta_w = 30 deg the range the DG march actually completes.
* Fig. 10: preservation of the radial field over 95% of the hopper, wedge
  and cone, P1, N = 400.
* Figs 11-14: transitions cone 30 -> 24 (P1 N = 400 and P2 N = 200),
  cone 30 -> 25, wedge 30 -> 25, wedge 30 -> 35, the stresses scaled by r.
* Work precision: error against the radial field and wall time for
  k = 0, 1, 2 over a range of N.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.hopper.dg import DGResult, HopperDG
from foamsilo.hopper.radial import (
    DELTA_PAPER,
    PHI_W_PAPER,
    HopperError,
    Material,
    radial_field,
)
from foamsilo.hopper.transition import solve_transition
from foamsilo.plots import finish, labelled_loglog, subplots

PAPER = Material.degrees(DELTA_PAPER, PHI_W_PAPER)
#: tau at 95% of the way down from r0 (r = 0.05 r0)
TAU_95 = -math.log(0.05)


def warm_up() -> None:
    """Compile (or load from cache) the DG kernel so that timings exclude it."""
    f = radial_field(3, 20, PAPER)
    dg = HopperDG(3, f.theta_w, PAPER, k=1, cells=4)
    ref = (lambda th: f.stresses(th)["Trr"], lambda th: f.stresses(th)["Trt"])
    dg.solve(dg.project(*ref), 0.01, reference=ref, records=1)
    dg.solve(dg.project(*ref), 0.01, records=1)


# ------------------------------------------------------------------ Fig. 9
def transition_chart(
    upper: np.ndarray,
    material: Material = PAPER,
    bar_at: float | None = 30.0,
    bar_step: float = 0.25,
) -> dict[str, Any]:
    """Admissible lower-hopper angles for each upper cone angle (Fig. 9 data).

    Returns per Theta_w: the largest psi of the radial field and whether it
    is monotonic; the paper's bound Theta_w - arctan(1/lambda_max) with
    lambda_max the largest |eigenvalue| over the upper radial field. (The
    rotated initial condition on Gamma_0 itself stays hyperbolic for every
    theta_w here whenever the upper field is: the limit comes from the
    march.) At ``bar_at`` the range of theta_w (step ``bar_step``) for which
    the DG march (P1, N = 100) reaches 95% of the lower hopper.
    """
    rows = []
    lim = material.psi_hyperbolic
    for big in upper:
        try:
            f = radial_field(3, float(big), material)
        except HopperError:
            continue
        psi_max, _ = f.psi_max()
        th = np.linspace(0, f.theta_w, 401)
        st = f.stresses(th)
        dg = HopperDG(3, f.theta_w, material, k=0, cells=2)
        l1, l2 = dg.eigenvalues(st["Trr"], st["Trt"])
        lam = float(max(np.abs(l1).max(), np.abs(l2).max()))
        bound = float(big) - math.degrees(math.atan(1 / lam))

        rows.append(
            {
                "upper_deg": float(big),
                "psi_max_deg": math.degrees(psi_max),
                "psi_monotonic": f.psi_monotonic(),
                "lambda_max": lam,
                "paper_bound_deg": bound,
            }
        )
    bar = None
    if bar_at is not None:
        done = []
        for lower in np.arange(bar_at - 15.0, bar_at + 4.0 + 1e-9, bar_step):
            r, _ = solve_transition(3, bar_at, float(lower), material, k=1, cells=100, records=2)
            if r.status == "ok":
                done.append(float(lower))
        bar = {
            "upper_deg": bar_at,
            "completes_deg": done,
            "min_deg": min(done) if done else None,
            "max_deg": max(done) if done else None,
        }
    return {"rows": rows, "bar": bar, "psi_limit_deg": math.degrees(lim)}


def plot_transition_chart(chart: dict[str, Any], path: Path) -> Path:
    """Fig. 9."""
    fig, ax = subplots(size=(6, 5))
    # beyond psi_max = pi/4 - delta/2 no initial condition is hyperbolic at all
    rows = [r for r in chart["rows"] if r["psi_max_deg"] < chart["psi_limit_deg"]]
    up = np.array([r["upper_deg"] for r in rows])
    ax.plot(up, up, "k:", lw=1, label=r"$\theta_w = \Theta_w$")
    ax.plot(
        up,
        [r["paper_bound_deg"] for r in rows],
        "C0-",
        label=r"C: $\Theta_w - \arctan(1/\lambda_{max})$",
    )
    bar = chart.get("bar")
    if bar and bar["min_deg"] is not None:
        ax.plot(
            [bar["upper_deg"]] * 2,
            [bar["min_deg"], bar["max_deg"]],
            "C3-",
            lw=4,
            label=f"DG completes 95% (P1, N=100): {bar['min_deg']:g}-{bar['max_deg']:g} deg",
        )
    ax.set_xlabel(r"upper cone half angle $\Theta_w$ [deg]")
    ax.set_ylabel(r"lower cone half angle $\theta_w$ [deg]")
    ax.set_title(
        r"Fig. 9: admissible transitions, $\delta$ = 32.1, $\mu$ = tan 11.7 deg", fontsize=9
    )
    ax.set_xlim(0, up.max() + 2)
    ax.set_ylim(0, up.max() + 2)
    return finish(fig, ax, path, legend_size=7)


# ----------------------------------------------------------------- Fig. 10
#: Wall friction of the perturbed initial condition (the paper's IC "does not
#: exactly satisfy the boundary conditions"): 0.5 deg off the wall's 11.7
PERTURBED_PHI_W = 11.2


def preservation(
    k: int = 1, cells: int = 400, material: Material = PAPER, theta_w: float = 30.0
) -> dict[int, DGResult]:
    """Radial-field preservation over 95% of the wedge (2) and cone (3)."""
    return {
        dim: solve_transition(
            dim,
            theta_w,
            theta_w,
            material,
            k=k,
            cells=cells,
            records=300,
        )[0]
        for dim in (2, 3)
    }


def perturbed_preservation(
    dim: int,
    k: int = 1,
    cells: int = 200,
    theta_w: float = 30.0,
    ic_phi_w: float = PERTURBED_PHI_W,
    records: int = 100,
) -> DGResult:
    """March from a radial field that misses the wall condition, against the true one.

    The initial condition is the radial field of a wall friction ``ic_phi_w``
    (scaled to the same axis stress): a smooth field that violates
    T_rt = -mu T_tt at the wall by about ``11.7 - ic_phi_w`` degrees of
    friction angle. The waves it sends off are what the paper sees in Fig. 10:
    in the wedge they reflect at the axis and keep growing, in the cone they
    meet from all around the axis and the field settles back to radial.
    """
    true = radial_field(dim, theta_w, PAPER)  # type: ignore[arg-type]
    off = radial_field(dim, theta_w, Material.degrees(DELTA_PAPER, ic_phi_w, PAPER.rho_g))  # type: ignore[arg-type]
    scale = true.sigma0 / off.sigma0
    dg = HopperDG(dim, true.theta_w, PAPER, k=k, cells=cells)  # type: ignore[arg-type]
    u0 = dg.project(
        lambda th: scale * off.stresses(th)["Trr"], lambda th: scale * off.stresses(th)["Trt"]
    )
    ref = (lambda th: true.stresses(th)["Trr"], lambda th: true.stresses(th)["Trt"])
    return dg.solve(u0, TAU_95, reference=ref, records=records)


def plot_preservation(
    results: dict[int, DGResult],
    path: Path,
    k: int,
    cells: int,
    perturbed: dict[int, DGResult] | None = None,
) -> Path:
    """Fig. 10: max relative difference to the radial field against tau, in %."""
    fig, axes = subplots(2, (10, 4))
    bounds = {2: 0.025, 3: 0.5}
    for ax, (dim, r) in zip(axes, sorted(results.items()), strict=True):
        assert r.error is not None
        ax.plot(r.tau, 100 * r.error, "k-", lw=1, label=f"P{k}, N = {cells}, radial IC")
        if perturbed and dim in perturbed and perturbed[dim].error is not None:
            p = perturbed[dim]
            assert p.error is not None
            ax.plot(
                p.tau,
                100 * p.error,
                "C0-",
                lw=1,
                label=f"IC missing the wall law (phi_w {PERTURBED_PHI_W} deg)",
            )
        ax.axhline(bounds[dim], color="C3", ls="--", lw=1, label=f"paper's largest: {bounds[dim]}%")
        ax.set_yscale("log")
        ax.set_xlabel(r"$\tau = -\ln r$")
        ax.set_ylabel("max difference to the radial field [%]")
        ax.set_title(f"{'wedge' if dim == 2 else 'cone'}, theta_w = 30 deg", fontsize=9)
    return finish(fig, axes, path, legend_size=7)


# --------------------------------------------------------------- Figs 11-14
TRANSITIONS = {
    "fig11a": (3, 30.0, 24.0, 1, 400),
    "fig11b": (3, 30.0, 24.0, 2, 200),
    "fig12": (3, 30.0, 25.0, 1, 400),
    "fig13": (2, 30.0, 25.0, 1, 400),
    "fig14": (2, 30.0, 35.0, 1, 400),
}


def plot_stress_maps(result: DGResult, dg: HopperDG, title: str, path: Path) -> Path:
    """R T_rr, r T_rt, r T_tt over (theta, r/r0): the approach to (or away from) a radial field."""
    fig, axes = subplots(3, (13, 4.2))
    theta = np.degrees(result.theta)
    r = np.exp(-result.tau)[:, None]
    a, b = result.t_rr, result.t_rt
    c = dg.alpha * a + np.sqrt(np.maximum(dg.beta * a * a + dg.gamma * b * b, 0))
    for ax, (name, v) in zip(axes, (("r T_rr", a), ("r T_rt", b), ("r T_tt", c)), strict=True):
        scaled = v / r  # stresses per unit r [Pa/m]
        mesh = ax.pcolormesh(theta, r[:, 0], scaled, shading="nearest", cmap="viridis")
        fig.colorbar(mesh, ax=ax, shrink=0.85, label="[Pa/m]")
        ax.set_xlabel(r"$\theta$ [deg]")
        ax.set_ylabel(r"$r/r_0$")
        ax.invert_yaxis()
        ax.set_title(f"{name.replace('r ', '')} / r", fontsize=9)
    fig.suptitle(title, fontsize=10)
    return finish(fig, axes, path, legend_size=6)


def transitions(out: Path, only: list[str] | None = None) -> dict[str, Any]:
    """Run the transitions of Figs 11-14 and draw them into ``out``."""
    rows = {}
    for name, (dim, up, lo, k, n) in TRANSITIONS.items():
        if only and name not in only:
            continue
        r, dg = solve_transition(dim, up, lo, PAPER, k=k, cells=n, records=200)  # type: ignore[arg-type]
        shape = "cone" if dim == 3 else "wedge"
        title = f"{shape} {up:g} -> {lo:g} deg, P{k}, N = {n}: {r.status}"
        if len(r.tau):
            plot_stress_maps(r, dg, title, out / f"hopper-{name}.png")
        rows[name] = {
            "dim": dim,
            "upper_deg": up,
            "lower_deg": lo,
            "k": k,
            "cells": n,
            "status": r.status,
            "steps": r.steps,
            "wall_s": round(r.wall_s, 2),
            "stop": r.stop,
            "file": f"hopper-{name}.png" if len(r.tau) else None,
        }
    return rows


# ---------------------------------------------------------- work precision
def work_precision(
    dims: tuple[int, ...] = (2, 3),
    ks: tuple[int, ...] = (0, 1, 2),
    cells: tuple[int, ...] = (25, 50, 100, 200, 400),
) -> dict[str, Any]:
    """Error against the radial field (max over the 95% march) and wall time."""
    warm_up()
    rows = []
    for dim in dims:
        for k in ks:
            for n in cells:
                r, _ = solve_transition(dim, 30.0, 30.0, PAPER, k=k, cells=n, records=50)  # type: ignore[arg-type]
                assert r.error is not None
                rows.append(
                    {
                        "dim": dim,
                        "k": k,
                        "cells": n,
                        "steps": r.steps,
                        "wall_s": round(r.wall_s, 4),
                        "max_rel_error": float(r.error.max()),
                        "status": r.status,
                    }
                )
    return {
        "benchmark": "hopper",
        "rows": rows,
    }


def plot_work_precision(result: dict[str, Any], path: Path) -> Path:
    """Error against wall time, one line per (dim, k)."""
    fig, axes = subplots(2, (11, 4.2))
    for ax, dim in zip(axes, (2, 3), strict=True):
        for k in (0, 1, 2):
            rows = [r for r in result["rows"] if r["dim"] == dim and r["k"] == k]
            if not rows:
                continue
            labelled_loglog(ax, rows, "wall_s", "max_rel_error", "cells", f"P{k}")
        ax.set_xlabel("wall time [s] (one core)")
        ax.set_ylabel("max difference to the radial field [%]")
        ax.set_title(
            f"{'wedge' if dim == 2 else 'cone'} 30 deg, 95% of the hopper (labels: N)", fontsize=9
        )
    return finish(fig, axes, path)


def work_precision_markdown(result: dict[str, Any]) -> str:
    """Return the table of the work-precision study (Markdown)."""
    m = result.get("machine") or {}
    lines = [
        f"Machine: {m.get('cpu', '?')}, one core; commit {result.get('commit')}; 30 deg hopper, "
        "delta = 32.1 deg, mu = tan 11.7 deg, P^k DG marched from r0 to 0.05 r0 (95%); error: "
        "largest difference to the radial field over the march, relative to max T_rr.",
        "",
        "| hopper | k | N | steps | wall [s] | max difference to radial |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for r in result["rows"]:
        lines.append(
            f"| {'wedge' if r['dim'] == 2 else 'cone'} | {r['k']} | {r['cells']} "
            f"| {r['steps']} | {r['wall_s']:.3f} "
            f"| {100 * r['max_rel_error']:.2e} % |"
        )
    return "\n".join(lines)
