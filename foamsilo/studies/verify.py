"""Code verification of siloFoam: steady channel flows against their exact profiles.

``foamsilo bench verification`` runs each entry of ``verification.toml``: a
channel periodic along the flow (:mod:`foamsilo.case.channel`), from rest
to its steady state, at doubling resolutions, through the one pipeline (a
foamsilo case, run with recovery and recorded). Each run is set against the
exact steady profile (:mod:`foamsilo.analytic.exact`):

* ``bagnold``: the mu(I) layer down an inclined plane, u(z) = (2/3) (I/d)
  sqrt(g cos theta) [h^(3/2) - (h - z)^(3/2)], I from mu(I) = tan(theta);
* ``film``: below the yield slope the viscosity cap holds throughout and the
  layer is a Newtonian film, u(z) = (g sin(theta) / nu) (h z - z^2/2);
* ``pipe``: a vertical pipe full of grains at the cap (axisymmetric wedge,
  the hoop terms of the viscous stress), u(r) = g (R^2 - r^2) / (4 nu).

The air above a layer rests its weight on it (the lid slips): the exact
profiles are taken for the loaded depth h' = h + rho_air h_air / rho, which
adds that weight to both the normal and the shear stress. Errors are over
the exact peak velocity u_p (the layer's surface, the pipe's axis); the
observed order between two resolutions is log(e_coarse / e_fine) /
log(n_fine / n_coarse).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.analytic.exact import bagnold_velocity, newtonian_film_velocity
from foamsilo.case import SCENE_FILE, time_directories, write_whole
from foamsilo.case.channel import Channel, create_channel_case
from foamsilo.errors import FoamsiloError
from foamsilo.foam import read_internal_field
from foamsilo.jsonio import dumps
from foamsilo.pipeline import run as run_case_solver
from foamsilo.scene import Scene, load_preset, load_scene_file
from foamsilo.studies.cases import fmt, git_commit, machine_info, overrides, pick, study_table
from foamsilo.toolchain import OpenFOAM, find_openfoam

#: The laws a verification entry may name
LAWS = ("bagnold", "film", "pipe")


@dataclass
class VerificationCheck:
    """A figure of the verification and the bound its size must stay under (and a floor)."""

    entry: str
    name: str
    value: float | None
    high: float
    why: str
    low: float | None = None

    @property
    def passed(self) -> bool:
        """Whether the value is finite, its size within the bound, and not under the floor."""
        return (
            self.value is not None
            and math.isfinite(self.value)
            and abs(self.value) <= self.high
            and (self.low is None or self.value >= self.low)
        )

    @property
    def bound(self) -> str:
        """The allowed range in words."""
        return f"{self.high:g}" if self.low is None else f"[{self.low:g}, {self.high:g}]"


def entries() -> dict[str, dict[str, Any]]:
    """Return the entries of ``verification.toml`` (checked: a known law, doubling cells)."""
    table = study_table("verification")
    for name, e in table.items():
        if e.get("law") not in LAWS:
            raise FoamsiloError(
                f"verification.toml [{name}].law: got {e.get('law')!r}; allowed: {', '.join(LAWS)}"
            )
    return table


def channel_for(entry: dict[str, Any], cells: int) -> Channel:
    """Return the channel of an entry at a resolution."""
    return Channel(
        tan_theta=float(entry.get("tan_theta", 0.0)),
        depth=float(entry["depth"]),
        cells=int(cells),
        air_depth=float(entry.get("air_depth", 0.0)),
        length=float(entry["length"]),
        geometry="pipe" if entry["law"] == "pipe" else "plane",
        reference_pressure=float(entry.get("reference_pressure", 0.0)),
    )


def channel_scene(entry: dict[str, Any], channel: Channel, extra: Sequence[str] = ()) -> Scene:
    """Return the scene a channel takes its grains, air and run from.

    Its silo (8 cells across, a slot or disk of 2 cells) only satisfies the
    scene's rules: the channel's mesh replaces it; its fill height is the
    layer's depth, or above a pipe's top. ``extra`` overrides (``key=value``)
    come last: a lever to measure (``foamsilo bench verification --set``).
    """
    plane = channel.geometry == "plane"
    width = 0.04 if plane else 2 * channel.depth
    height = channel.height if plane else max(0.04, channel.length)
    sets = [
        f"silo.width={width!r}",
        "mesh.cells_across=8",
        "mesh.growth_rate=1.0",
        "mesh.orifice_edge_refinement=1.0",
        "mesh.orifice_exit_refinement=1",
        f"silo.orifice_width={width / 4!r}",
        f"mesh.representation='{'planar' if plane else 'axisymmetric'}'",
        "gas.mode='open-top'",
        f"silo.height={height!r}",
        f"silo.fill_height={channel.depth if plane else height!r}",
        f"run.end_time={float(entry['end_time'])!r}",
        f"run.write_interval={float(entry['write_interval'])!r}",
        *overrides(entry.get("set")),
        *extra,
    ]
    return load_preset(entry["preset"], sets)


def loaded_depth(scene: Scene, channel: Channel) -> float:
    """Return h' = h + rho_void h_void / rho, the depth whose weight the base carries."""
    air = channel.height - channel.depth
    return channel.depth + scene.void_density * air / scene.material.density


def exact_velocity(law: str, scene: Scene, channel: Channel, y: np.ndarray) -> np.ndarray:
    """Return the exact steady velocity along the slope at heights ``y`` in the layer.

    Raises
    ------
    FoamsiloError
        A film above the yield slope (the cap would not hold throughout).
    """
    m, g, h = scene.material, scene.gravity, loaded_depth(scene, channel)
    if law == "pipe":
        r = np.asarray(y, dtype=float)
        return np.asarray(g * (channel.depth**2 - r**2) / (4 * scene.eta_max / m.density))
    if law == "bagnold":
        return bagnold_velocity(y, h, channel.theta, m.mu_s, m.delta_mu, m.i0,
                                m.grain_diameter, g, law=m.friction_law)  # fmt: skip
    if channel.tan_theta >= m.mu_s:
        raise FoamsiloError(
            f"film: tan(theta) = {channel.tan_theta:g} must be below mu_s = {m.mu_s:g} for the "
            "viscosity cap to hold throughout the film"
        )
    return newtonian_film_velocity(y, h, channel.theta, scene.eta_max / m.density, g)


@dataclass
class ChannelResult:
    """One run set against its exact profile (errors over the exact peak velocity).

    ``y`` is the height above the base (a layer) or the radius (a pipe);
    ``u`` the velocity along the flow; the peak is at the layer's surface or
    the pipe's axis.
    """

    cells: int
    time: float
    y: list[float]
    u: list[float]
    u_exact: list[float]
    peak_velocity: float
    peak_velocity_exact: float
    peak_error: float
    mean_error: float
    l2_error: float
    max_error: float
    unsteadiness: float
    alpha_min: float
    alpha_max: float
    steps: int | None
    cpu_s: float | None


def reduce_channel(case_dir: Path, law: str) -> ChannelResult:
    """Set the latest time of a channel case against its exact profile.

    Raises
    ------
    FoamsiloError
        Fewer than two written times (the steadiness needs two).
    """
    from foamsilo.case import read_metadata, read_run_record
    from foamsilo.case.channel import CHANNEL_KEY

    scene = load_scene_file(case_dir / SCENE_FILE)
    channel = Channel(**read_metadata(case_dir)[CHANNEL_KEY])
    times = [t for t in time_directories(case_dir) if float(t) > 0]
    if len(times) < 2:
        raise FoamsiloError(f"{case_dir}: {len(times)} written times; the steadiness needs two")
    n = channel.cells
    centres = read_internal_field(case_dir / "0" / "C")
    pipe = channel.geometry == "pipe"

    def along(t: str) -> np.ndarray:
        U = read_internal_field(case_dir / t / "U")
        return -U[:n, 1] if pipe else U[:n, 0]  # down the pipe's axis, down the slope

    u, u_prev = along(times[-1]), along(times[-2])
    alpha = read_internal_field(case_dir / times[-1] / "alpha.granular")[:n]
    y = np.hypot(centres[:n, 0], centres[:n, 2]) if pipe else centres[:n, 1]
    exact = exact_velocity(law, scene, channel, y)
    peak_at = 0.0 if pipe else channel.depth
    u_p_exact = float(exact_velocity(law, scene, channel, np.array([peak_at]))[0])
    if pipe:  # the two inner cells, extrapolated in r^2 to the axis (exact for a parabola)
        u_p = float((u[0] * y[1] ** 2 - u[1] * y[0] ** 2) / (y[1] ** 2 - y[0] ** 2))
    else:  # the top two rows, extrapolated linearly to the surface at y = h
        u_p = float(u[-1] + (u[-1] - u[-2]) * (channel.depth - y[-1]) / (y[-1] - y[-2]))
    zz = np.linspace(0.0, channel.depth, 4001)
    weight = zz if pipe else np.ones_like(zz)  # an area mean over the pipe's section
    uz = exact_velocity(law, scene, channel, zz)
    mean_exact = float(np.trapezoid(uz * weight, zz) / np.trapezoid(weight, zz))
    volumes = read_internal_field(case_dir / "0" / "V")[:n]
    mean = float(np.sum(u * volumes) / np.sum(volumes))
    err = u - exact
    run = read_run_record(case_dir) or {}
    return ChannelResult(
        cells=n,
        time=float(times[-1]),
        y=y.tolist(),
        u=u.tolist(),
        u_exact=exact.tolist(),
        peak_velocity=u_p,
        peak_velocity_exact=u_p_exact,
        peak_error=u_p / u_p_exact - 1,
        mean_error=mean / mean_exact - 1,
        l2_error=float(np.sqrt(np.mean(err**2))) / u_p_exact,
        max_error=float(np.max(np.abs(err))) / u_p_exact,
        unsteadiness=float(np.max(np.abs(u - u_prev))) / u_p_exact,
        alpha_min=float(alpha.min()),
        alpha_max=float(alpha.max()),
        steps=run.get("steps"),
        cpu_s=run.get("cpu_seconds"),
    )


def observed_orders(rows: list[ChannelResult], key: str) -> list[float | None]:
    """Observed order of ``key`` between each resolution and the next finer one."""
    out: list[float | None] = []
    for a, b in zip(rows, rows[1:], strict=False):
        ea, eb = abs(getattr(a, key)), abs(getattr(b, key))
        ok = ea > 0 and eb > 0
        out.append(math.log(ea / eb) / math.log(b.cells / a.cells) if ok else None)
    return out


def check_row(name: str, entry: dict[str, Any], rows: list[ChannelResult]) -> ChannelResult:
    """Return the row the peak velocity is judged on: ``check_cells``, else the coarsest.

    Raises
    ------
    FoamsiloError
        ``check_cells`` names a grid that was not run.
    """
    want = entry.get("check_cells", rows[0].cells)
    at = next((r for r in rows if r.cells == want), None)
    if at is None:
        raise FoamsiloError(
            f"verification.toml [{name}].check_cells = {want}: not among the grids run "
            f"({', '.join(str(r.cells) for r in rows)})"
        )
    return at


def run_entry(
    name: str,
    entry: dict[str, Any],
    quick: bool,
    work: Path,
    of: OpenFOAM,
    say: Any,
    extra: Sequence[str] = (),
) -> dict[str, Any]:
    """Run one entry at its resolutions (``extra``: overrides on top); rows, orders, checks."""
    rows: list[ChannelResult] = []
    for cells in pick(entry, "cells", quick):
        channel = channel_for(entry, cells)
        scene = channel_scene(entry, channel, extra)
        case_dir = work / name / f"cells{cells}"
        t0 = time.perf_counter()
        create_channel_case(scene, channel, case_dir, of, overwrite=True)
        run_case_solver(case_dir, of, rerun=True)
        row = reduce_channel(case_dir, entry["law"])
        rows.append(row)
        say(f"{name}, {cells} cells: u_p {row.peak_error:+.3%}, L2 {row.l2_error:.2e}, "
            f"steady to {row.unsteadiness:.1e} ({time.perf_counter() - t0:.0f} s)")  # fmt: skip
    tol = entry["tolerance"]
    at = check_row(name, entry, rows)
    checks = [
        VerificationCheck(name, f"peak velocity error, {at.cells} cells",
                          at.peak_error, tol["peak_velocity"], tol["peak_velocity_why"]),
        VerificationCheck(name, "largest unsteadiness at the end",
                          max(r.unsteadiness for r in rows), tol["unsteadiness"],
                          tol["unsteadiness_why"]),
    ]  # fmt: skip
    if len(rows) >= 2 and "order_l2_low" in tol:
        order = observed_orders(rows, "l2_error")[-1]
        checks.append(VerificationCheck(
            name, f"observed order (L2), {rows[-2].cells} to {rows[-1].cells} cells", order,
            tol["order_l2_high"], tol["order_l2_why"], low=tol["order_l2_low"]))  # fmt: skip
    return {
        "title": entry["title"],
        "source": entry["source"],
        "law": entry["law"],
        "tan_theta": entry.get("tan_theta"),
        "depth": entry["depth"],
        "rows": [asdict(r) for r in rows],
        "order_l2": observed_orders(rows, "l2_error"),
        "order_peak": observed_orders(rows, "peak_error"),
        "checks": [{**asdict(c), "bound": c.bound, "passed": c.passed} for c in checks],
    }


def run_verification(
    quick: bool,
    out_dir: Path,
    work_dir: Path,
    only: list[str] | None = None,
    say: Any = lambda _: None,
    sets: Sequence[str] = (),
) -> dict[str, Any]:
    """Run the verification; write ``verification[-quick][-set].json``, ``.md`` and ``.png``.

    ``sets``: scene overrides applied to every case (a lever to measure); its
    report is ``verification-set``, so that the checked-in one stays the
    defaults'.
    """
    commit = git_commit()  # before the runs (git_commit)
    table = entries()
    names = only or list(table)
    bad = [n for n in names if n not in table]
    if bad:
        raise FoamsiloError(f"unknown verification entry {bad[0]!r}; valid: " + ", ".join(table))
    of = find_openfoam()
    t0 = time.perf_counter()
    result: dict[str, Any] = {
        "quick": quick,
        "set": list(sets),
        "machine": machine_info(),
        "commit": commit,
    }
    for name in names:
        result[name] = run_entry(name, table[name], quick, Path(work_dir), of, say, sets)
    result["wall_s"] = time.perf_counter() - t0
    result["checks"] = [c for n in names for c in result[n]["checks"]]
    stem = report_stem(quick, sets)
    out_dir.mkdir(parents=True, exist_ok=True)
    plot_verification(result, names, out_dir / f"{stem}.png")
    write_whole(out_dir / f"{stem}.json", dumps(result, indent=1) + "\n")
    write_whole(out_dir / f"{stem}.md", verification_markdown(result, names, stem))
    return result


def plot_verification(result: dict[str, Any], names: list[str], path: Path) -> Path:
    """Profiles against the exact ones, and the errors against the resolution."""
    from foamsilo.plots import finish, subplots

    fig, axes = subplots(ncols=len(names) + 1, size=(4.2 * (len(names) + 1), 4))
    for ax, name in zip(axes, names, strict=False):
        e = result[name]
        finest = e["rows"][-1]
        ax.plot(finest["u_exact"], np.array(finest["y"]) / e["depth"], "k-", label="exact")
        for r in e["rows"]:
            ax.plot(r["u"], np.array(r["y"]) / e["depth"], ".", ms=3, label=f"{r['cells']} cells")
        ylabel = "r / R" if e["law"] == "pipe" else "z / h"
        ax.set(xlabel="u [m/s]", ylabel=ylabel, title=name)
    ax = axes[-1]
    for name in names:
        rows = result[name]["rows"]
        n = [r["cells"] for r in rows]
        ax.loglog(n, [r["l2_error"] for r in rows], "o-", label=f"{name}: L2 error / u_s")
        ax.loglog(n, [abs(r["peak_error"]) for r in rows], "s--", label=f"{name}: |u_p error|")
    ax.set(xlabel="cells across the layer", ylabel="relative error", title="convergence")
    return finish(fig, list(axes), path)


def report_stem(quick: bool, sets: Sequence[str]) -> str:
    """Name of the report files: ``verification``, ``-quick``, ``-set`` (overrides given)."""
    return "verification" + ("-quick" if quick else "") + ("-set" if sets else "")


def verification_markdown(result: dict[str, Any], names: list[str], stem: str) -> str:
    """Return the report: per law, the table of errors and orders; the checks."""
    m = result["machine"]
    sets = "".join(f" --set {s}" for s in result.get("set", []))
    lines = [
        "# Code verification of siloFoam" + (" (quick)" if result["quick"] else ""),
        "",
        f"`foamsilo bench verification{' --quick' if result['quick'] else ''}{sets}` on "
        f"{m['cpu']}, "
        f"{m['cores']} cores, {m['date']}; commit {result['commit']}; "
        f"{result['wall_s']:.0f} s wall in all.",
        "",
        "A channel periodic along the flow, one line of cells (`foamsilo/case/channel.py`): "
        "a layer on an inclined plane, or a vertical pipe as an axisymmetric wedge; run from "
        "rest to its steady state through the pipeline and set against the exact steady "
        "profile (`foamsilo/studies/verify.py`). Errors are over the exact peak velocity u_p "
        "(the layer's surface, the pipe's axis), extrapolated from the two nearest cells; "
        "*order* is the observed order against the next coarser grid; *unsteadiness* is "
        "the largest change of the profile over the last write interval.",
        "",
    ]
    for name in names:
        e = result[name]
        lines += [
            f"## {name}: {e['title']}",
            "",
            f"Source: {e['source']}. "
            + (
                f"Radius {e['depth']} m."
                if e["law"] == "pipe"
                else f"tan(theta) = {e['tan_theta']}, depth {e['depth']} m."
            ),
            "",
            "| cells | u_p error | mean-velocity error | L2 error | order (L2) | "
            "order (u_p) | max error | unsteadiness | alpha min - max | steps | CPU [s] |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        orders = [None, *e["order_l2"]]
        orders_s = [None, *e["order_peak"]]
        for r, p, ps in zip(e["rows"], orders, orders_s, strict=True):
            lines.append(
                f"| {r['cells']} | {r['peak_error']:+.3%} | {r['mean_error']:+.3%} | "
                f"{r['l2_error']:.2e} | {fmt(p, '.2f')} | {fmt(ps, '.2f')} | "
                f"{r['max_error']:.2e} | {r['unsteadiness']:.1e} | "
                f"{r['alpha_min']:.5f} - {r['alpha_max']:.5f} | {fmt(r['steps'], 'd')} | "
                f"{fmt(r['cpu_s'], '.1f')} |"
            )
        lines.append("")
    lines += ["## Checks", "", "| entry | figure | value | bound | why | |",
              "| --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    for c in result["checks"]:
        lines.append(
            f"| {c['entry']} | {c['name']} | {fmt(c['value'], '.3g')} | {c['bound']} | "
            f"{c['why']} | {'pass' if c['passed'] else 'FAIL'} |"
        )
    lines += ["", f"![profiles and convergence]({stem}.png)", ""]
    return "\n".join(lines)
