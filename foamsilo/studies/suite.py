"""The validation suite: ``foamsilo bench validation [--quick]``.

What a user reads before trusting foamsilo: how close the OpenFOAM path is
to theory and experiment, what that costs, and where it breaks. Every entry
runs real siloFoam cases through the pipeline (two at a time on two
cores) and writes its table and plots into ``docs/validation/``
(``suite.md``; ``suite-quick.md`` for ``--quick``), each row with the
resolution, the wall and CPU time, and the error. The cases and the
tolerances of the checks (each with its reason) are data:
``foamsilo/studies/suite.toml``. ``--quick`` runs the reduced versions of
the same entries and fails when a checked figure leaves its tolerance.

Entries
-------
``presets``
    Every preset (each seed scene of the papers) at its own defaults: each
    must reach a steady discharge.
``work-precision``
    The planar silo of Zhou sec. III.B and the axisymmetric lab silo (Zhou
    Table I) at several resolutions: steady Q against the finest and against
    the analytic law, wall time, the resolution to pick for 5% and 2%.
``beverloo``
    Venier Test 1 (outlets 3 to 12 cm, axisymmetric): the fit W = C (d - f)^2.5
    with C, f and R^2; and the planar silo against the orifice width, 2D Beverloo.
``gas-lab``
    The lab silo with air injected at the top, on Q/Q0: against eq. 17 with
    the run's own pore-pressure gradient (checked) and eq. 23 (reported).
``extremes``
    Stiff and extreme scenes at their defaults, each of which must reach a
    steady discharge (with the runner's recoveries where it diverges).
``cap``
    Q at the lowest and highest viscosity cap (1e2 and 1e5 rho sqrt(g L^3)):
    planar, axisymmetric, 3D and gas-assisted scenes.
``time-step``
    Q on a fixed mesh at the default Courant limits and at smaller ones:
    whether a steady rate is converged in time (full suite only).

The full report also judges issue 18's cost targets and the presets' default
grids on these rows (:mod:`foamsilo.studies.targets`, ``suite.toml``
``[[targets]]`` and ``[default-resolution]``).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.case import write_whole
from foamsilo.errors import FoamsiloError
from foamsilo.jsonio import dumps
from foamsilo.post.convergence import (
    LOW_ORDER,
    LOW_ORDER_SAFETY_FACTOR,
    SAFETY_FACTOR,
    range_bounds_gci,
)
from foamsilo.studies.cases import (
    Jobs,
    StudyCase,
    fmt,
    git_commit,
    jobs_words,
    machine_info,
    overrides,
    pick,
    record_fields,
    run_rows,
    study_table,
    summary_fields,
    wall_limits,
)
from foamsilo.studies.targets import (
    as_dicts,
    band,
    cost_fit,
    default_resolutions,
    family,
    judge,
)

Row = dict[str, Any]
OnRow = Callable[[Row], None] | None


@dataclass
class Check:
    """A figure of the suite and the range it must stay in (from ``suite.toml``)."""

    entry: str
    name: str
    value: float | None
    low: float
    high: float
    why: str

    @property
    def passed(self) -> bool:
        """Whether the value is finite and inside [low, high]."""
        return (
            self.value is not None
            and math.isfinite(self.value)
            and (self.low <= self.value <= self.high)
        )


def _series(entry: dict[str, Any], quick: bool) -> tuple[list[Any], list[StudyCase]]:
    """Return the values of a series entry and its cases (one per value)."""
    values = pick(entry, "values", quick)
    table = pick(entry, "set", quick) or {}
    key = entry["key"]
    short = key.split(".")[-1]
    label = {"cells_across": "{v} across", "orifice_width": "{short} {v:g} m"}.get(short, "{v}")
    cases = [
        StudyCase(
            label.format(v=v, short=short),
            entry["preset"],
            [f"{key}={v!r}", *overrides(_similar(entry, table, v))],
        )
        for v in values
    ]
    return values, cases


def _similar(entry: dict[str, Any], table: dict[str, Any], value: Any) -> dict[str, Any]:
    """Return a series' overrides at ``value``; with ``similar_to``, its grading refined alike.

    ``similar_to = N0``: the growth rate and largest cells in ``set`` are
    those of the grid N0 across, and every grid of the series is that one
    refined as a whole (:func:`foamsilo.mesh.layout.similar_grading`).
    """
    if "similar_to" not in entry:
        return table
    from foamsilo.mesh.layout import similar_grading

    grading = ("mesh.growth_rate", "mesh.coarse_cells_across")
    if entry["key"] != "mesh.cells_across" or any(k not in table for k in grading):
        raise FoamsiloError(
            f"work-precision/{entry.get('name', entry['preset'])}: similar_to needs "
            f"key = 'mesh.cells_across' and {' and '.join(grading)} in its set"
        )
    growth, coarse = similar_grading(
        int(value), int(entry["similar_to"]), float(table[grading[0]]), int(table[grading[1]])
    )
    return {**table, grading[0]: growth, grading[1]: coarse}


# ----------------------------------------------------------- work precision
def _recommend(cells: list[int], err: list[float], level: float) -> int | None:
    """Coarsest resolution from which every finer one is within ``level`` of the finest."""
    from foamsilo.post.convergence import coarsest_within

    return coarsest_within(cells[:-1], err[:-1], level)


def work_precision_series() -> list[str]:
    """Names of the work-precision series (``name``, default: the preset)."""
    return [e.get("name", e["preset"]) for e in study_table("suite")["work-precision"]]


def work_precision(
    quick: bool,
    work: Path,
    jobs: Jobs,
    limit: float,
    on_row: OnRow = None,
    series: str | None = None,
    values: list[float] | None = None,
    earlier: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Steady Q against resolution and wall time, planar and axisymmetric.

    Each series is named by its ``name`` (default: its preset); ``series``
    runs that one only. A series with no ``quick_values`` is left out of the
    quick suite. With ``values`` (``series`` named) only those resolutions
    run, and their rows replace or join those of ``earlier`` (the series as
    the last report holds it; rows of resolutions no longer in its entry go).

    Raises
    ------
    FoamsiloError
        ``values`` without a ``series``, or a value that is not one of the
        series' resolutions.
    """
    from foamsilo.compare import open_top_law
    from foamsilo.scene import load_preset

    entries = study_table("suite")["work-precision"]
    names = work_precision_series()
    if values is not None and series is None:
        raise FoamsiloError("--values: needs one series, --only work-precision/NAME")
    out: dict[str, Any] = {}
    for name, entry in zip(names, entries, strict=True):
        if (series is not None and name != series) or (quick and "quick_values" not in entry):
            continue
        preset = entry["preset"]
        cells, cases = _series(entry, quick)
        keep = _chosen(name, cells, values)
        rows = run_rows([cases[i] for i in keep], work / name, jobs, limit, on_row,
                        dirs=[f"{i:02d}" for i in keep])  # fmt: skip
        for r, i in zip(rows, keep, strict=True):
            r["cells_across"] = cells[i]
        if values is not None:
            rows = _merged_rows((earlier or {}).get("rows", []), rows, cells)
        # a scene with no analytic law (a hopper) says so in its entry
        law_name, q_law = (None, None) if entry.get("law") is False else open_top_law(
            load_preset(preset))  # fmt: skip
        out[name] = {"law": law_name, "Q_law": q_law, "rows": rows}
        if entry.get("about"):
            out[name]["about"] = entry["about"]
        derive_work_precision(out[name])
    return out


def _chosen(name: str, cells: list[Any], values: list[float] | None) -> list[int]:
    """Places in a series' resolutions of ``values`` (all without).

    Raises
    ------
    FoamsiloError
        A value that is not one of the series' resolutions (they are listed).
    """
    if values is None:
        return list(range(len(cells)))
    bad = [v for v in values if v not in cells]
    if bad:
        raise FoamsiloError(
            f"--values: work-precision/{name} has no resolution {bad[0]:g}; its resolutions: "
            + ", ".join(f"{c:g}" for c in cells)
            + " (a new one goes into its entry in suite.toml first)"
        )
    return [i for i, c in enumerate(cells) if c in values]


def _merged_rows(earlier: list[Row], new: list[Row], cells: list[Any]) -> list[Row]:
    """Return a series' rows: the new ones, and the earlier ones at its other resolutions.

    In the order of ``cells`` (the series' resolutions); an earlier row at a
    resolution the series no longer lists is left out.
    """
    ran = {r["cells_across"] for r in new}
    kept = [r for r in earlier if r.get("cells_across") in cells and r["cells_across"] not in ran]
    return sorted(kept + new, key=lambda r: cells.index(r["cells_across"]))


def _floored_row(row: Row) -> bool:
    """Whether a row's scene holds its 3D O-grid at a floor (rebuilt from its preset and sets)."""
    from foamsilo.mesh import o_grid_floored
    from foamsilo.scene import load_preset

    if not row.get("preset"):
        return False
    return o_grid_floored(load_preset(row["preset"], list(row.get("sets") or [])))


def derive_work_precision(data: dict[str, Any]) -> None:
    """Add the figures a work-precision series derives from its rows.

    Each row's error against the finest and against the law; the grid
    convergence of the steady Q (observed order, Richardson extrapolation,
    GCI, :mod:`foamsilo.post.convergence`) with each row's error against the
    extrapolated Q; and the cost per simulated second fitted as a power of
    the cells across, to project the cost of the 2% and 1% resolutions.
    Recomputed when the report is written again from ``suite.json``.
    """
    from foamsilo.post.convergence import (
        coarsest_within,
        extrapolation_time_error,
        grid_convergence,
    )

    rows = data["rows"]
    # the finest row with a steady rate: a finer one that found none is no reference
    q_fin = next((r["Q"] for r in reversed(rows) if r.get("Q") and r.get("outcome") == "steady"),
                 None)  # fmt: skip
    for r in rows:
        q = r.get("Q")
        r["err_vs_finest"] = abs(q / q_fin - 1) if q and q_fin else None
        r["err_vs_law"] = q / data["Q_law"] - 1 if q and data.get("Q_law") else None
        r["err_vs_extrapolated"] = None
    cells = [r["cells_across"] for r in rows]
    errs = [r["err_vs_finest"] if r["err_vs_finest"] is not None else math.inf for r in rows]
    data["recommend_5pct"] = _recommend(cells, errs, 0.05)
    data["recommend_2pct"] = _recommend(cells, errs, 0.02)
    for r in rows:
        r["o_grid_floored"] = _floored_row(r)
    # a 3D O-grid held at its floors is finer than its cells across say: no
    # refinement family with the finer rows (foamsilo.mesh.o_grid_floored)
    steady = family(rows)
    data["convergence"] = None
    if len(steady) < 3:
        return
    grids, rates = [r["cells_across"] for r in steady], [r["Q"] for r in steady]
    g = grid_convergence(grids, rates)
    conv = g.as_dict()
    conv["extrapolated_time_error"] = extrapolation_time_error(
        grids, rates, [r.get("Q_time_error") for r in steady]
    )
    if g.extrapolated is not None:
        for r in steady:
            r["err_vs_extrapolated"] = r["Q"] / g.extrapolated - 1
        # a measured grid is within a level with its time band inside it (as the targets)
        reach = [abs(r["err_vs_extrapolated"]) + band(r) for r in steady]
        for key, level in (("2pct", 0.02), ("1pct", 0.01)):
            conv[f"coarsest_within_{key}"] = coarsest_within(g.cells, reach, level)
    fit = cost_fit(steady)
    if fit is not None:
        k, lnc0 = fit
        conv["cost_exponent"] = k
        for key in ("2pct", "1pct"):
            n = conv[f"cells_for_{key}"]
            conv[f"cpu_per_simulated_s_for_{key}"] = (
                float(math.exp(lnc0) * n**k) if n is not None else None
            )
    data["convergence"] = conv


# ------------------------------------------------------------------ Beverloo
def beverloo_fit(d: np.ndarray, w: np.ndarray, exponent: float) -> dict[str, float]:
    """Fit W = C (d - f)^exponent: linear in d for W^(1/exponent); C, f and R^2."""
    y = np.asarray(w, float) ** (1.0 / exponent)
    slope, intercept = np.polyfit(d, y, 1)
    pred = slope * np.asarray(d) + intercept
    r2 = 1 - np.sum((y - pred) ** 2) / np.sum((y - y.mean()) ** 2)
    return {"C": float(slope**exponent), "f": float(-intercept / slope), "R2": float(r2)}


def beverloo(
    quick: bool, work: Path, jobs: Jobs, limit: float, on_row: OnRow = None
) -> dict[str, Any]:
    """Venier Test 1 outlets (axisymmetric) and the planar silo against the orifice width."""
    from foamsilo.scene import load_preset

    out: dict[str, Any] = {}
    for key, entry in study_table("suite")["beverloo"].items():
        widths, cases = _series(entry, quick)
        rows = run_rows(cases, work / key, jobs, limit, on_row)
        for r, w in zip(rows, widths, strict=True):
            r["orifice_m"] = w
        out[key] = {"title": entry["title"], "exponent": entry["exponent"], "rows": rows}
        ok = [r for r in rows if r.get("Q")]
        if len(ok) >= 3:
            fit = beverloo_fit(
                np.array([r["orifice_m"] for r in ok]),
                np.array([r["Q"] for r in ok]),
                entry["exponent"],
            )
            if entry["exponent"] == 1.5:  # the planar law: C over rho sqrt(g)
                sc = load_preset(entry["preset"])
                fit["C_dimensionless"] = fit["C"] / (sc.material.density * sc.gravity**0.5)
            out[key]["fit"] = fit
    return out


# ---------------------------------------------------------- gas-assisted lab
def gas_lab(
    quick: bool, work: Path, jobs: Jobs, limit: float, on_row: OnRow = None
) -> dict[str, Any]:
    """Zhou's cylindrical lab silo with air injected at the top, against eqs. 17 and 23.

    Each grain size also runs with the open top, and the comparison is made
    on Q/Q0 (the rate over the open-top rate, Zhou's Fig. 7 axes): the
    continuum's own Q0 is above eq. 1 (see work-precision), and the ratio
    isolates the gas. eq. 23 with the Table I constants (phi_o from eq. 2 with
    xi_phi = 0.83, Ergun permeabilities at phi_o, Forchheimer term on, A = 1)
    is the experiments' law; eq. 17, Q/Q0 = sqrt(1 + <dp_f/dz>/(rho g)) with
    the simulation's own mean pore-pressure gradient over the zone of radius
    D/2 above the orifice (Zhou's Fig. 6b), is the model's mechanism, which a
    run must obey.
    """
    cases, keys = gas_lab_cases(quick)
    rows = run_rows(cases, work / "gas-lab", jobs, limit, on_row)
    for r, (d, q) in zip(rows, keys, strict=True):
        r["grain_diameter"], r["q_air_lpm"] = d, q
    data = {"rows": rows}
    derive_gas_lab(data)
    return data


def gas_lab_cases(quick: bool) -> tuple[list[StudyCase], list[tuple[float, float | None]]]:
    """Return the gas-lab cases, each with its own wall-time limit, and their keys."""
    cases, keys = _gas_lab_cases(quick)
    own = gas_lab_wall_limits()
    for c in cases:
        c.wall_limit = own.get(c.label)
    return cases, keys


def _gas_lab_cases(quick: bool) -> tuple[list[StudyCase], list[tuple[float, float | None]]]:
    """Return the gas-lab cases and each one's (grain diameter, air flow; None: open top)."""
    entry = study_table("suite")["gas-lab"]
    preset = entry["preset"]
    base = overrides(pick(entry, "set", quick))
    cases: list[StudyCase] = []
    keys: list[tuple[float, float | None]] = []
    for d in pick(entry, "grain_diameters", quick):
        size = f"material.grain_diameter={d!r}"
        cases.append(StudyCase(f"d = {d * 1e6:.0f} um, open top", preset, [*base, size]))
        keys.append((d, None))
        for q in pick(entry, "air_flows_lpm", quick):
            mode = (
                ["gas.mode='closed-top'", *overrides(entry.get("closed_top_set"))]
                if q == 0
                else ["gas.mode='injection'", f"gas.q_air_lpm={q!r}"]
            )
            label = f"d = {d * 1e6:.0f} um, Q_air = {q:g} L/min"
            cases.append(StudyCase(label, preset, [*base, size, *mode]))
            keys.append((d, q))
    return cases, keys


def gas_lab_wall_limits() -> dict[str, float]:
    """Return the gas-lab rows' own wall-time limits (``suite.toml`` [gas-lab] ``wall_limits``)."""
    labels = [c.label for c in _gas_lab_cases(quick=False)[0]]
    return wall_limits(study_table("suite")["gas-lab"], "suite.toml gas-lab", labels)


def derive_gas_lab(data: dict[str, Any]) -> None:
    """Add Q/Q0 and its laws to the gas rows (``sim_ratio``, ``eq17_ratio``, ``eq23_ratio``).

    ``eq17_force_error`` is eq. 17 squared, the orifice's force balance
    (Q/Q0)^2 = 1 + G, its difference over the forces balanced, 1 + |G|.

    Q/Q0 only from steady rates: an open-top rate or a gas rate that is not
    steady gives none.
    """
    from foamsilo.analytic.zhou import gas_assisted

    rows = data["rows"]

    def steady_q(r: Row) -> float | None:
        return r.get("Q") if r["outcome"] == "steady" else None

    q_open = {r["grain_diameter"]: steady_q(r) for r in rows if r["q_air_lpm"] is None}
    for r in rows:
        d, q = r["grain_diameter"], r["q_air_lpm"]
        if q is None:
            continue
        r["eq23_ratio"] = gas_assisted("cyl-bottom", d, q * 1e-3 / 60).Q_reduced
        q_sim, q0 = steady_q(r), q_open.get(d)
        r["sim_ratio"] = q_sim / q0 if q_sim and q0 else None
        r["rel_error"] = r["sim_ratio"] / r["eq23_ratio"] - 1 if r["sim_ratio"] else None
        zone = r.get("zone_gradient_scaled")
        r["eq17_ratio"] = math.sqrt(1 + zone) if zone is not None and zone > -1 else None
        r["eq17_rel_error"] = (
            r["sim_ratio"] / r["eq17_ratio"] - 1 if r["sim_ratio"] and r["eq17_ratio"] else None
        )
        # eq. 17 as the force balance it is, (Q/Q0)^2 = 1 + G, over the forces
        # it balances: well posed where sqrt(1 + G) turns on a small difference
        r["eq17_force_error"] = (
            (r["sim_ratio"] ** 2 - 1 - zone) / (1 + abs(zone))
            if r["sim_ratio"] and zone is not None
            else None
        )


# ------------------------------------------------------------------ extremes
def extremes(
    quick: bool, work: Path, jobs: Jobs, limit: float, on_row: OnRow = None
) -> dict[str, Any]:
    """Stiff and extreme scenes: run to the end or stop with a diagnosis."""
    table = [e for e in study_table("suite")["extremes"] if e.get("quick") or not quick]
    cases = [StudyCase(e["label"], e["preset"], overrides(e.get("set"))) for e in table]
    rows = run_rows(cases, work / "extremes", jobs, limit, on_row)
    # does the rate depend on the cap? each row against its default-cap twin
    q = {r["label"]: r.get("Q") for r in rows}
    for r, e in zip(rows, table, strict=True):
        ref = q.get(e["twin"]) if e.get("twin") else None
        r["twin"] = e.get("twin")
        r["vs_default_cap"] = r["Q"] / ref - 1 if r.get("Q") and ref else None
    return {"rows": rows}


# ----------------------------------------------------------- cap independence
def cap_independence(
    quick: bool, work: Path, jobs: Jobs, limit: float, on_row: OnRow = None
) -> dict[str, Any]:
    """Each scene at the lowest and the highest viscosity cap of ``suite.toml`` [cap]."""
    table = study_table("suite")["cap"]
    entries = [e for e in table["cases"] if e.get("quick") or not quick]
    caps = table["caps"]
    cases = [
        StudyCase(f"{e['label']}, eta_max = {c:g}", e["preset"],
                  [*overrides(e.get("set")), f"material.viscosity_cap_scaled={c!r}"])
        for e in entries
        for c in caps
    ]  # fmt: skip
    rows = run_rows(cases, work / "cap", jobs, limit, on_row)
    pairs = []
    for k, e in enumerate(entries):
        lo, hi = rows[len(caps) * k], rows[len(caps) * k + len(caps) - 1]
        change = hi["Q"] / lo["Q"] - 1 if lo.get("Q") and hi.get("Q") else None
        pairs.append({"label": e["label"], "caps": caps, "Q": [lo.get("Q"), hi.get("Q")],
                      "change": change, "outcomes": [lo["outcome"], hi["outcome"]]})  # fmt: skip
    return {"rows": rows, "pairs": pairs}


# ------------------------------------------------------------------ time step
def time_step_scenes() -> list[str]:
    """Return the labels of the time-step entry's scenes (``suite.toml`` [[time-step.cases]])."""
    return [e["label"] for e in study_table("suite")["time-step"]["cases"]]


def time_step_independence(
    quick: bool,
    work: Path,
    jobs: Jobs,
    limit: float,
    on_row: OnRow = None,
    only: str | None = None,
) -> dict[str, Any]:
    """Each scene at a fixed mesh and several Courant limits (``suite.toml`` [time-step]).

    Both the all-cell and the free-surface limit take each value (a scene's
    ``interface_courants``, where given, the free-surface limit at each); the
    first value of a scene is its reference. Not part of the quick suite. ``only``
    (a scene's label) runs that scene alone, its cases in the directories
    they have in the whole entry.
    """
    table = study_table("suite")["time-step"]
    if quick:
        return {"scenes": []}
    entries = table["cases"]
    plan = [(e, list(e.get("courants", table["courants"]))) for e in entries]
    cases = [
        StudyCase(f"{e['label']}, Courant {c:g}", e["preset"],
                  [*overrides(e.get("set")), f"run.max_courant={c!r}",
                   f"run.max_interface_courant={i!r}"])
        for e, courants in plan
        for c, i in zip(courants, _interface_courants(e, courants), strict=True)
    ]  # fmt: skip
    # one scene: its cases keep their places in the whole entry
    scene_of = [e["label"] for e, courants in plan for _ in courants]
    keep = [i for i, label in enumerate(scene_of) if only is None or label == only]
    plan = [(e, courants) for e, courants in plan if only is None or e["label"] == only]
    it = iter(run_rows([cases[i] for i in keep], work / "time-step", jobs, limit, on_row,
                       dirs=[f"{i:02d}" for i in keep]))  # fmt: skip
    scenes = []
    for e, courants in plan:
        rows = [next(it) for _ in courants]
        for r, c, i in zip(rows, courants, _interface_courants(e, courants), strict=True):
            r["courant"] = c
            r["interface_courant"] = i
        scenes.append({"label": e["label"], "rows": rows})
    out = {"scenes": scenes}
    derive_time_step(out)
    return out


def _interface_courants(entry: dict[str, Any], courants: list[float]) -> list[float]:
    """Return a time-step scene's free-surface Courant limits: its own, or its all-cell ones."""
    given = entry.get("interface_courants")
    if given is None:
        return courants
    if len(given) != len(courants):
        raise ValueError(
            f"suite.toml time-step {entry['label']!r}: interface_courants has {len(given)} "
            f"values; allowed: one per Courant limit ({len(courants)})"
        )
    return [float(v) for v in given]


def _courant_words(row: dict[str, Any]) -> str:
    """Return a time-step row's Courant limits: one value, or all cells / free surface."""
    c, i = row["courant"], row.get("interface_courant", row["courant"])
    return f"{c:g}" if i == c else f"{c:g} / {i:g}"


def derive_time_step(data: dict[str, Any]) -> None:
    """Each row's change of Q against its scene's first (default) Courant limit.

    Also the relative spread of the rate in the steady window (``Q_std / Q``),
    shown beside its step-to-step part (``Q_step_swing``).
    """
    for scene in data["scenes"]:
        ref = scene["rows"][0].get("Q") if scene["rows"][0].get("outcome") == "steady" else None
        for r in scene["rows"]:
            q = r.get("Q") if r.get("outcome") == "steady" else None
            r["vs_default_step"] = q / ref - 1 if q and ref else None
            r["spread"] = r["Q_std"] / r["Q"] if r.get("Q") and r.get("Q_std") else None


# ------------------------------------------------------------------- presets
def presets(
    quick: bool,
    work: Path,
    jobs: Jobs,
    limit: float,
    on_row: OnRow = None,
    only: str | None = None,
) -> dict[str, Any]:
    """Every preset (each seed scene of the papers) at its own defaults, to its end time.

    ``only`` runs that preset alone.
    """
    from foamsilo.scene import load_preset, preset_names

    entry = study_table("suite")["presets"]
    names = [only] if only else (entry["quick"] if quick else preset_names())
    own = preset_wall_limits()
    cases = [StudyCase(n, n, [], wall_limit=own.get(n)) for n in names]
    rows = run_rows(cases, work / ("presets" if only is None else f"presets-{only}"), jobs,
                    limit, on_row)  # fmt: skip
    for r in rows:
        scene = load_preset(r["preset"])
        r["representation"] = scene.representation
        r["cells_across"] = scene.cells_across
        r["scheme"] = scene.stress_pressure_coupling
        r["flow_rate_scale"] = scene.flow_rate_scale[0]
    return {"rows": rows}


def preset_wall_limits() -> dict[str, float]:
    """Return the presets' own wall-time limits (``suite.toml`` [presets] ``wall_limits``)."""
    from foamsilo.scene import preset_names

    return wall_limits(study_table("suite")["presets"], "suite.toml presets", preset_names())


def longest_wall_limit(limit: float) -> float:
    """Return the longest wall-time limit a case of the suite runs under (s).

    ``limit`` is the suite's per-case limit; a preset's or a gas-lab row's own
    ``wall_limits`` can be longer (a batch job's ``--time`` must cover it).
    """
    return max([limit, *preset_wall_limits().values(), *gas_lab_wall_limits().values()])


# --------------------------------------------------------------------- suite
ENTRIES: dict[str, Callable[..., dict[str, Any]]] = {
    "presets": presets,
    "work-precision": work_precision,
    "beverloo": beverloo,
    "gas-lab": gas_lab,
    "extremes": extremes,
    "cap": cap_independence,
    "time-step": time_step_independence,
}


def _finest_common(names: list[str], wp: dict[str, Any]) -> tuple[str, float | None]:
    """Return a name and Q_a / Q_b - 1 of two series at their finest common steady grid."""
    a, b = (wp[n]["rows"] for n in names)
    steady_b = {r["cells_across"]: r["Q"] for r in b if r["outcome"] == "steady"}
    common = [r for r in a if r["outcome"] == "steady" and r["cells_across"] in steady_b]
    what = f"{names[0]} / {names[1]} - 1"
    if not common:
        return f"{what} (no resolution steady in both)", None
    n = max(r["cells_across"] for r in common)
    q = next(r["Q"] for r in common if r["cells_across"] == n)
    return f"{what}, {n} across", q / steady_b[n] - 1


def checks(result: dict[str, Any]) -> list[Check]:
    """Return the suite's figures with their tolerances (``suite.toml`` ``[checks]``)."""
    tol = study_table("suite")["checks"]

    def check(key: str, name: str, value: float | None) -> Check:
        t = tol[key]
        return Check(t["entry"], name, value, float(t["low"]), float(t["high"]), t["why"])

    out: list[Check] = []
    # a partial run (--only) holds some series only: each check takes what is there
    wp = result.get("work-precision") or {}
    for r in wp.get("zhou-planar", {}).get("rows", []):
        # a rate that is not steady (or swings from step to step) is no Q*
        q_star = r.get("Q_dimensionless") if r["outcome"] == "steady" else None
        out.append(check("planar-q-star", f"planar {r['cells_across']} across: Q*", q_star))
    axi = wp.get("zhou-cyl-bottom", {}).get("rows", [])
    if axi:
        # a row that is not steady has no rate to rise: the check fails on it
        q = [r.get("Q") for r in axi if r["outcome"] == "steady"]
        rises = all(q) and all(b > a for a, b in zip(q[:-1], q[1:], strict=True))
        up = 1.0 if len(q) == len(axi) and rises else 0.0
        out.append(check("lab-silo-rises", "lab silo: Q rises with resolution", up))
        for r in axi:
            out.append(
                check(
                    "lab-silo-flux-volume",
                    f"lab silo, {r['cells_across']} across: |Q flux / Q volume - 1|",
                    r.get("flux_vs_volume_rel_diff"),
                )
            )
    pair = tol["three-d-axisymmetric"]["series"]
    if all(n in wp for n in pair):  # full suite only
        out.append(check("three-d-axisymmetric", *_finest_common(pair, wp)))
    bev = result.get("beverloo")
    if bev:
        out.append(
            check(
                "venier-r2",
                "Venier Test 1: R^2 of W = C (d - f)^2.5",
                bev["venier"].get("fit", {}).get("R2"),
            )
        )
        out.append(
            check(
                "planar-beverloo-c",
                "planar: C of Q = C rho sqrt(g) (D - f)^1.5",
                bev["planar"].get("fit", {}).get("C_dimensionless"),
            )
        )
    gl = result.get("gas-lab")
    if gl:
        for r in gl["rows"]:
            steady = 1.0 if r["outcome"] == "steady" else 0.0
            out.append(check("gas-lab-steady", f"{r['label']}: steady at its defaults", steady))
            if r["q_air_lpm"] is not None:
                name = f"{r['label']}: eq. 17's force balance, ((Q/Q0)^2 - 1 - G) / (1 + |G|)"
                out.append(check("gas-lab-eq17", name, r.get("eq17_force_error")))
    pre = result.get("presets")
    if pre:
        for r in pre["rows"]:
            steady = 1.0 if r["outcome"] == "steady" else 0.0
            out.append(check("presets-steady", f"preset {r['label']}: steady at its defaults",
                             steady))  # fmt: skip
    ext = result.get("extremes")
    if ext:
        for r in ext["rows"]:
            steady = 1.0 if r["outcome"] == "steady" else 0.0
            out.append(check("extremes-steady", f"{r['label']}: steady at its defaults", steady))
            if r.get("twin"):
                out.append(check("extremes-cap", f"{r['label']}: Q against {r['twin']}",
                                 r.get("vs_default_cap")))  # fmt: skip
    cap = result.get("cap")
    if cap:
        for pair in cap["pairs"]:
            out.append(check("cap-independence", f"{pair['label']}: Q(1e5)/Q(1e2) - 1",
                             pair.get("change")))  # fmt: skip
    ts = result.get("time-step")
    if ts:
        for scene in ts["scenes"]:
            first = _courant_words(scene["rows"][0])
            for r in scene["rows"][1:]:
                name = f"{scene['label']}, Courant {_courant_words(r)}: Q against Courant {first}"
                out.append(check("time-step", name, r.get("vs_default_step")))
    return out


def run_suite(
    quick: bool,
    out_dir: Path,
    work_dir: Path,
    only: list[str] | None = None,
    jobs: Jobs = 2,
    limit: float = 900.0,
    on_row: OnRow = None,
    values: list[float] | None = None,
) -> dict[str, Any]:
    """Run the suite; write ``suite[-quick].json`` and ``.md`` with plots into ``out_dir``.

    ``values``: with ``only`` one series (``work-precision/NAME``), run those
    of its resolutions only, their rows put into the series of the report
    already in ``out_dir``.
    """
    from foamsilo.scene import preset_names

    names = only or list(ENTRIES)
    # "work-precision/NAME" (one series), "presets/NAME" (one preset) or
    # "time-step/LABEL" (one scene): a part of an entry, merged into the others
    split = [(n.partition("/")[0], n.partition("/")[2]) for n in names]
    parts = {
        "work-precision": work_precision_series(),
        "presets": preset_names(),
        "time-step": time_step_scenes(),
    }
    bad = [
        f"{n}/{sub}" if sub else n
        for n, sub in split
        if n not in ENTRIES or (sub and sub not in parts.get(n, []))
    ]
    if bad:
        raise FoamsiloError(
            f"unknown suite entry {bad[0]!r}; valid: "
            + ", ".join(ENTRIES)
            + "; or one series: "
            + ", ".join(f"work-precision/{k}" for k in parts["work-precision"])
            + "; or one preset: "
            + ", ".join(f"presets/{k}" for k in parts["presets"])
            + "; or one time-step scene: "
            + ", ".join(f"'time-step/{k}'" for k in parts["time-step"])
        )
    if values is not None and (len(split) != 1 or split[0][0] != "work-precision"
                               or not split[0][1]):  # fmt: skip
        raise FoamsiloError("--values: needs one series, --only work-precision/NAME")
    stem = "suite-quick" if quick else "suite"
    result: dict[str, Any] = {}
    previous = out_dir / f"{stem}.json"
    if only and previous.exists():
        # a partial rerun updates its entries in the existing report
        result = json.loads(previous.read_text())
        result.pop("checks", None)
    commits = result.get("commits") or {k: result.get("commit") for k in ENTRIES if k in result}
    timing = result.get("wall_s", {})
    # how each entry's cases ran: a partial rerun with other --jobs keeps the
    # others' (older reports hold one value for all)
    earlier = _jobs(result["jobs"]) if "jobs" in result else None
    ran_as = result.get("jobs_by_entry") or {k: earlier for k in timing if earlier}
    # and on which machine: a partial rerun elsewhere keeps the others' (older
    # reports hold one machine for all)
    cpu_of = result.get("cpu_by_entry") or {
        k: result["machine"]["cpu"] for k in timing if "machine" in result
    }
    result.update({"quick": quick, "machine": machine_info(), "jobs": jobs_words(jobs)})
    at = git_commit()  # before the runs (git_commit)
    for name, sub in split:
        t0 = time.perf_counter()
        if sub and name == "presets":
            part = presets(quick, Path(work_dir) / name, jobs, limit, on_row, only=sub)
            rows = {r["label"]: r for r in (result.get(name) or {}).get("rows", [])}
            rows.update({r["label"]: r for r in part["rows"]})
            result[name] = {"rows": [rows[k] for k in sorted(rows)]}
            key = f"{name}/{sub}"
        elif sub and name == "time-step":
            part = time_step_independence(quick, Path(work_dir) / name, jobs, limit, on_row,
                                          only=sub)  # fmt: skip
            result[name] = {"scenes": _merged_scenes(result.get(name), part["scenes"])}
            key = f"{name}/{sub}"
        elif sub:
            earlier = (result.get(name) or {}).get(sub)
            part = work_precision(quick, Path(work_dir) / name, jobs, limit, on_row, series=sub,
                                  values=values, earlier=earlier)  # fmt: skip
            result[name] = {**(result.get(name) or {}), **part}
            key = f"{name}/{sub}"
        else:
            result[name] = ENTRIES[name](quick, Path(work_dir) / name, jobs, limit, on_row)
            key = name
            # the whole entry rerun: its parts' earlier reruns are in it now
            for book in (timing, commits, ran_as, cpu_of):
                for k in [k for k in book if k.startswith(f"{name}/")]:
                    del book[k]
        spent = time.perf_counter() - t0
        if values is not None:
            # some rows added: the series' other rows keep where, how and
            # from which commit they ran
            timing[key] = timing.get(key, 0.0) + spent
            commits[key] = _joined(commits.get(key), at)
            ran_as[key] = _joined(ran_as.get(key), result["jobs"])
            cpu_of[key] = _joined(cpu_of.get(key), result["machine"]["cpu"])
        else:
            timing[key] = spent
            commits[key] = at
            ran_as[key] = result["jobs"]
            cpu_of[key] = result["machine"]["cpu"]
    result["wall_s"] = timing
    result["commits"] = commits
    result["jobs_by_entry"] = ran_as
    result["cpu_by_entry"] = cpu_of
    every = {c for v in commits.values() if v for c in str(v).split(", ")}
    result["commit"] = ", ".join(sorted(every))
    return write_report(result, out_dir, stem)


def _merged_scenes(
    earlier: dict[str, Any] | None, new: list[dict[str, Any]]
) -> list[dict[str, Any]]:
    """Return the time-step entry's scenes, ``new`` in place of theirs, in suite.toml's order.

    A scene no longer in suite.toml keeps its place after the listed ones.
    """
    by_label = {s["label"]: s for s in (earlier or {}).get("scenes", [])}
    by_label.update({s["label"]: s for s in new})
    order = time_step_scenes()
    listed = [by_label[k] for k in order if k in by_label]
    return listed + [s for k, s in by_label.items() if k not in order]


def _joined(*words: str | None) -> str | None:
    """Return the words joined by ", ", each once, in order (None and repeats left out)."""
    seen = [w for w in words if w]
    return ", ".join(dict.fromkeys(p for w in seen for p in w.split(", "))) or None


def rewrite_report(quick: bool, out_dir: Path) -> dict[str, Any]:
    """Write the report again from ``suite[-quick].json`` in ``out_dir``; nothing runs.

    The derived figures (errors, grid convergence, checks) are computed
    again from the rows, so a new analysis reaches results already paid for;
    a row missing a figure of a later version takes it from its case's
    ``summary.json`` when the case is still there.
    """
    stem = "suite-quick" if quick else "suite"
    path = out_dir / f"{stem}.json"
    if not path.is_file():
        raise FoamsiloError(f"{path}: no suite results to write a report from; run the suite first")
    result = json.loads(path.read_text())
    for row in _case_rows(result):
        case_dir = Path(row["case_dir"])
        summary = case_dir / "summary.json"
        if summary.is_file():
            fields = summary_fields(json.loads(summary.read_text()))
            row.update({k: v for k, v in fields.items() if row.get(k) is None})
        if case_dir.is_dir():
            row.update(record_fields(case_dir))
    for data in (result.get("work-precision") or {}).values():
        derive_work_precision(data)
    if result.get("time-step"):
        derive_time_step(result["time-step"])
    if result.get("gas-lab"):
        derive_gas_lab(result["gas-lab"])
    return write_report(result, out_dir, stem)


def _case_rows(node: Any) -> list[Row]:
    """Every row of a case in the suite's results (a dict with ``case_dir``), at any depth."""
    if isinstance(node, dict):
        if "case_dir" in node and "outcome" in node:
            return [node]
        return [r for v in node.values() for r in _case_rows(v)]
    if isinstance(node, list):
        return [r for v in node for r in _case_rows(v)]
    return []


def write_report(result: dict[str, Any], out_dir: Path, stem: str) -> dict[str, Any]:
    """Check the figures; write the plots, ``<stem>.json`` and ``<stem>.md``; return the result."""
    result.pop("checks", None)
    result["checks"] = [{**asdict(c), "passed": c.passed} for c in checks(result)]
    if not result.get("quick"):  # the quick suite's coarse grids judge no target
        table = study_table("suite")
        result["targets"] = as_dicts(judge(result, table))
        result["default_resolutions"] = default_resolutions(result, table["default-resolution"])
    out_dir.mkdir(parents=True, exist_ok=True)
    plot_work_precision(result, out_dir / f"{stem}-work-precision.png")
    plot_beverloo(result, out_dir / f"{stem}-beverloo.png")
    plot_time_steps(result, out_dir / f"{stem}-time-steps.png")
    write_whole(out_dir / f"{stem}.json", dumps(result, indent=1) + "\n")
    write_whole(out_dir / f"{stem}.md", suite_markdown(result, stem))
    return result


# ------------------------------------------------------------------- output
def plot_work_precision(result: dict[str, Any], path: Path) -> None:
    """Error against the finest resolution over wall time (work-precision)."""
    from foamsilo.plots import finish, labelled_loglog, subplots

    wp = result.get("work-precision")
    if not wp:
        return
    import matplotlib.pyplot as plt

    fig, ax = subplots(size=(7, 5.5))
    # more series than the default cycle's ten colours: one colour each
    ax.set_prop_cycle(color=[plt.get_cmap("tab20")(i) for i in range(20)])
    for preset, data in wp.items():
        rows = [r for r in data["rows"][:-1] if r.get("err_vs_finest")]
        labelled_loglog(ax, rows, "wall_s", "err_vs_finest", "cells_across", f"{preset} (N across)")
    for level in (5, 2):
        ax.axhline(level, color="0.6", ls=":", lw=1)
    ax.set_xlabel("wall time per case [s] (one core)")
    ax.set_ylabel("|Q - Q(finest)| / Q(finest) [%]")
    finish(fig, ax, path, legend_size=6)


def plot_beverloo(result: dict[str, Any], path: Path) -> None:
    """Q against outlet size with the fitted Beverloo laws."""
    from foamsilo.plots import finish, subplots

    bev = result.get("beverloo")
    if not bev:
        return
    fig, axes = subplots(2, (11, 4.2))
    for ax, key in zip(axes, bev, strict=False):
        exp = bev[key].get("exponent", 2.5)
        unit = "kg/(m s)" if exp == 1.5 else "kg/s"
        rows = [r for r in bev[key]["rows"] if r.get("Q")]
        d = np.array([r["orifice_m"] for r in rows])
        ax.plot(d * 100, [r["Q"] for r in rows], "ko", label="siloFoam, steady Q")
        fit = bev[key].get("fit")
        if fit:
            dd = np.linspace(max(fit["f"], 0.0) + 1e-4, d.max() * 1.1, 100)
            ax.plot(
                dd * 100,
                fit["C"] * (dd - fit["f"]) ** exp,
                "C3-",
                label=f"W = C (d - f)^{exp}: C = {fit['C']:.4g}, f = {fit['f'] * 100:.2f} cm, "
                f"R^2 = {fit['R2']:.4f}",
            )
        ax.set_xlabel("outlet size [cm]")
        ax.set_ylabel(f"Q [{unit}]")
        ax.set_title(bev[key].get("title", key), fontsize=9)
    finish(fig, axes, path, legend_size=7)


def plot_time_steps(result: dict[str, Any], path: Path) -> None:
    """Time-step histories of the stiff and extreme cases."""
    from foamsilo.plots import finish, subplots

    ext = result.get("extremes")
    if not ext:
        return
    fig, ax = subplots(size=(7, 4.5))
    for r in ext["rows"]:
        h = np.array(r.get("dt_history") or [])
        if h.size:
            ax.semilogy(h[:, 0], h[:, 1], lw=1, label=f"{r['label']}: {r['outcome']}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("time step [s]")
    finish(fig, ax, path, legend_size=6)


def _time_error_words(se: float | None) -> str:
    """Return the sentence on how far the rows' time averages move the extrapolation."""
    if se is None:
        return (
            "The rows' time averages, each moved by its standard error, leave no "
            "extrapolation or have none: its time error is not known."
        )
    return (
        f"The rows' time averages alone move the extrapolation by {se:.2%} (one standard "
        "error, propagated from the three grids' batch-means errors; not in the GCI)."
    )


def _convergence_words(conv: dict[str, Any] | None) -> str:
    """Return one paragraph on the grid convergence of a work-precision series."""
    if not conv:
        return (
            "Grid convergence: fewer than three steady resolutions of one refinement family "
            "(rows whose 3D O-grid sits at its floors are left out), no estimate."
        )
    grids = ", ".join(map(str, conv["cells"][-3:]))
    head = f"Grid convergence of Q (the three finest steady grids, {grids} across): {conv['kind']}"
    if conv["kind"] != "monotone":
        return f"{head}; uncertainty of the finest {fmt(conv['gci'], '.1%')} (half the range)."
    by_triple = ", ".join(fmt(p, ".2f") for p in conv["orders_by_triple"])
    used = conv.get("order_used")
    capped = ""
    if used is not None and used < conv["order"]:
        capped = (
            f", above the scheme's formal order, so the extrapolation and the GCI take p = {used:g}"
            + (
                f" and the GCI is at least {SAFETY_FACTOR:g} times the three grids' range "
                "(Eca & Hoekstra 2014)"
                if range_bounds_gci(conv["order"], used)
                else ""
            )
        )
    elif used is not None and used > conv["order"]:
        capped = (
            f", under {LOW_ORDER:g}: not yet the asymptotic range, so the extrapolation and "
            f"the GCI take p = {used:g} and the safety factor {LOW_ORDER_SAFETY_FACTOR:g} "
            "(Eca & Hoekstra 2014)"
        )
    parts = [
        f"{head}, observed order p = {conv['order']:.2f} (each run of three grids: {by_triple})"
        f"{capped}, extrapolated Q = {conv['extrapolated']:.5g}, GCI of the finest "
        f"{conv['gci']:.1%}. {_time_error_words(conv.get('extrapolated_time_error'))}"
    ]
    for key, level in (("2pct", "2%"), ("1pct", "1%")):
        n, measured = conv[f"cells_for_{key}"], conv[f"coarsest_within_{key}"]
        cost = conv.get(f"cpu_per_simulated_s_for_{key}")
        where = (
            f"measured from {measured} across (its rate's time band inside)"
            if measured
            else "no measured grid"
        )
        proj = f"; the error model puts it at {n:.0f} across" if n is not None else ""
        if cost is not None:
            proj += (
                f", a projected {cost:.3g} CPU-s per simulated second (cost ~ N^"
                f"{conv['cost_exponent']:.2f}, fitted on the rows)"
            )
        parts.append(f"Within {level} of the extrapolation: {where}{proj}.")
    return " ".join(parts)


def _targets_markdown(result: dict[str, Any]) -> list[str]:
    """Return the section on issue 18's targets and the presets' default grids."""
    targets, defaults = result.get("targets") or [], result.get("default_resolutions") or []
    if not (result.get("work-precision") and (targets or defaults)):
        return []
    lines = [
        "## Issue 18's targets",
        "",
        "Judged on the rows above (one core per case; `suite.toml` `[[targets]]`, each "
        "with its reason). Met: measured within the limit; missed: measured or projected "
        "beyond it; not shown: no measured grid reaches the level. A grid is within a "
        "level only with its rate's 95% time-averaging band (two standard errors of the "
        "batch means) inside it.",
        "",
        "| target | figure | limit | verdict | where it stands |",
        "| --- | --- | --- | --- | --- |",
    ]
    for t in targets:
        verdict = t["verdict"] if t["verdict"] == "met" else f"**{t['verdict']}**"
        lines.append(
            f"| {t['what']} | {fmt(t['value'], '.3g')} {t['unit']} | {t['limit']:g} "
            f"| {verdict} | {t['detail']} |"
        )
    lines += [
        "",
        "**The presets' default grids** against their own series (issue 18 asks the 1% "
        "grid in 2D and axisymmetric, the 2% one in 3D):",
        "",
        "| preset | representation | cells across | error there (its 95% time band) "
        "| asked | default within "
        "| how | the grid asked |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in defaults:
        within = {True: "yes", False: "**no**", None: "-"}[r["within"]]
        lines.append(
            f"| {r['preset']} | {r['representation']} | {r['cells_across']} "
            f"| {fmt(r['error'], '+.2%')}{f' (±{b:.2%})' if (b := r.get('band')) else ''} "
            f"| {fmt(r['level'], '.0%')} | {within} | {r['how']} "
            f"| {r['needed']} |"
        )
    return [*lines, ""]


def short_cpu(name: str) -> str:
    """Return a processor's name without its marks ("Intel(R) Xeon(R) Processor": "Intel Xeon")."""
    words = name.replace("(R)", "").replace("(TM)", "").split("@")[0].split()
    return " ".join(w for w in words if w not in ("Processor", "CPU"))


def _cpu_cell(rows: list[dict[str, Any]]) -> Callable[[dict[str, Any]], str]:
    """Return a table's CPU-time cell: with its row's processor where the rows name several.

    A CPU time is its machine's; rows of one table measured on different
    processors are not comparable without saying which.
    """
    named = {r["cpu"] for r in rows if r.get("cpu")}

    def cell(r: dict[str, Any]) -> str:
        text = fmt(r.get("cpu_s"), ".0f")
        return f"{text} ({short_cpu(r['cpu'])})" if len(named) > 1 and r.get("cpu") else text

    return cell


def _jobs(value: Any) -> str:
    # older reports hold the number of cases at a time
    return f"{value} cases at a time" if isinstance(value, int) else str(value)


def suite_markdown(result: dict[str, Any], stem: str) -> str:
    """Return the suite's report (Markdown)."""
    m = result["machine"]
    ran_as = result.get("jobs_by_entry") or {}
    cpu_of = result.get("cpu_by_entry") or {}
    # an entry whose rows ran on several machines names each
    cpus = {c for v in cpu_of.values() if v for c in v.split(", ")} | {m["cpu"]}
    one_cpu = len(cpus) == 1
    cmd = "foamsilo bench validation" + (" --quick" if result["quick"] else "")

    def how(k: str) -> str:
        jobs = ran_as.get(k) or _jobs(result["jobs"])
        return jobs if one_cpu else f"{jobs}, {cpu_of.get(k, m['cpu'])}"

    lines = [
        f"# Validation suite{' (quick)' if result['quick'] else ''}",
        "",
        f"`{cmd}` on {m['cpu'] if one_cpu else ' and '.join(sorted(cpus))}, {m['cores']} "
        f"cores; commit {result['commit']}. Wall time per entry"
        + ("" if one_cpu else " (the machine it ran on)")
        + ": "
        + ", ".join(f"{k} {v / 60:.1f} min ({how(k)})" for k, v in result["wall_s"].items())
        + ".",
        "",
    ]
    pre = result.get("presets")
    if pre:
        lines += [
            "## The presets at their defaults",
            "",
            "Each seed scene as `foamsilo run PRESET` runs it: its own mesh, end time and "
            "numerics. Swing: the step-to-step part of the rate's spread (above 1%: a "
            "numerical oscillation, no steady rate).",
            "",
            "| preset | representation | stress coupling | cells | outcome | Q | Q* (scale) "
            "| spread | swing | recoveries | steps | CPU [s] |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        cpu = _cpu_cell(pre["rows"])
        for r in pre["rows"]:
            q = r.get("Q")
            lines.append(
                f"| {r['label']} | {r['representation']} | {r['scheme']} "
                f"| {fmt(r.get('cells'), 'd')} | {r['outcome']} | {fmt(q, '.5g')} "
                f"| {fmt(r.get('Q_dimensionless'), '.4f')} ({r['flow_rate_scale']}) "
                f"| {fmt(r['Q_std'] / q if q and r.get('Q_std') is not None else None, '.2%')} "
                f"| {fmt(r.get('Q_step_swing'), '.2%')} | {fmt(r.get('recoveries'), 'd')} "
                f"| {fmt(r.get('steps'), 'd')} | {cpu(r)} |"
            )
        lines += [""] + [f"* **{r['label']}**: {r['detail']}" for r in pre["rows"]
                         if r.get("detail")] + [""]  # fmt: skip
    wp = result.get("work-precision")
    if wp:
        lines += [
            "## Error against run time",
            "",
            f"![work precision]({stem}-work-precision.png)",
            "",
        ]
        for preset, data in wp.items():
            about = f" {data['about']}" if data.get("about") else ""
            law = (f"law: {data['law']}, Q = {data['Q_law']:.5g}" if data.get("Q_law")
                   else "no analytic law")  # fmt: skip
            at = {
                k: f"{data[k]} across" if data[k] else "no grid"
                for k in ("recommend_5pct", "recommend_2pct")
            }
            lines += [
                f"**{preset}**{about} ({law}); resolution "
                f"for 5%: {at['recommend_5pct']}, for 2%: "
                f"{at['recommend_2pct']} (against the finest run).",
                "",
                "| cells across | cells | Q | Q* | vs finest | vs extrapolated | vs law "
                "| time error | wall [s] | CPU [s] | steps | recoveries |",
                "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
            ]
            cpu = _cpu_cell(data["rows"])
            for r in data["rows"]:
                q, qe = r.get("Q"), r.get("Q_time_error")
                # a rate that is not steady is no grid figure: said beside it
                shown = fmt(q, ".5g") + (f" ({r['outcome']})" if r["outcome"] != "steady" else "")
                floor = " (O-grid at its floors)" if r.get("o_grid_floored") else ""
                lines.append(
                    f"| {r['cells_across']}{floor} | {fmt(r.get('cells'), 'd')} "
                    f"| {shown} | {fmt(r.get('Q_dimensionless'), '.4f')} "
                    f"| {fmt(r.get('err_vs_finest'), '.1%')} "
                    f"| {fmt(r.get('err_vs_extrapolated'), '+.1%')} "
                    f"| {fmt(r.get('err_vs_law'), '+.1%')} "
                    f"| {fmt(qe / q if q and qe is not None else None, '.2%')} "
                    f"| {fmt(r.get('wall_s'), '.0f')} "
                    f"| {cpu(r)} | {fmt(r.get('steps'), 'd')} "
                    f"| {fmt(r.get('recoveries'), 'd')} |"
                )
            lines += ["", _convergence_words(data.get("convergence")), ""]
    bev = result.get("beverloo")
    if bev:
        lines += ["## Beverloo scaling", "", f"![Beverloo]({stem}-beverloo.png)", ""]
        for key in bev:
            title = bev[key].get("title", key)
            fit = bev[key].get("fit") or {}
            lines += [
                f"**{title}**: C = {fmt(fit.get('C'), '.4g')}, f = "
                f"{fmt(fit.get('f'), '.4f')} m, R² = {fmt(fit.get('R2'), '.4f')}"
                + (f", C/(ρ√g) = {fit['C_dimensionless']:.3f}" if "C_dimensionless" in fit else "")
                + ".",
                "",
                "| outlet [m] | Q | Q std | outcome | wall [s] |",
                "| --- | --- | --- | --- | --- |",
            ]
            for r in bev[key]["rows"]:
                lines.append(
                    f"| {r['orifice_m']:g} | {fmt(r.get('Q'), '.5g')} "
                    f"| {fmt(r.get('Q_std'), '.2g')} | {r['outcome']} "
                    f"| {fmt(r.get('wall_s'), '.0f')} |"
                )
            lines.append("")
    ext = result.get("extremes")
    if ext:
        lines += [
            "## Stiff and extreme cases",
            "",
            f"![time steps]({stem}-time-steps.png)",
            "",
            "| case | outcome | Q | vs default cap | steps | recoveries | Δt min – max [s] "
            "| wall [s] |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in ext["rows"]:
            lines.append(
                f"| {r['label']} | {r['outcome']} | {fmt(r.get('Q'), '.5g')} "
                f"| {fmt(r.get('vs_default_cap'), '+.1%')} | {fmt(r.get('steps'), 'd')} "
                f"| {fmt(r.get('recoveries'), 'd')} "
                f"| {fmt(r.get('dt_min'), '.2g')} – {fmt(r.get('dt_max'), '.2g')} "
                f"| {fmt(r.get('wall_s'), '.0f')} |"
            )
        lines += [""] + [
            f"* **{r['label']}**: {r['detail']}" for r in ext["rows"] if r.get("detail")
        ]
        lines.append("")
    gl = result.get("gas-lab")
    if gl:
        lines += [
            "## Gas-assisted lab silo against eqs. 17 and 23",
            "",
            "Zhou Table I cylinder, axisymmetric. Q: the steady rate with its standard "
            "deviation; Q/Q0 against the same grains with the open top. Eq. 17: "
            "sqrt(1 + G), G the run's mean dp_f/dz over the zone of radius D/2 above the "
            "orifice over rho g (the model's mechanism, Zhou Fig. 6b); eq. 23: the "
            "experiments' law (Table I constants, A = 1). Force balance: eq. 17 squared, "
            "((Q/Q0)^2 - 1 - G) / (1 + |G|), the difference over the forces it balances "
            "(the check's figure; the rate's difference turns on 1 + G, small near G = -1).",
            "",
            "| case | outcome | Q [kg/s] | swing | Q/Q0 simulated | G | Q/Q0 eq. 17 | difference "
            "| force balance | Q/Q0 eq. 23 | difference | recoveries | wall [s] |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in gl["rows"]:
            q = f"{fmt(r.get('Q'), '.4g')} ± {fmt(r.get('Q_std'), '.2g')}"
            lines.append(
                f"| {r['label']} | {r['outcome']} | {q} | {fmt(r.get('Q_step_swing'), '.2%')} "
                f"| {fmt(r.get('sim_ratio'), '.3f')} | {fmt(r.get('zone_gradient_scaled'), '.3g')} "
                f"| {fmt(r.get('eq17_ratio'), '.3f')} | {fmt(r.get('eq17_rel_error'), '+.1%')} "
                f"| {fmt(r.get('eq17_force_error'), '+.1%')} "
                f"| {fmt(r.get('eq23_ratio'), '.3f')} | {fmt(r.get('rel_error'), '+.1%')} "
                f"| {fmt(r.get('recoveries'), 'd')} | {fmt(r.get('wall_s'), '.0f')} |"
            )
        notes = [f"* **{r['label']}**: {r['outcome']}: {r['detail']}" for r in gl["rows"]
                 if r.get("detail")]  # fmt: skip
        lines += ["", *notes, ""]
    cap = result.get("cap")
    if cap:
        lines += [
            "## Q against the viscosity cap",
            "",
            "| scene | eta_max [rho sqrt(g L^3)] | Q | change | outcomes |",
            "| --- | --- | --- | --- | --- |",
        ]
        for pair in cap["pairs"]:
            caps = " / ".join(f"{c:g}" for c in pair["caps"])
            qs = " / ".join(fmt(q, ".5g") for q in pair["Q"])
            lines.append(
                f"| {pair['label']} | {caps} | {qs} | {fmt(pair.get('change'), '+.2%')} "
                f"| {' / '.join(pair['outcomes'])} |"
            )
        lines.append("")
    ts = result.get("time-step")
    if ts and ts["scenes"]:
        lines += [
            "## Q against the time step",
            "",
            "Each scene on a fixed mesh at its default Courant limits (its first row) and "
            "at smaller ones (the all-cell and the free-surface limit both set to the "
            "value; two values: all cells / free surface). "
            "Spread: the standard deviation of the instantaneous rate in the steady "
            "window over Q; swing: the part of it that changes from one step to the next "
            "(`Q_step_swing`; above 1% the report warns: a numerical oscillation).",
            "",
            "| scene | Courant | outcome | Q | vs default step | spread | swing "
            "| Δt median [s] | steps | recoveries | CPU [s] |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        cpu = _cpu_cell([r for scene in ts["scenes"] for r in scene["rows"]])
        for scene in ts["scenes"]:
            for r in scene["rows"]:
                lines.append(
                    f"| {scene['label']} | {_courant_words(r)} | {r['outcome']} "
                    f"| {fmt(r.get('Q'), '.5g')} | {fmt(r.get('vs_default_step'), '+.2%')} "
                    f"| {fmt(r.get('spread'), '.2%')} | {fmt(r.get('Q_step_swing'), '.2%')} "
                    f"| {fmt(r.get('dt_median'), '.3g')} "
                    f"| {fmt(r.get('steps'), 'd')} | {fmt(r.get('recoveries'), 'd')} "
                    f"| {cpu(r)} |"
                )
        lines.append("")
    lines += _targets_markdown(result)
    lines += [
        "## Checks",
        "",
        "| entry | figure | value | allowed | why | |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for c in result["checks"]:
        lines.append(
            f"| {c['entry']} | {c['name']} | {fmt(c['value'], '.4g')} "
            f"| [{c['low']:g}, {c['high']:g}] | {c['why']} "
            f"| {'pass' if c['passed'] else '**FAIL**'} |"
        )
    return "\n".join(lines) + "\n"
