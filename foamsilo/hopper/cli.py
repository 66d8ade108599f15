"""``foamsilo hopper radial|solve|transition|figures``: the hopper stress models."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.hopper.radial import DELTA_PAPER, PHI_W_PAPER, RHO_G_CORN, Material, radial_field


def _material(args: argparse.Namespace) -> Material:
    return Material.degrees(args.delta, args.phi_w, args.rho_g)


def radial(args: argparse.Namespace) -> dict[str, Any]:
    """Radial stress field on a grid from the axis to the wall."""
    m = _material(args)
    f = radial_field(args.dim, args.theta_w, m)
    th = np.linspace(0.0, f.theta_w, args.points)
    sig, psi = f.sigma_psi(th)
    st = f.stresses(th)
    psi_max, at = f.psi_max()
    return {
        "dim": args.dim,
        "theta_w_deg": args.theta_w,
        "psi_w": m.psi_w,
        "psi_w_deg": math.degrees(m.psi_w),
        "chi_w": m.chi_w,
        "psi_max_deg": math.degrees(psi_max),
        "psi_max_at_deg": math.degrees(at),
        "psi_monotonic": f.psi_monotonic(),
        "units": "stresses per unit r [Pa/m], compressive positive; angles in rad",
        "theta": th.tolist(),
        "sigma": sig.tolist(),
        "psi": psi.tolist(),
        "Trr": st["Trr"].tolist(),
        "Ttt": st["Ttt"].tolist(),
        "Trt": st["Trt"].tolist(),
        "Tpp": st["Tpp"].tolist(),
    }


def solve(args: argparse.Namespace) -> dict[str, Any]:
    """DG march down the hopper (a transition when --upper-theta-w differs)."""
    from foamsilo.hopper.figures import plot_stress_maps, warm_up
    from foamsilo.hopper.transition import solve_transition

    warm_up()
    upper = args.upper_theta_w if args.upper_theta_w is not None else args.theta_w
    r, dg = solve_transition(
        args.dim, upper, args.theta_w, _material(args), k=args.k, cells=args.cells, depth=args.depth
    )
    out: dict[str, Any] = {
        "dim": args.dim,
        "k": args.k,
        "cells": args.cells,
        "theta_w_deg": args.theta_w,
        "upper_theta_w_deg": upper,
        "depth": args.depth,
        "status": r.status,
        "steps": r.steps,
        "wall_s": r.wall_s,
        "tau_reached": float(r.tau[-1]) if len(r.tau) else 0.0,
    }
    if r.error is not None and len(r.error):
        out["max_rel_error_vs_radial"] = float(r.error.max())
        out["final_rel_error_vs_radial"] = float(r.error[-1])
    if r.stop:
        out["stop"] = r.stop
    if args.picture and len(r.tau):
        title = f"{'cone' if args.dim == 3 else 'wedge'} {upper:g} -> {args.theta_w:g} deg"
        out["picture"] = str(plot_stress_maps(r, dg, title, Path(args.picture)))
    return out


def figures(args: argparse.Namespace) -> dict[str, Any]:
    """Figs 9-14 of the paper into --output (PNG + JSON)."""
    from foamsilo.hopper import figures as fg

    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    fg.warm_up()
    chart = fg.transition_chart(np.arange(2.0, 46.0, 1.0))
    fg.plot_transition_chart(chart, out / "hopper-fig9.png")
    pres = fg.preservation(k=1, cells=400)
    perturbed = {d: fg.perturbed_preservation(d) for d in (2, 3)}
    fg.plot_preservation(pres, out / "hopper-fig10.png", 1, 400, perturbed)
    trans = fg.transitions(out)
    result = {
        "fig9": chart,
        "fig10": {
            str(d): {
                "max_rel_error": float(r.error.max()) if r.error is not None else None,
                "final_rel_error": float(r.error[-1]) if r.error is not None else None,
                "wall_s": r.wall_s,
                "steps": r.steps,
            }
            for d, r in pres.items()
        },
        "fig10_perturbed": {
            str(d): {"error_start": float(r.error[1]), "error_end": float(r.error[-1])}
            for d, r in perturbed.items()
            if r.error is not None
        },
        "transitions": trans,
    }
    (out / "hopper-figures.json").write_text(json.dumps(result, indent=1, default=str) + "\n")
    return result


def register(sub: Any, add_json: Callable[[Any], None]) -> None:
    """Add the ``hopper`` command and its forms to the CLI."""
    from foamsilo.analytic.cli import command_with_forms

    form = command_with_forms(sub, "hopper", "hopper stresses: radial fields and the DG solver",
                              "Steady hopper stresses (Gremaud & Matthews).", add_json)  # fmt: skip

    def material(sp: Any) -> None:
        sp.add_argument("--dim", type=int, choices=[2, 3], default=3, help="2 wedge, 3 cone")
        sp.add_argument("--delta", type=float, default=DELTA_PAPER, help="internal friction [deg]")
        sp.add_argument("--phi-w", type=float, default=PHI_W_PAPER, help="wall friction [deg]")
        sp.add_argument("--theta-w", type=float, default=30.0, help="half angle [deg]")
        sp.add_argument("--rho-g", type=float, default=RHO_G_CORN, help="rho g [N/m^3]")

    sp = form("radial", radial, "Jenike radial stress field (eqs 16-17)")
    material(sp)
    sp.add_argument("--points", type=int, default=101, help="grid points axis to wall")

    for name, help_ in (
        ("solve", "DG march down the hopper (eq. 12, sec. 5)"),
        ("transition", "a wall-angle transition (sec. 6): --upper-theta-w"),
    ):
        sp = form(name, solve, help_)
        material(sp)
        sp.add_argument("--k", type=int, choices=[0, 1, 2], default=1, help="polynomial degree")
        sp.add_argument("--cells", type=int, default=400, help="cells N across the half hopper")
        sp.add_argument(
            "--upper-theta-w",
            type=float,
            required=name == "transition",
            help="upper hopper half angle [deg] (a transition when it differs)",
        )
        sp.add_argument("--depth", type=float, default=0.95, help="fraction of r0 marched")
        sp.add_argument("--picture", help="PNG of the stresses scaled by r")

    sp = form("figures", figures, "the paper's Figs 9-14 (PNG, JSON)")
    sp.add_argument("-o", "--output", default="docs/hopper", help="directory")
