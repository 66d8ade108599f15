"""Issue 18's cost targets and the presets' default grids, judged on the suite's rows.

The validation suite (:mod:`foamsilo.studies.suite`) measures the steady Q of
each work-precision series at several grids, with its cost, and every preset at
its defaults. This module reads those results: for each target of
``suite.toml`` ``[[targets]]`` the figure it asks for (CPU-s per simulated
second, wall time, cost per cell and step), a verdict, and, for a target
missed, what stands in the way (the grid it would need and what that costs);
and for each preset of ``[default-resolution]`` the error of its default grid
against its series' extrapolated Q. Nothing here runs a case: the figures are
recomputed from ``suite.json`` whenever the report is written.

Verdicts: ``met`` (measured within the limit), ``missed`` (measured or
projected beyond it), ``not shown`` (no measured grid reaches the level and no
projection says it misses, or the series did not run).

A measured grid is within a level only with its rate's time-averaging band
(:func:`band`, the 95% half-width the reports give) inside it: a margin
smaller than what averaging leaves unknown does not show the grid is there.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from foamsilo.post.convergence import FORMAL_ORDER, GridConvergence, coarsest_within

Row = dict[str, Any]

#: A target's unit, by kind
UNITS = {
    "cost": "CPU-s per simulated s",
    "wall": "s wall",
    "cell-step": "x",
    "preset": "s wall",
}


@dataclass(frozen=True)
class Verdict:
    """One target's figure against its limit.

    Attributes
    ----------
    name, what, kind, why : str
        The target as ``suite.toml`` gives it.
    limit : float
        The largest figure that meets it, in ``unit``.
    unit : str
        The figure's unit (:data:`UNITS`).
    value : float or None
        The figure, measured or projected (``detail`` says which); None where
        nothing measures it.
    verdict : str
        ``met``, ``missed`` or ``not shown``.
    detail : str
        Where the figure comes from and, for a missed target, what stands in
        the way.
    """

    name: str
    what: str
    kind: str
    why: str
    limit: float
    unit: str
    value: float | None
    verdict: str
    detail: str


def band(row: Row) -> float:
    """Return a row's 95% time-averaging half-width over its Q (0 where not measured).

    The time part of :func:`foamsilo.post.grid.combined_uncertainty`, the band
    a run reports (two standard errors of the batch-means estimate).
    """
    from foamsilo.post.grid import combined_uncertainty

    q, se = row.get("Q"), row.get("Q_time_error")
    if not q or se is None or not math.isfinite(se):
        return 0.0
    return float(combined_uncertainty(float(q), float(se), None)["relative"])


def cost_fit(rows: list[Row]) -> tuple[float, float] | None:
    """Fit CPU-s per simulated second as ``c0 n^k`` over a series' rows.

    Parameters
    ----------
    rows : list of dict
        Work-precision rows with ``cells_across``, ``cpu_s`` and
        ``simulated_time_s``.

    Returns
    -------
    tuple of float or None
        ``(k, ln c0)``; None with fewer than two rows that have a cost.
    """
    pts = [(r["cells_across"], r["cpu_s"] / r["simulated_time_s"]) for r in rows
           if r.get("cpu_s") and r.get("simulated_time_s")]  # fmt: skip
    if len(pts) < 2:
        return None
    k, lnc0 = np.polyfit(np.log([n for n, _ in pts]), np.log([c for _, c in pts]), 1)
    return float(k), float(lnc0)


def _cost(row: Row) -> float | None:
    return row["cpu_s"] / row["simulated_time_s"] if row.get("cpu_s") and row.get(
        "simulated_time_s") else None  # fmt: skip


def _grid(conv: dict[str, Any] | None) -> GridConvergence | None:
    """Return the series' grid convergence rebuilt from its report dict (monotone only)."""
    if not conv or conv.get("kind") != "monotone" or conv.get("extrapolated") is None:
        return None
    kwargs: dict[str, Any] = {f.name: conv.get(f.name) for f in fields(GridConvergence)}
    return GridConvergence(**kwargs)


def family(rows: list[Row]) -> list[Row]:
    """Return the rows a series' convergence is judged on: steady, off an O-grid floor."""
    return [r for r in rows if r.get("Q") and r.get("outcome") == "steady"
            and not r.get("o_grid_floored")]  # fmt: skip


def _order_words(g: GridConvergence) -> str:
    return (
        f"observed order {g.order:.2f}, extrapolated Q {g.extrapolated:.5g}, "
        f"GCI of the finest {g.gci:.1%}"
    )


@dataclass(frozen=True)
class _Resolution:
    """Where one series reaches a level: the grid, its cost, measured or projected."""

    series: str
    cells: float
    cost: float | None
    measured: bool
    #: the processor a measured cost was measured on, where its row names it
    cpu: str | None = None

    def where(self) -> str:
        how = "measured" if self.measured else "projected by the error model"
        on = f" on {self.cpu}" if self.cpu else ""
        cost = f", {self.cost:.3g} CPU-s per simulated s{on}" if self.cost is not None else ""
        return f"{self.cells:.0f} across ({how}){cost}"

    def words(self) -> str:
        return f"{self.series}: {self.where()}"


def _resolution(
    name: str, data: dict[str, Any], level: float, refs: list[float] | None = None
) -> _Resolution | None:
    """Return a series' coarsest grid within ``level`` of every extrapolated Q, with its cost.

    ``refs``: the extrapolated Q of every series of the scene (default: this
    series' own); the converged Q is known only to their spread, so a grid
    counts where it is within ``level`` of each. Beyond the finest grid the
    error model takes this series to ``level`` less its extrapolation's
    distance to the farthest one; None where that distance is ``level`` or more.
    """
    g = _grid(data.get("convergence"))
    if g is None or g.error_vs_extrapolated is None or g.extrapolated is None:
        return None
    refs = refs or [g.extrapolated]
    steady = family(data["rows"])
    errs = [max(abs(r["Q"] / e - 1) for e in refs) + band(r) for r in steady]
    n = coarsest_within([r["cells_across"] for r in steady], errs, level)
    if n is not None:
        row = next(r for r in steady if r["cells_across"] == n)
        return _Resolution(name, float(n), _cost(row), True, row.get("cpu"))
    gap = max(abs(g.extrapolated / e - 1) for e in refs)
    model = g.cells_for(level - gap) if gap < level else None
    if model is None:
        return None
    fit = cost_fit(steady)
    cost = math.exp(fit[1]) * model ** fit[0] if fit else None
    return _Resolution(name, model, cost, False)


def _cost_target(t: dict[str, Any], wp: dict[str, Any]) -> tuple[float | None, str, str]:
    level = float(t["level"])
    grids = {s: g for s in t["series"] if s in wp
             if (g := _grid(wp[s].get("convergence"))) is not None}  # fmt: skip
    missing = [s for s in t["series"] if s not in wp]
    if not grids:
        return None, "not shown", "no series with a grid convergence estimate" + (
            f" ({', '.join(missing)} not run)" if missing else "")  # fmt: skip
    refs = _extrapolations(wp, list(grids))
    spread = _spread(refs)
    span = (
        "extrapolated Q: "
        + ", ".join(f"{s} {g.extrapolated:.5g} (order {g.order:.2f})" for s, g in grids.items())
        + (
            f"; their spread {spread:.1%}, within which the converged Q is known"
            if len(refs) > 1
            else ""
        )  # fmt: skip
    )
    found = [r for s in grids if (r := _resolution(s, wp[s], level, refs)) is not None]
    if not found:
        return (
            None,
            "missed",
            (
                f"{span}. In the way: no grid is within {level:.0%} of every extrapolation, "
                f"measured or by the error model (the orders "
                + ", ".join(f"{g.order:.2f}" for g in grids.values())
                + f" against the scheme's {FORMAL_ORDER:g}, the extrapolations "
                f"{spread:.1%} apart)"
            ),
        )
    priced = [r for r in found if r.cost is not None]
    best = min(priced, key=lambda r: r.cost or math.inf) if priced else found[0]
    others = "; ".join(r.words() for r in found if r is not best)
    g = grids[best.series]
    detail = f"cheapest within {level:.0%} of every extrapolation: {best.words()}" + (
        f"; the others: {others}" if others else "") + f". {span}"  # fmt: skip
    if best.cost is None:
        return None, "not shown", detail
    if best.cost <= float(t["limit"]):
        verdict = "met" if best.measured else "not shown"
    else:
        verdict = "missed"
        own = _resolution(best.series, wp[best.series], level)
        mine = g.extrapolated
        if own is not None and own.cells < best.cells and mine is not None:
            # the series' own limit is reached sooner: the other estimates cost the rest
            far, q = max(((s, float(h.extrapolated)) for s, h in grids.items()
                          if h.extrapolated is not None),
                         key=lambda sq: abs(sq[1] / mine - 1))  # fmt: skip
            detail += (
                f". In the way: the estimates' spread; {best.series} is within {level:.0%} "
                f"of its own extrapolation from {own.where()}, and "
                f"within {level:.0%} of the farthest ({far}, {q:.5g}) from "
                f"{best.cells:.0f} across, {best.cost / float(t['limit']):.2g} times the target"
            )
            if own.cpu and best.cpu and own.cpu != best.cpu:
                # a cost is its machine's: two rows' costs compare only on one
                detail += " (the two costs measured on different processors)"
        else:
            detail += (
                f". In the way: Q converges at order {g.order:.2f}, "
                f"{'under' if (g.order or 0.0) < FORMAL_ORDER else 'not under'} the scheme's "
                f"{FORMAL_ORDER:g}, so the {level:.0%} grid is {best.cells:.0f} across and "
                f"costs {best.cost / float(t['limit']):.2g} times the target"
            )
    return best.cost, verdict, detail


def _extrapolated(t: dict[str, Any], wp: dict[str, Any]) -> list[tuple[float, str]]:
    """Return every extrapolated Q a ``wall`` target's rows are judged on, each with whose."""
    out = []
    for name in [t["series"][0], *t.get("reference", [])]:
        g = _grid((wp.get(name) or {}).get("convergence"))
        if g is not None and g.extrapolated is not None:
            out.append((g.extrapolated, f"{name}'s {g.extrapolated:.5g} ({_order_words(g)})"))
    return out


def _wall_target(t: dict[str, Any], wp: dict[str, Any]) -> tuple[float | None, str, str]:
    name, level = t["series"][0], float(t["level"])
    if name not in wp:
        return None, "not shown", f"{name} not run"
    refs = _extrapolated(t, wp)
    steady = family(wp[name]["rows"])
    if not refs or not steady:
        return None, "not shown", f"no extrapolated Q for {name}"
    # the converged Q is known to the extrapolations' spread: the farthest counts
    errs = [max((r["Q"] / q - 1 for q, _ in refs), key=abs) for r in steady]
    table = ", ".join(f"{r['cells_across']} across {e:+.1%} ({r['wall_s'] / 60:.1f} min)"
                      for r, e in zip(steady, errs, strict=True))  # fmt: skip
    reach = [abs(e) + band(r) for r, e in zip(steady, errs, strict=True)]
    n = coarsest_within([r["cells_across"] for r in steady], reach, level)
    detail = f"against the farthest of {'; '.join(w for _, w in refs)}: {table}"
    if n is None:
        return None, "not shown", f"no grid within {level:.0%}; {detail}"
    wall = next(r["wall_s"] for r in steady if r["cells_across"] == n)
    verdict = "met" if wall <= float(t["limit"]) else "missed"
    return wall, verdict, f"{n} across; {detail}"


def _row(wp: dict[str, Any], name: str, cells: int) -> Row | None:
    data = wp.get(name)
    rows = [r for r in (data or {}).get("rows", []) if r["cells_across"] == cells]
    return rows[0] if rows else None


def _cell_step_target(t: dict[str, Any], wp: dict[str, Any]) -> tuple[float | None, str, str]:
    per: list[float] = []
    words = []
    for name, cells in (t["a"], t["b"]):
        r = _row(wp, name, int(cells))
        if r is None or not (r.get("cpu_s") and r.get("cells") and r.get("steps")):
            return None, "not shown", f"{name} at {cells} across not run"
        per.append(r["cpu_s"] / (r["cells"] * r["steps"]))
        words.append(f"{name} at {cells} across {per[-1] * 1e6:.2f} us per cell-step")
    ratio = per[0] / per[1]
    return ratio, "met" if ratio <= float(t["limit"]) else "missed", "; ".join(words)


def _preset_error(data: dict[str, Any], cells: int) -> tuple[float | None, str]:
    """Return a grid's error against its series' converged Q, and how it was found."""
    conv = data.get("convergence") or {}
    g = _grid(conv)
    row = next((r for r in data["rows"] if r["cells_across"] == cells), None)
    if g is not None and g.error_vs_extrapolated is not None and g.order_used:
        if row is not None and row.get("err_vs_extrapolated") is not None:
            return row["err_vs_extrapolated"], "measured, against the extrapolated Q"
        e1 = g.error_vs_extrapolated[-1]
        e = e1 * (g.cells[-1] / cells) ** g.order_used
        return e, "by the error model, against the extrapolated Q"
    if conv.get("kind") in ("oscillatory", "converged") and row is not None:
        unc = conv.get("gci")
        return row.get("err_vs_finest"), (
            f"against the finest grid ({conv['kind']}; its uncertainty {unc:.1%})"
            if unc is not None else "against the finest grid")  # fmt: skip
    return None, "no grid convergence estimate"


def _extrapolations(wp: dict[str, Any], names: list[str]) -> list[float]:
    """Return the extrapolated Q of each named series that has one."""
    grids = [_grid(wp[n].get("convergence")) for n in names]
    return [float(g.extrapolated) for g in grids if g is not None and g.extrapolated]


def _spread(refs: list[float] | None) -> float:
    """Relative spread of a scene's extrapolated Q (0 with fewer than two)."""
    return max(refs) / min(refs) - 1 if refs else 0.0


def _needed(name: str, data: dict[str, Any], level: float, refs: list[float] | None = None) -> str:
    res = _resolution(name, data, level, refs)
    if res is not None:
        return f"{level:.0%} needs {res.words()}"
    conv = data.get("convergence") or {}
    if conv.get("kind") in ("oscillatory", "converged"):
        # no order to extrapolate with: the coarsest grid within the level of the finest
        rows = [r for r in data["rows"][:-1] if r.get("err_vs_finest") is not None]
        n = coarsest_within([r["cells_across"] for r in rows],
                            [r["err_vs_finest"] for r in rows], level)  # fmt: skip
        if n is not None:
            return f"{level:.0%} of the finest grid from {n} across (measured, {conv['kind']})"
    words = f"no {level:.0%} grid from {name}"
    spread = _spread(refs)
    if spread >= level:
        # no grid can be within the level of estimates further apart than it:
        # say so, and what the series' own estimate alone would ask
        own = _resolution(name, data, level)
        words += f": the extrapolations are {spread:.1%} apart"
        if own is not None:
            words += f"; within {level:.0%} of its own alone: {own.where()}"
    return words


def default_resolutions(result: dict[str, Any], table: dict[str, Any]) -> list[dict[str, Any]]:
    """Each preset's default grid against its own series (and those it is ``also`` judged on).

    Parameters
    ----------
    result : dict
        The suite's results (``work-precision`` and ``presets``).
    table : dict
        ``suite.toml`` ``[default-resolution]``: preset -> series and level, and
        ``also``: the scene's other series, whose extrapolations count too (the
        converged Q is known only to their spread, as in a cost target).

    Returns
    -------
    list of dict
        One per preset of the presets table: its default cells across, the
        error there, the level asked, the grid that reaches it, and whether
        the default does (None where nothing measures it).
    """
    from foamsilo.scene import load_preset, preset_names

    wp = result.get("work-precision") or {}
    out = []
    for preset in preset_names():
        scene = load_preset(preset)
        cells = scene.cells_across
        row: dict[str, Any] = {"preset": preset, "representation": scene.representation,
                               "cells_across": cells, "error": None, "within": None}  # fmt: skip
        ask = table.get(preset)
        if ask is None or ask["series"] not in wp:
            row.update(level=None, how="no convergence series", needed="-")
            out.append(row)
            continue
        level = float(ask["level"])
        data = wp[ask["series"]]
        err, how = _preset_error(data, cells)
        # the preset's own run, where the suite ran it on this grid, over the model
        run = next((r for r in (result.get("presets") or {}).get("rows", [])
                    if r["label"] == preset and r.get("cells_across") == cells
                    and r.get("outcome") == "steady" and r.get("Q")), None)  # fmt: skip
        g = _grid(data.get("convergence"))
        if run is not None and g is not None and g.extrapolated:
            err, how = run["Q"] / g.extrapolated - 1, "the preset's run, against the extrapolated Q"
        also = [a for a in ask.get("also", []) if a in wp and _extrapolations(wp, [a])]
        refs = _extrapolations(wp, [ask["series"], *also]) if also else None
        grid_q = run or next((r for r in data["rows"] if r["cells_across"] == cells
                              and r.get("outcome") == "steady" and r.get("Q")), None)  # fmt: skip
        if refs and grid_q is not None:
            # against the farthest of the scene's estimates
            err = max((grid_q["Q"] / e - 1 for e in refs), key=abs)
            src = "the preset's run" if run is not None else "measured"
            how = f"{src}, against the farthest of {len(refs)} extrapolations"
            how += f" (also {', '.join(also)})"
        row.update(level=level, error=err, band=band(grid_q or {}), how=f"{ask['series']}, {how}",
                   needed=_needed(ask["series"], data, level, refs))  # fmt: skip
        row["within"] = None if err is None else abs(err) + row["band"] <= level
        out.append(row)
    return out


def _preset_target(t: dict[str, Any], result: dict[str, Any]) -> tuple[float | None, str, str]:
    rows = {r["preset"]: r for r in default_resolutions(result, {t["preset"]: t})}
    res = rows[t["preset"]]
    run = next((r for r in (result.get("presets") or {}).get("rows", [])
                if r["label"] == t["preset"]), None)  # fmt: skip
    if res["error"] is None or run is None or run.get("wall_s") is None:
        return None, "not shown", "the preset or its series not run"
    wall = float(run["wall_s"])
    detail = (
        f"{res['cells_across']} across: {res['error']:+.1%} ({res['how']}), "
        f"{wall:.0f} s wall for its {run['simulated_time_s']:g} s"
    )
    if res["within"] and wall <= float(t["limit"]):
        return wall, "met", detail
    return wall, "missed", f"{detail}. In the way: {res['needed']}"


def judge(result: dict[str, Any], table: dict[str, Any]) -> list[Verdict]:
    """Return every target of ``suite.toml`` judged on the suite's results.

    Parameters
    ----------
    result : dict
        The suite's results.
    table : dict
        The whole ``suite.toml`` (``targets`` and ``default-resolution``).
    """
    wp = result.get("work-precision") or {}
    out = []
    for t in table.get("targets", []):
        kind = t["kind"]
        if kind == "cost":
            value, verdict, detail = _cost_target(t, wp)
        elif kind == "wall":
            value, verdict, detail = _wall_target(t, wp)
        elif kind == "cell-step":
            value, verdict, detail = _cell_step_target(t, wp)
        elif kind == "preset":
            value, verdict, detail = _preset_target(t, result)
        else:
            raise ValueError(f"suite.toml target {t['name']!r}: kind {kind!r}; "
                             f"valid: {', '.join(UNITS)}")  # fmt: skip
        out.append(Verdict(t["name"], t["what"], kind, t["why"], float(t["limit"]),
                           UNITS[kind], value, verdict, detail))  # fmt: skip
    return out


def as_dicts(verdicts: list[Verdict]) -> list[dict[str, Any]]:
    """Plain data for ``suite.json``."""
    return [asdict(v) for v in verdicts]
