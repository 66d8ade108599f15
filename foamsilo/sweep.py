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
    "run.n_procs" = 2               # a case's own MPI ranks (else ranks_per_case)

    [slurm]                         # for --backend slurm (the command line's options win)
    partition = "compute"
    account = "silo-project"
    time_limit = "02:00:00"         # per job, Slurm's format
    sbatch = ["--qos=normal"]       # further #SBATCH lines

Each case runs through a :class:`~foamsilo.pipeline.Backend`: on this
machine (:func:`foamsilo.pipeline.run_many`, each case in its own worker
process under the CPU budget) or on a Slurm cluster
(:class:`foamsilo.slurm.SlurmBackend`, each case a batch job running the same
worker). Either way a case is resumable: a finished case is only reduced again, an interrupted
one continues from its latest complete time directory, a fresh one is
created, a running one is left alone (and reported). Every scene is
validated before anything runs. The summary table (``summary.csv``,
``summary.json``) is written whole (temporary file, then rename) after every
finished case.
"""

from __future__ import annotations

import csv
import io
import itertools
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from foamsilo.case import write_whole
from foamsilo.compare import COMPARE_MD, compare
from foamsilo.errors import FoamsiloError, SceneError
from foamsilo.jsonio import dumps
from foamsilo.pipeline import Backend, Budget, CaseSpec, LocalBackend, Outcome
from foamsilo.report import sweep_report
from foamsilo.scene import format_override, load_scene, read_toml
from foamsilo.slurm import SlurmOptions

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
_SWEEP_KEYS = {
    "base", "name", "output", "ranks_per_case", "cpu_budget", "set", "grid", "cases", "slurm"
}  # fmt: skip


@dataclass
class SweepCase:
    """One case of a sweep: its overrides and directory."""

    index: int
    overrides: dict[str, Any]
    directory: Path

    @property
    def sets(self) -> list[str]:
        """The overrides as ``--set KEY=VALUE`` values."""
        return [format_override(k, v) for k, v in self.overrides.items()]


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
    slurm: SlurmOptions = field(default_factory=SlurmOptions)

    @property
    def budget(self) -> Budget:
        """The CPU budget its cases run under."""
        return Budget(self.cpu_budget, self.ranks_per_case)

    @property
    def cases_at_once(self) -> int:
        """How many cases run at the same time (cases x ranks <= budget)."""
        return self.budget.cases_at_once


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
    data = read_toml(path, "sweep")
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
    slurm = data.get("slurm", {})
    if not isinstance(slurm, dict):
        raise SceneError("sweep.slurm", "must be a table of sbatch options")
    options = SlurmOptions.from_table(slurm, "sweep.slurm")
    return Sweep(path, base, name, output, ranks, budget, cases, options)


def _spec(sweep: Sweep, case: SweepCase) -> CaseSpec:
    """Return the pipeline's view of a sweep case: resumable, replaced when its scene changed."""
    return CaseSpec(
        case_dir=case.directory,
        scene=sweep.base,
        overrides=tuple(case.sets),
        # a case's own run.n_procs wins over the sweep's ranks_per_case
        n_procs=None if "run.n_procs" in case.overrides else sweep.ranks_per_case,
        resume=True,
        update=True,
        label=case.directory.name,
    )


def _row(case: SweepCase, outcome: Outcome | None) -> dict[str, Any]:
    row: dict[str, Any] = {"case": case.index, "directory": str(case.directory)}
    row.update(case.overrides)
    if outcome is None:
        row["status"] = "pending"
        return row
    if outcome.ok and outcome.summary is not None:
        row["status"] = "ok"
        row.update({k: outcome.summary.get(k) for k in OUTPUT_KEYS})
        run = outcome.summary.get("run") or {}
        row["wall_s"] = run.get("wall_seconds")
        row["cpu_s"] = run.get("cpu_seconds")
    else:
        row["status"] = outcome.status
        row["error"] = (outcome.error or {}).get("message", "")
    return row


def write_summary(sweep: Sweep, rows: list[dict[str, Any]]) -> None:
    """``summary.json`` and ``summary.csv`` of the sweep, each written whole."""
    sweep.output.mkdir(parents=True, exist_ok=True)
    payload = {"sweep": str(sweep.path), "base": sweep.base, "cases": rows}
    write_whole(sweep.output / "summary.json", dumps(payload) + "\n")
    columns: list[str] = []
    for r in rows:
        columns += [k for k in r if k not in columns]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns)
    w.writeheader()
    for r in rows:
        w.writerow(r)
    write_whole(sweep.output / "summary.csv", buf.getvalue())


def run_sweep(
    sweep: Sweep, log: Callable[[str], None] | None = None, backend: Backend | None = None
) -> list[dict[str, Any]]:
    """Run every case of ``sweep``; return the summary rows.

    ``backend``: where the cases run (default: this machine, under the
    sweep's CPU budget; :class:`foamsilo.slurm.SlurmBackend` for a cluster).
    """
    say = log or (lambda m: None)
    sweep.output.mkdir(parents=True, exist_ok=True)
    results: dict[int, Outcome | None] = {c.index: None for c in sweep.cases}
    if backend is None:
        budget = sweep.budget
        backend = LocalBackend(budget)
        say(
            f"sweep {sweep.name}: {len(sweep.cases)} cases, {budget.cases_at_once} at once x "
            f"{sweep.ranks_per_case} rank(s) (budget {sweep.cpu_budget} cores)"
        )
    else:
        say(f"sweep {sweep.name}: {len(sweep.cases)} cases")
    write_summary(sweep, [_row(c, None) for c in sweep.cases])  # all pending
    by_dir = {c.directory: c for c in sweep.cases}

    def done(outcome: Outcome) -> None:
        case = by_dir[outcome.spec.case_dir]
        results[case.index] = outcome
        rows = [_row(c, results[c.index]) for c in sweep.cases]
        write_summary(sweep, rows)
        say(f"case {case.index} ({case.directory.name}): {rows[case.index]['status']}")

    try:
        backend.run([_spec(sweep, c) for c in sweep.cases], on_done=done)
    finally:
        write_summary(sweep, [_row(c, results[c.index]) for c in sweep.cases])
    rows = [_row(c, results[c.index]) for c in sweep.cases]
    if all(r["status"] == "pending" for r in rows):
        raise FoamsiloError("no case ran")
    _compare_and_report(sweep.output, say)
    return rows


def _compare_and_report(output: Path, say: Callable[[str], None]) -> None:
    """Set the sweep's points on the analytic curves; write its ``report.md``."""
    try:
        compare(output)
    except FoamsiloError as exc:
        (output / COMPARE_MD).unlink(missing_ok=True)
        say(f"no comparison with an analytic law: {exc}")
    say(f"report: {sweep_report(output)}")
