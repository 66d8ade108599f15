"""Sweeps: many variations of one scene, run under a CPU budget, resumable.

A sweep file (TOML) names a base scene and the variations::

    base = "zhou-planar"            # preset name or scene file (relative to the sweep file)
    name = "orifice-width"          # cases go to runs/<name>/ unless `output` is given
    ranks_per_case = 1              # MPI ranks of each case
    cpu_budget = 2                  # cores to use (default: all); cases at once =
                                    # cpu_budget // ranks_per_case

    [set]                           # overrides applied to every case
    "run.end_time" = 0.5

    [grid]                          # every combination of these values ...
    "silo.orifice_width" = [0.02, 0.025, 0.03]

    [[cases]]                       # ... or (and) an explicit list of overrides
    "silo.orifice_width" = 0.035

Each case runs as ``foamsilo run BASE -o DIR --set ... --resume --json`` in
its own process, so the command line's rules hold per case: a finished case
is only post-processed again, an interrupted one continues from its latest
complete time directory, a fresh one is created. Every scene is validated
before anything runs. The summary table (``summary.csv``, ``summary.json``)
is written whole (temporary file, then rename) after every finished case.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from foamsilo.case import write_whole
from foamsilo.errors import FoamsiloError, SceneError
from foamsilo.scene import load_scene

#: Reduced outputs copied from each case's summary into the table
OUTPUT_KEYS = (
    "representation",
    "cells",
    "steady",
    "Q",
    "Q_std",
    "Q_from_volume",
    "Q_units",
    "Q_dimensionless",
    "flux_vs_volume_rel_diff",
    "mass_balance_rel_error",
)
_SWEEP_KEYS = {"base", "name", "output", "ranks_per_case", "cpu_budget", "set", "grid", "cases"}


@dataclass
class SweepCase:
    """One case of a sweep: its overrides and directory."""

    index: int
    overrides: dict[str, Any]
    directory: Path

    @property
    def sets(self) -> list[str]:
        """The overrides as ``--set KEY=VALUE`` values."""
        return [f"{k}={_toml_value(v)}" for k, v in self.overrides.items()]


@dataclass
class Sweep:
    """A parsed, validated sweep file."""

    path: Path
    base: str
    name: str
    output: Path
    ranks_per_case: int
    cpu_budget: int
    cases: list[SweepCase]

    @property
    def cases_at_once(self) -> int:
        """How many cases run at the same time (cases x ranks <= budget)."""
        return max(1, self.cpu_budget // self.ranks_per_case)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return "'" + v + "'"
    return repr(v)


def _slug(overrides: dict[str, Any]) -> str:
    parts = [f"{k.split('.')[-1]}={v}" for k, v in overrides.items()]
    text = "_".join(parts) or "base"
    return "".join(c if c.isalnum() or c in "=._-" else "-" for c in text)[:80]


def load_sweep(path: Path) -> Sweep:
    """Read and validate a sweep file (every case's scene included).

    Raises
    ------
    SceneError
        A sweep key or a case's scene value is wrong; the message names it
        (``sweep.cpu_budget``, ``cases[2].silo.orifice_width``).
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise SceneError("sweep", f"cannot read {path}: {exc}") from None
    unknown = sorted(set(data) - _SWEEP_KEYS)
    if unknown:
        raise SceneError(f"sweep.{unknown[0]}", f"unknown key; allowed: {sorted(_SWEEP_KEYS)}")
    if "base" not in data:
        raise SceneError("sweep.base", "missing: a preset name or a scene file")
    base = str(data["base"])
    if Path(base).suffix == ".toml" and not Path(base).is_absolute():
        base = str((path.parent / base).resolve())
    name = str(data.get("name", path.stem))
    output = Path(data.get("output", Path("runs") / name))
    cores = os.cpu_count() or 1
    ranks = data.get("ranks_per_case", 1)
    budget = data.get("cpu_budget", cores)
    if not isinstance(ranks, int) or ranks < 1:
        raise SceneError("sweep.ranks_per_case", f"got {ranks!r}; allowed: an integer >= 1")
    if not isinstance(budget, int) or budget < ranks:
        raise SceneError(
            "sweep.cpu_budget", f"got {budget!r}; allowed: an integer >= ranks_per_case ({ranks})"
        )
    common = dict(data.get("set", {}))
    grid = data.get("grid", {})
    for k, vals in grid.items():
        if not isinstance(vals, list) or not vals:
            raise SceneError(f"sweep.grid.{k}", "must be a non-empty list of values")
    variants: list[dict[str, Any]] = []
    if grid:
        keys = list(grid)
        combos = itertools.product(*grid.values())
        variants += [dict(zip(keys, combo, strict=True)) for combo in combos]
    variants += [dict(c) for c in data.get("cases", [])]
    if not variants:
        raise SceneError("sweep.grid", "no cases: give [grid] values or [[cases]]")
    cases = []
    for i, v in enumerate(variants):
        overrides = {**common, **v}
        case = SweepCase(i, overrides, output / f"{i:03d}-{_slug(v)}")
        try:
            load_scene(base, case.sets)
        except SceneError as exc:
            raise SceneError(f"cases[{i}].{exc.field}", str(exc)) from None
        cases.append(case)
    return Sweep(path, base, name, output, ranks, budget, cases)


def _run_case(sweep: Sweep, case: SweepCase) -> dict[str, Any]:
    """Run (or resume, or just post-process) one case in its own process."""
    cmd = [sys.executable, "-m", "foamsilo.cli", "run", sweep.base, "-o", str(case.directory)]
    for s in case.sets:
        cmd += ["--set", s]
    cmd += ["--update", "--resume", "--quiet", "--json", "--np", str(sweep.ranks_per_case)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    try:
        payload = json.loads(proc.stdout)
    except json.JSONDecodeError:
        payload = {"ok": False, "error": {"type": "crash", "message": proc.stderr[-2000:]}}
    return payload


def _row(case: SweepCase, payload: dict[str, Any] | None) -> dict[str, Any]:
    row: dict[str, Any] = {"case": case.index, "directory": str(case.directory)}
    row.update(case.overrides)
    if payload is None:
        row["status"] = "pending"
        return row
    if payload.get("ok"):
        row["status"] = "ok"
        row.update({k: payload.get(k) for k in OUTPUT_KEYS})
        run = payload.get("run") or {}
        row["wall_s"] = run.get("wall_seconds")
        row["cpu_s"] = run.get("cpu_seconds")
    else:
        err = payload.get("error", {})
        row["status"] = err.get("type", "error")
        row["error"] = err.get("message", "")
    return row


def write_summary(sweep: Sweep, rows: list[dict[str, Any]]) -> None:
    """``summary.json`` and ``summary.csv`` of the sweep, each written whole."""
    sweep.output.mkdir(parents=True, exist_ok=True)
    payload = {"sweep": str(sweep.path), "base": sweep.base, "cases": rows}
    write_whole(sweep.output / "summary.json", json.dumps(payload, indent=2) + "\n")
    columns: list[str] = []
    for r in rows:
        columns += [k for k in r if k not in columns]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns)
    w.writeheader()
    for r in rows:
        w.writerow(r)
    write_whole(sweep.output / "summary.csv", buf.getvalue())


def run_sweep(sweep: Sweep, log: Any = None) -> list[dict[str, Any]]:
    """Run every case of ``sweep`` under its CPU budget; return the summary rows."""
    say = log or (lambda m: None)
    sweep.output.mkdir(parents=True, exist_ok=True)
    results: dict[int, dict[str, Any] | None] = {c.index: None for c in sweep.cases}
    say(
        f"sweep {sweep.name}: {len(sweep.cases)} cases, {sweep.cases_at_once} at once x "
        f"{sweep.ranks_per_case} rank(s) (budget {sweep.cpu_budget} cores)"
    )
    write_summary(sweep, [_row(c, None) for c in sweep.cases])  # all pending
    with ThreadPoolExecutor(max_workers=sweep.cases_at_once) as pool:
        futures = {pool.submit(_run_case, sweep, c): c for c in sweep.cases}
        for fut in as_completed(futures):
            case = futures[fut]
            results[case.index] = fut.result()
            rows = [_row(c, results[c.index]) for c in sweep.cases]
            write_summary(sweep, rows)
            r = rows[case.index]
            say(f"case {case.index} ({case.directory.name}): {r['status']}")
    rows = [_row(c, results[c.index]) for c in sweep.cases]
    write_summary(sweep, rows)
    if all(r["status"] == "pending" for r in rows):
        raise FoamsiloError("no case ran")
    _compare_and_report(sweep.output, say)
    return rows


def _compare_and_report(output: Path, say: Any) -> None:
    """Set the sweep's points on the analytic curves; write its ``report.md``."""
    from foamsilo.compare import COMPARE_MD, compare
    from foamsilo.report import sweep_report

    try:
        compare(output)
    except FoamsiloError as exc:
        (output / COMPARE_MD).unlink(missing_ok=True)
        say(f"no comparison with an analytic law: {exc}")
    say(f"report: {sweep_report(output)}")
