"""``foamsilo analytic ...``: the plain-Python models from the command line."""

from __future__ import annotations

import argparse
import csv
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.analytic import beverloo, exact, fit, zhou
from foamsilo.errors import FoamsiloError


def _q_air(args: argparse.Namespace) -> float:
    if args.q_air is not None and args.q_air_lpm is not None:
        raise FoamsiloError("give --q-air (m^3/s) or --q-air-lpm (L/min), not both")
    if args.q_air is not None:
        return float(args.q_air)
    return float(args.q_air_lpm or 0.0) * zhou.LPM


def gas(args: argparse.Namespace) -> dict[str, Any]:
    """Eq. 23 with the Table I constants of a preset."""
    r = zhou.gas_assisted(
        args.preset, args.d, _q_air(args), D=args.orifice, W=args.width, phi_b=args.phi_b,
        rho_p=args.rho_p, A=args.A, inertial=not args.no_inertial, phi_o=args.phi_o,
    )  # fmt: skip
    out = r.as_dict()
    out.update(preset=args.preset, silo_width=args.silo_width, q_air_m3s=_q_air(args))
    return out


def open_top(args: argparse.Namespace) -> dict[str, Any]:
    """Eq. 1 (bottom) or eq. 24 (lateral), and eq. 2/25 for phi_o."""
    c = zhou.config(args.preset)
    D = args.orifice or c.orifice_sizes[0]
    W = args.width or (c.orifice_widths[0] if c.orifice_widths else None)
    if c.position == "bottom":
        q0 = zhou.q0_bottom(D, args.d, args.phi_b, args.rho_p, c.C0 or math.nan, c.alpha_D,
                            c.beta, zhou.orifice_area(c, D, W))  # fmt: skip
        law = "eq. 1"
    else:
        q0 = zhou.q0_lateral(D, W or D, args.d, args.phi_b, args.rho_p, c.C0l or math.nan,
                             c.alpha_D, c.alpha_W, c.beta, c.gamma2)  # fmt: skip
        law = "eq. 24"
    phi_o = None
    if c.xi_phi is not None:
        lat_w = W if c.position == "lateral" else None
        phi_o = float(zhou.phi_orifice(D, args.d, args.phi_b, c.xi_phi, c.alpha_D, c.beta,
                                       lat_w, c.alpha_W))  # fmt: skip
    return {"preset": c.name, "law": law, "Q0": float(q0), "phi_o": phi_o, "D": D, "W": W}


def impermeable(args: argparse.Namespace) -> dict[str, Any]:
    """Eq. 3: Q = rho_p phi_b Q_air."""
    qa = _q_air(args)
    return {"Q": float(zhou.q_impermeable(qa, args.phi_b, args.rho_p)), "q_air_m3s": qa}


def beverloo_2d(args: argparse.Namespace) -> dict[str, Any]:
    """Slot Beverloo law per unit depth."""
    c = beverloo.beverloo_2d_constant() if args.C is None else args.C
    q = float(beverloo.beverloo_2d(args.orifice, args.rho, args.g, c, args.k, args.d or 0.0))
    out: dict[str, Any] = {"Q_per_depth": q, "C": c, "k": args.k}
    if args.silo_width:
        out["Q_dimensionless"] = q / (args.rho * math.sqrt(args.g * args.silo_width**3))
    return out


def bagnold(args: argparse.Namespace) -> dict[str, Any]:
    """Steady mu(I) flow down an incline."""
    th = math.radians(args.theta_deg)
    z = np.linspace(0.0, args.depth, args.points)
    u = exact.bagnold_velocity(z, args.depth, th, args.mu_s, args.delta_mu, args.i0, args.d)
    return {
        "inertial_number": exact.bagnold_inertial_number(th, args.mu_s, args.delta_mu, args.i0),
        "z": z.tolist(),
        "u": u.tolist(),
        "surface_velocity": float(u[-1]),
        "mean_velocity": exact.bagnold_mean_velocity(
            args.depth, th, args.mu_s, args.delta_mu, args.i0, args.d
        ),
        "max_viscosity": exact.bagnold_max_viscosity(
            args.depth, th, args.mu_s, args.delta_mu, args.i0, args.d, args.rho
        ),
    }


def janssen(args: argparse.Namespace) -> dict[str, Any]:
    """Hydrostatic and Janssen stresses down a silo."""
    R = exact.hydraulic_radius(args.shape, args.width, args.thickness)
    s = np.linspace(0.0, args.depth, args.points)
    sv = exact.janssen_vertical_stress(s, args.rho, R, args.K, args.mu_w)
    return {
        "hydraulic_radius": R,
        "depth": s.tolist(),
        "hydrostatic": exact.hydrostatic_pressure(s, args.rho).tolist(),
        "vertical_stress": sv.tolist(),
        "wall_pressure": (args.K * sv).tolist(),
        "saturation": args.rho * 9.81 * R / (args.K * args.mu_w),
    }


def darcy_slit(args: argparse.Namespace) -> dict[str, Any]:
    """Darcy flow into the bottom slot of a planar silo, along the axis."""
    y = np.linspace(0.0, args.height, args.points)
    p = exact.darcy_slit_pressure(0.0, y, args.flux, args.kappa, args.eta, args.slit_width,
                                  args.silo_width)  # fmt: skip
    far = args.eta * args.flux / (args.kappa * (args.silo_width or math.inf))
    return {"y": y.tolist(), "p": p.tolist(), "far_gradient": far}


def table1(args: argparse.Namespace) -> dict[str, Any]:
    """Table I of Zhou et al. 2019."""
    rows = []
    for c in zhou.TABLE_I.values():
        d = dict(c.__dict__)
        d.pop("extra")
        rows.append(d)
    return {"configurations": rows}


def _read_csv(path: str, *cols: str) -> list[np.ndarray]:
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise FoamsiloError(f"{path}: no data rows")
    missing = [c for c in cols if c not in rows[0]]
    if missing:
        raise FoamsiloError(f"{path}: missing columns {missing}; has {list(rows[0])}")
    return [np.array([float(r[c]) for r in rows]) for c in cols]


def fit_open_top(args: argparse.Namespace) -> dict[str, Any]:
    """Fit C0, alpha_D, beta to a CSV with columns D, d, Q (SI)."""
    D, d, Q = _read_csv(args.data, "D", "d", "Q")
    return fit.fit_open_top(D, d, Q, args.phi_b, args.rho_p).as_dict()


def fit_phi(args: argparse.Namespace) -> dict[str, Any]:
    """Fit phi_o (one grain size) or xi_phi (several) to a CSV: d, q_air, Q (SI)."""
    d, qa, Q = _read_csv(args.data, "d", "q_air", "Q")
    kw = {"D": args.orifice, "phi_b": args.phi_b, "rho_p": args.rho_p, "A": args.A}
    if len(np.unique(d)) == 1:
        return fit.fit_phi_o(args.preset, float(d[0]), qa, Q, **kw).as_dict()
    return fit.fit_xi_phi(args.preset, d, qa, Q, **kw).as_dict()


def figures(args: argparse.Namespace) -> dict[str, Any]:
    """Model lines of Zhou Figs 2b, 2c, 7c, 9."""
    from foamsilo.analytic.figures import all_figures

    return {"figures": [str(p) for p in all_figures(Path(args.output))]}


Form = Callable[[str, Callable[[argparse.Namespace], dict[str, Any]], str], Any]


def command_with_forms(sub: Any, name: str, help_: str, description: str,
                       add_json: Callable[[Any], None]) -> Form:  # fmt: skip
    """Add ``foamsilo NAME FORM ...``; return ``form(name, func, help)`` to add a form.

    Each form's function returns the JSON payload (``cmd_analytic`` prints it).
    """
    p = sub.add_parser(name, help=help_, description=description)
    forms = p.add_subparsers(dest="form", required=True, metavar="FORM")

    def form(name: str, func: Callable[[argparse.Namespace], dict[str, Any]], help_: str) -> Any:
        sp = forms.add_parser(name, help=help_, description=help_)
        add_json(sp)
        sp.set_defaults(analytic=func)
        return sp

    return form


def register(sub: Any, add_json: Callable[[Any], None]) -> None:
    """Add the ``analytic`` command and its forms to the CLI."""
    form = command_with_forms(sub, "analytic", "analytic laws and exact solutions (plain Python)",
                              "Analytic discharge laws and exact solutions.", add_json)  # fmt: skip

    def material(sp: Any, preset: bool = True) -> None:
        if preset:
            sp.add_argument("--preset", default="cyl-bottom", choices=list(zhou.TABLE_I),
                            help="Table I configuration")  # fmt: skip
        sp.add_argument("--d", type=float, required=True, help="grain diameter [m]")
        sp.add_argument("--orifice", type=float, help="orifice size D [m] (Table I default)")
        sp.add_argument("--width", type=float, help="orifice width W [m] (rectangular)")
        sp.add_argument("--phi-b", type=float, default=0.6, help="bulk volume fraction")
        sp.add_argument("--rho-p", type=float, default=zhou.GLASS_DENSITY, help="kg/m^3")

    def air(sp: Any) -> None:
        sp.add_argument("--q-air-lpm", type=float, help="injected air flow [L/min]")
        sp.add_argument("--q-air", type=float, help="injected air flow [m^3/s]")

    sp = form("gas", gas, "gas-assisted discharge rate, eqs 1-2 and 17-23")
    material(sp)
    air(sp)
    sp.add_argument("--silo-width", type=float, help="L [m] (reported only)")
    sp.add_argument("--A", type=float, default=1.0, help="zone correction of N_v")
    sp.add_argument("--phi-o", type=float, help="volume fraction at the orifice (eq. 2 default)")
    sp.add_argument("--no-inertial", action="store_true", help="Darcy only (N_i = 0)")

    sp = form("open-top", open_top, "open-top rate, eq. 1 or eq. 24, and phi_o")
    material(sp)

    sp = form("impermeable", impermeable, "zero-permeability limit, eq. 3")
    air(sp)
    sp.add_argument("--phi-b", type=float, default=0.6)
    sp.add_argument("--rho-p", type=float, default=zhou.GLASS_DENSITY)

    sp = form("beverloo-2d", beverloo_2d, "slot Beverloo law per unit depth")
    sp.add_argument("--orifice", type=float, required=True, help="slot width D [m]")
    sp.add_argument("--rho", type=float, default=2500.0)
    sp.add_argument("--g", type=float, default=9.81)
    sp.add_argument("--C", type=float, help="prefactor (default: continuum, 1.28)")
    sp.add_argument("--k", type=float, default=0.0)
    sp.add_argument("--d", type=float, help="grain diameter for the k d correction [m]")
    sp.add_argument("--silo-width", type=float, help="L [m] for Q/(rho sqrt(g L^3))")

    sp = form("bagnold", bagnold, "steady mu(I) flow down an inclined plane")
    sp.add_argument("--theta-deg", type=float, required=True)
    sp.add_argument("--depth", type=float, required=True, help="layer depth h [m]")
    sp.add_argument("--mu-s", type=float, default=0.4)
    sp.add_argument("--delta-mu", type=float, default=0.28)
    sp.add_argument("--i0", type=float, default=0.4)
    sp.add_argument("--d", type=float, required=True, help="grain diameter [m]")
    sp.add_argument("--rho", type=float, default=2500.0)
    sp.add_argument("--points", type=int, default=21)

    sp = form("janssen", janssen, "hydrostatic and Janssen stresses in a silo")
    sp.add_argument("--shape", choices=["cylinder", "slot", "box"], default="cylinder")
    sp.add_argument("--width", type=float, required=True, help="diameter or width [m]")
    sp.add_argument("--thickness", type=float, help="box thickness [m]")
    sp.add_argument("--rho", type=float, default=1500.0, help="bulk density [kg/m^3]")
    sp.add_argument("--K", type=float, default=0.4, help="Janssen coefficient")
    sp.add_argument("--mu-w", type=float, default=0.3, help="wall friction coefficient")
    sp.add_argument("--depth", type=float, required=True, help="fill depth [m]")
    sp.add_argument("--points", type=int, default=21)

    sp = form("darcy-slit", darcy_slit, "Darcy flow into the bottom slot of a planar silo")
    sp.add_argument("--slit-width", type=float, required=True, help="D [m]")
    sp.add_argument("--silo-width", type=float, help="L [m] (omit: half-plane)")
    sp.add_argument("--flux", type=float, required=True, help="gas flux per depth [m^2/s]")
    sp.add_argument("--kappa", type=float, required=True, help="permeability [m^2]")
    sp.add_argument("--eta", type=float, default=zhou.AIR_VISCOSITY)
    sp.add_argument("--height", type=float, required=True, help="profile up to this y [m]")
    sp.add_argument("--points", type=int, default=21)

    form("table1", table1, "Table I of Zhou et al. 2019")

    sp = form("fit-open-top", fit_open_top, "fit C0, alpha_D, beta (CSV: D, d, Q in SI)")
    sp.add_argument("data")
    sp.add_argument("--phi-b", type=float, default=0.6)
    sp.add_argument("--rho-p", type=float, default=zhou.GLASS_DENSITY)

    sp = form("fit-phi", fit_phi, "fit phi_o or xi_phi (CSV: d, q_air, Q in SI)")
    sp.add_argument("data")
    sp.add_argument("--preset", default="cyl-bottom", choices=list(zhou.TABLE_I))
    sp.add_argument("--orifice", type=float)
    sp.add_argument("--phi-b", type=float, default=0.6)
    sp.add_argument("--rho-p", type=float, default=zhou.GLASS_DENSITY)
    sp.add_argument("--A", type=float, default=1.0)

    sp = form("figures", figures, "model lines of Zhou Figs 2b, 2c, 7c, 9")
    sp.add_argument("-o", "--output", default="docs/figures", help="directory")
