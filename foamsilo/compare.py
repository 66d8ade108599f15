"""Simulation points on the analytic curves: ``foamsilo compare CASE|SWEEP``.

Each finished case (its ``summary.json``) is set against the law that
predicts its steady rate:

* open top, planar: the 2D Beverloo law Q = C rho sqrt(g) D^(3/2) with the
  continuum constant C = 1.28 of Zhou et al. 2019 (k = 0: a continuum has no
  empty annulus);
* open top, flat-bottomed cylinder with a centred orifice: Zhou et al. eq. 1
  with the Table I constants (C0 = 0.69, alpha_D = 0.81, beta = 0.08);
* closed top or air injected at the top: eq. 23 (Darcy, with the Forchheimer
  term when the scene has it), in the continuum form the simulation solves
  (phi_o = 1, rho = the phase density, the scene's permeabilities), with the
  zone correction A = 1 and the A = 0.68 the paper fitted to its own
  simulations.  Q0 is the simulated open-top rate of the same geometry when
  the sweep holds one (as in the paper), otherwise the open-top law above.

Written next to the case or sweep: ``compare.json``, ``compare.md`` (the
table of relative errors) and ``compare.png`` (the points on the curves).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.analytic.beverloo import (
    ZHOU_PLANAR_D_OVER_L,
    ZHOU_PLANAR_Q,
    ZHOU_PLANAR_Q_SPREAD,
    beverloo_2d,
    beverloo_2d_constant,
)
from foamsilo.case import SCENE_FILE, write_whole
from foamsilo.errors import FoamsiloError
from foamsilo.jsonio import dumps
from foamsilo.scene import Scene, load_scene_file

COMPARE_JSON = "compare.json"
COMPARE_MD = "compare.md"
COMPARE_PNG = "compare.png"
#: Zone correction of eq. 23 fitted by Zhou et al. to their 2D simulations
A_PAPER = 0.68


@dataclass
class Point:
    """One simulated steady rate and its analytic prediction.

    Attributes
    ----------
    case
        Case directory.
    law
        ``beverloo-2d``, ``zhou-eq1`` or ``eq23``.
    orifice_width, q_air
        D [m] and the injected air flow (per unit depth for planar) [m^3/s or m^2/s].
    q, q_std
        Simulated steady rate and its spread [kg/s, or kg/(m s) planar].
    q_law
        The law's rate (eq. 23: with A = 0.68).
    rel_error
        (q - q_law) / q_law.
    q_law_a1, rel_error_a1
        Eq. 23 with A = 1 (None for open-top laws).
    q0, q0_source
        Open-top rate eq. 23 starts from, and where it comes from.
    """

    case: str
    scene: str
    representation: str
    cells_across: int
    law: str
    orifice_width: float
    q_air: float
    q: float
    q_std: float
    q_law: float
    rel_error: float
    units: str
    q_law_a1: float | None = None
    rel_error_a1: float | None = None
    q0: float | None = None
    q0_source: str | None = None


_LAW_NAMES = {
    "beverloo-2d": f"2D Beverloo, C = {beverloo_2d_constant():.2f}",
    "zhou-eq1": "Zhou et al. eq. 1 (Table I)",
    "eq23": f"eq. 23, A = {A_PAPER}",
    "feeder": "the feeder's rate",
}


def open_top_law(scene: Scene, orifice_width: float | None = None) -> tuple[str, float]:
    """Name and rate of the open-top law for a scene (at ``orifice_width`` if given).

    Raises
    ------
    FoamsiloError
        No law for this geometry (hoppers, lateral or eccentric orifices, 3D boxes).
    """
    s = scene.silo
    D = s.orifice_width if orifice_width is None else orifice_width
    bottom = s.orifice_position == "bottom" and s.eccentricity == 0.0
    if scene.representation == "planar" and bottom:
        return "beverloo-2d", float(beverloo_2d(D, scene.material.density, scene.gravity))
    if s.shape == "cylindrical" and bottom:
        return "zhou-eq1", zhou_eq1(scene, D)
    raise FoamsiloError(
        f"{scene.name}: no analytic open-top law for a {s.shape} silo "
        f"({scene.representation}, {s.orifice_position} orifice); laws exist for planar silos "
        "with a centred bottom orifice (2D Beverloo) and cylinders with one (Zhou eq. 1)"
    )


def zhou_eq1(scene: Scene, orifice_width: float) -> float:
    """Zhou et al. eq. 1 with the Table I constants of the bottom-orifice cylinder [kg/s].

    The phase density of the continuum is the bulk density phi_b rho_p (phi = 1).
    """
    from foamsilo.analytic.zhou import config, q0_bottom

    c = config("cyl-bottom")
    assert c.C0 is not None
    m = scene.material
    return float(
        q0_bottom(
            orifice_width,
            m.grain_diameter,
            1.0,
            m.density,
            c.C0,
            c.alpha_D,
            c.beta,
            None,
            scene.gravity,
        )
    )


def eq23(scene: Scene, q0: float, q_air: float, A: float) -> float:
    """Eq. 23 for a scene, continuum form (phi_o = 1, the scene's permeabilities).

    ``q0`` and ``q_air`` per unit depth for a planar scene (S_o = D), whole
    otherwise (S_o = pi D^2 / 4).
    """
    from foamsilo.analytic.zhou import reduced_flow_rate

    D, rho, g = scene.silo.orifice_width, scene.material.density, scene.gravity
    s_o = D if scene.representation == "planar" else math.pi * D**2 / 4
    nv = A * scene.air.viscosity * q0 / (rho**2 * scene.permeability * g * s_o)
    ki = scene.inertial_permeability
    ni = (
        scene.air.density * scene.material.grain_diameter * q0**2 / (rho**3 * ki * g * s_o**2)
        if ki
        else 0.0
    )
    return float(q0 * reduced_flow_rate(rho * q_air / q0, nv, ni))


@dataclass(frozen=True)
class Reference:
    """A published or analytic rate a scene's steady Q is set against.

    Attributes
    ----------
    key
        ``zhou-planar`` (the converged continuum rate of Zhou sec. III.B),
        ``beverloo-2d``, ``zhou-eq1`` or ``eq23``.
    label
        What a legend or a table says of it.
    q
        The rate [kg/s, or kg/(m s) planar].
    spread
        Half-width of its band, in the units of ``q`` (0: a line).
    """

    key: str
    label: str
    q: float
    spread: float = 0.0


def references(scene: Scene) -> list[Reference]:
    """Return the rates that apply to a scene (what ``compare`` and the plots use).

    A feeder scene: the feeder's rate.
    Gas-coupled scenes: eq. 23 (A = 0.68, Q0 from the open-top law); open-top
    planar scenes: the 2D Beverloo law, and Zhou's converged 0.16 for their
    D = L/4 silo without wall friction; cylinders with a centred bottom
    orifice: Zhou eq. 1. Other shapes have none.
    """
    planar = scene.representation == "planar"
    feeder = scene.silo.feeder_flow_rate
    if feeder is not None:  # the discharge is what the feeder draws
        q = scene.material.density * (feeder / (scene.silo.thickness or 1.0) if planar else feeder)
        return [Reference("feeder", f"the feeder, {feeder * 3600:.4g} m^3/h", q)]
    try:
        law, q_open = open_top_law(scene)
    except FoamsiloError:
        return []
    if scene.gas_coupled:
        q_air = scene.q_air_per_depth if planar else scene.q_air
        q = eq23(scene, q_open, q_air, A_PAPER)
        return [Reference("eq23", f"eq. 23, A = {A_PAPER}, Q0 from {_LAW_NAMES[law]}", q)]
    if not planar:
        from foamsilo.analytic.zhou import config

        label = f"Zhou et al. 2019 eq. 1, C0 = {config('cyl-bottom').C0}: {q_open * 1e3:.2f} g/s"
        return [Reference("zhou-eq1", label, q_open)]
    scale = scene.rho_sqrt_gL3
    out = []
    d_over_l = scene.silo.orifice_width / scene.silo.width
    if abs(d_over_l / ZHOU_PLANAR_D_OVER_L - 1) < 0.01 and not scene.wall_friction:
        out.append(
            Reference(
                "zhou-planar",
                f"Zhou et al. 2019, {ZHOU_PLANAR_Q:g} +- {ZHOU_PLANAR_Q_SPREAD:g}",
                ZHOU_PLANAR_Q * scale,
                ZHOU_PLANAR_Q_SPREAD * scale,
            )
        )
    label = f"2D Beverloo, C = {beverloo_2d_constant():.2f}: {q_open / scale:.3f}"
    out.append(Reference("beverloo-2d", label, q_open))
    return out


def reference_sections(scene: Scene, q: float | None) -> dict[str, Any]:
    """Return the ``reference`` (and, planar, ``beverloo_2d``) sections of a run's summary."""
    _, scale = scene.flow_rate_scale
    out: dict[str, Any] = {}
    for ref in references(scene):
        rel = (q - ref.q) / ref.q if q is not None else None
        if ref.key == "zhou-planar":
            out["reference"] = {
                "source": "Zhou et al. 2019, sec. III.B (open top), converged continuum rate",
                "Q_dimensionless": ZHOU_PLANAR_Q,
                "spread": ZHOU_PLANAR_Q_SPREAD,
                "rel_diff": rel,
            }
        elif ref.key == "beverloo-2d":
            out["beverloo_2d"] = {
                "law": "Q = C rho sqrt(g) D^(3/2) (k = 0, continuum)",
                "C": beverloo_2d_constant(),
                "Q_dimensionless": ref.q / scale,
                "rel_diff": rel,
            }
        else:
            out["reference"] = {
                "source": ref.label,
                "Q": ref.q,
                "Q_dimensionless": ref.q / scale,
                "rel_diff": rel,
            }
    return out


def _case_dirs(target: Path) -> tuple[str, list[Path]]:
    """``("case", [dir])`` or ``("sweep", [dirs])`` for a case or sweep directory."""
    if (target / SCENE_FILE).exists():
        return "case", [target]
    table = target / "summary.json"
    if table.exists():
        data = json.loads(table.read_text())
        if "cases" in data:
            dirs = [Path(r["directory"]) for r in data["cases"] if r.get("status") == "ok"]
            if not dirs:
                raise FoamsiloError(f"sweep {target}: no finished case to compare")
            return "sweep", dirs
    raise FoamsiloError(
        f"{target} is neither a case (no {SCENE_FILE}) nor a sweep output (no summary.json "
        "with a cases table)"
    )


def _geometry_key(scene: Scene) -> tuple[Any, ...]:
    s = scene.silo
    return (
        scene.representation,
        s.shape,
        s.width,
        s.orifice_width,
        scene.cells_across,
        scene.material.grain_diameter,
    )


@dataclass(frozen=True)
class RunPoint:
    """What compare needs of one reduced run."""

    case: Path
    scene: Scene
    steady: bool
    q: float | None
    q_std: float | None
    reason: str = ""


def _load_points(dirs: list[Path]) -> tuple[list[RunPoint], list[dict[str, str]]]:
    """Run points from the ``summary.json`` of each case directory."""
    points, skipped = [], []
    for d in dirs:
        summary_file = d / "summary.json"
        if not summary_file.exists():
            skipped.append({"case": str(d), "reason": "not post-processed (no summary.json)"})
            continue
        try:
            s = json.loads(summary_file.read_text())
        except ValueError as exc:
            skipped.append({"case": str(d), "reason": f"summary.json unreadable: {exc}"})
            continue
        points.append(
            RunPoint(
                d,
                load_scene_file(d / SCENE_FILE),
                bool(s.get("steady")),
                s.get("Q"),
                s.get("Q_std"),
                s.get("steady_reason") or "not steady",
            )
        )
    return points, skipped


def compare_runs(
    runs: list[RunPoint],
    target: Path,
    kind: str = "case",
    skipped: list[dict[str, str]] | None = None,
    write: bool = True,
) -> dict[str, Any]:
    """Set reduced runs on their analytic laws; write ``compare.*`` into ``target``.

    Returns
    -------
    dict
        ``kind``, ``points`` (one per case, see :class:`Point`), ``skipped``
        (cases without a steady rate or a law, with the reason) and the error
        statistics; also written as ``compare.json``/``.md``/``.png`` when
        ``write``.

    Raises
    ------
    FoamsiloError
        Nothing to compare (no steady rate, or no law for the geometry).
    """
    skipped = list(skipped or [])
    loaded = []
    for r in runs:
        if not r.steady or r.q is None:
            skipped.append({"case": str(r.case), "reason": r.reason or "not steady"})
        else:
            loaded.append(r)
    # simulated open-top rates, for eq. 23's Q0
    sim_q0 = {_geometry_key(r.scene): float(r.q or 0.0) for r in loaded if not r.scene.gas_coupled}
    points: list[Point] = []
    scenes: list[Scene] = []
    for r in loaded:
        sc = r.scene
        assert r.q is not None
        planar = sc.representation == "planar"
        q_air = sc.q_air_per_depth if planar else sc.q_air
        units = "kg/(m s)" if planar else "kg/s"
        feeder = [ref for ref in references(sc) if ref.key == "feeder"]
        try:
            law, q_open = ("feeder", feeder[0].q) if feeder else open_top_law(sc)
        except FoamsiloError as exc:
            skipped.append({"case": str(r.case), "reason": str(exc)})
            continue
        common: dict[str, Any] = dict(
            case=str(r.case),
            scene=sc.name,
            representation=sc.representation,
            cells_across=sc.cells_across,
            orifice_width=sc.silo.orifice_width,
            q_air=q_air,
            q=r.q,
            q_std=r.q_std or 0.0,
            units=units,
        )
        scenes.append(sc)
        if not sc.gas_coupled:
            points.append(Point(law=law, q_law=q_open, rel_error=r.q / q_open - 1, **common))
            continue
        key = _geometry_key(sc)
        q0, src = (sim_q0[key], "simulation (open top)") if key in sim_q0 else (q_open, law)
        q68, q1 = eq23(sc, q0, q_air, A_PAPER), eq23(sc, q0, q_air, 1.0)
        points.append(
            Point(
                law="eq23",
                q_law=q68,
                q_law_a1=q1,
                q0=q0,
                q0_source=src,
                rel_error=r.q / q68 - 1,
                rel_error_a1=r.q / q1 - 1,
                **common,
            )
        )
    if not points:
        raise FoamsiloError(
            f"{target}: nothing to compare; "
            + "; ".join(f"{Path(s['case']).name}: {s['reason']}" for s in skipped)
        )
    errors = np.array([p.rel_error for p in points])
    result: dict[str, Any] = {
        "kind": kind,
        "target": str(target),
        "points": [asdict(p) for p in points],
        "skipped": skipped,
        "rms_rel_error": float(np.sqrt(np.mean(errors**2))),
        "max_abs_rel_error": float(np.max(np.abs(errors))),
        "beverloo_2d_C": beverloo_2d_constant(),
        "eq23_A": A_PAPER,
    }
    if write:
        result["files"] = [COMPARE_JSON, COMPARE_MD, COMPARE_PNG]
        plot_comparison(points, scenes, target / COMPARE_PNG)
        write_whole(target / COMPARE_MD, comparison_markdown(result))
        write_whole(target / COMPARE_JSON, dumps(result) + "\n")
    return result


def compare(target: Path, write: bool = True) -> dict[str, Any]:
    """Compare the cases of a case or sweep directory with the analytic laws.

    Reads each case's ``summary.json``; see :func:`compare_runs`.
    """
    target = Path(target).resolve()
    kind, dirs = _case_dirs(target)
    points, skipped = _load_points(dirs)
    return compare_runs(points, target, kind, skipped, write)


def comparison_markdown(result: dict[str, Any]) -> str:
    """Return the table of relative errors (Markdown)."""
    lines = [
        "| case | D [m] | Q_air | Q simulated | law | Q law | error | eq. 23 A = 1 | error |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for p in result["points"]:
        a1 = (
            f"{p['q_law_a1']:.5g} | {p['rel_error_a1']:+.1%}"
            if p["q_law_a1"] is not None
            else "- | -"
        )
        lines.append(
            f"| {Path(p['case']).name} | {p['orifice_width']:.4g} | {p['q_air']:.3g} "
            f"| {p['q']:.5g} ± {p['q_std']:.2g} {p['units']} | {_LAW_NAMES[p['law']]} "
            f"| {p['q_law']:.5g} | {p['rel_error']:+.1%} | {a1} |"
        )
    lines += [
        "",
        f"rms relative error {result['rms_rel_error']:.1%}, largest "
        f"{result['max_abs_rel_error']:.1%} (cases: {len(result['points'])}).",
    ]
    for s in result["skipped"]:
        lines.append(f"\nNot compared: {Path(s['case']).name}: {s['reason']}")
    return "\n".join(lines) + "\n"


def plot_comparison(points: list[Point], scenes: list[Scene], path: Path) -> Path:
    """Q against D on the open-top law, and Q against Q_air on eq. 23 (PNG)."""
    from foamsilo.plots import finish, subplots

    dry = [(p, sc) for p, sc in zip(points, scenes, strict=True) if p.law != "eq23"]
    wet = [(p, sc) for p, sc in zip(points, scenes, strict=True) if p.law == "eq23"]
    panels = [x for x in (dry, wet) if x]
    fig, axes = subplots(len(panels), (6 * len(panels), 4.2), squeeze=False)
    for ax, group in zip(axes[0], panels, strict=True):
        p0, sc0 = group[0]
        if p0.law != "eq23":
            ds = np.array([p.orifice_width for p, _ in group])
            lo, hi = 0.6 * ds.min(), 1.25 * ds.max()
            dd = np.linspace(lo, hi, 100)
            if p0.law == "feeder":  # the rate the feeder imposes, whatever D
                ax.axhline(p0.q_law, color="k", label=_LAW_NAMES[p0.law])
            else:
                ax.plot(dd * 1e3, [open_top_law(sc0, x)[1] for x in dd], "k-",
                        label=_LAW_NAMES[p0.law])  # fmt: skip
            ax.errorbar(
                ds * 1e3,
                [p.q for p, _ in group],
                yerr=[p.q_std for p, _ in group],
                fmt="o",
                color="C3",
                capsize=3,
                label="siloFoam (steady Q)",
            )
            ax.set_xlabel("orifice width D [mm]")
        else:
            qa = np.array([p.q_air for p, _ in group])
            hi = 1.2 * max(qa.max(), 1e-12)
            xx = np.linspace(0.0, hi, 60)
            for A, style in ((1.0, "k--"), (A_PAPER, "r-")):
                ax.plot(
                    xx,
                    [eq23(sc0, p0.q0 or 0.0, x, A) for x in xx],
                    style,
                    label=f"eq. 23, A = {A:g} (Q0: {p0.q0_source})",
                )
            ax.errorbar(
                qa,
                [p.q for p, _ in group],
                yerr=[p.q_std for p, _ in group],
                fmt="o",
                color="C3",
                capsize=3,
                label="siloFoam",
            )
            planar = sc0.representation == "planar"
            ax.set_xlabel("Q_air per unit depth [m^2/s]" if planar else "Q_air [m^3/s]")
        ax.set_ylabel(f"Q [{p0.units}]")
        ax.set_ylim(bottom=0)
    return finish(fig, axes[0], path)
