"""Cases of a study as data: read from TOML, run through the pipeline, one row each.

A study (the validation suite, a reproduction, a benchmark) lists its cases
in a TOML file shipped beside it (:func:`study_table`); :func:`run_rows`
runs them through :func:`foamsilo.pipeline.run_many` (a fresh case each,
under the CPU budget) and turns each :class:`~foamsilo.pipeline.Outcome`
into a row: the outcome in words, Q, the cost, and the time-step history.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.errors import SceneError
from foamsilo.pipeline import Backend, Budget, CaseSpec, LocalBackend, Outcome
from foamsilo.post.steady import STEP_SWING_WARNING
from foamsilo.process import cpu_model
from foamsilo.run import STEP_TABLE
from foamsilo.scene import format_override, load_preset, read_toml

#: Where a study's cases run: cases at a time on this machine, or a backend
#: (:class:`foamsilo.slurm.SlurmBackend`)
Jobs = int | Backend


def backend_of(jobs: Jobs) -> Backend:
    """Return the backend of ``jobs``: ``jobs`` cases at a time here, or the backend given."""
    return LocalBackend(Budget(cores=jobs)) if isinstance(jobs, int) else jobs


def jobs_words(jobs: Jobs) -> str:
    """Return how a study's cases ran, in words, for its report."""
    inner: Any = getattr(jobs, "inner", jobs)  # the backend under a progress display
    if isinstance(inner, LocalBackend):
        inner = inner.budget.cases_at_once
    return f"{inner} cases at a time" if isinstance(inner, int) else f"on {type(inner).__name__}"


def study_table(name: str) -> dict[str, Any]:
    """Return the TOML table of a study shipped in ``foamsilo/studies/<name>.toml``."""
    path = Path(str(resources.files("foamsilo.studies") / f"{name}.toml"))
    return read_toml(path, f"studies/{name}.toml")


def overrides(table: dict[str, Any] | None) -> list[str]:
    """``{"run.end_time": 1.0}`` -> ``["run.end_time=1.0"]``."""
    return [format_override(k, v) for k, v in (table or {}).items()]


def pick(entry: dict[str, Any], key: str, quick: bool) -> Any:
    """``entry["quick_<key>"]`` in the quick suite when it is given, else ``entry[key]``."""
    return entry.get(f"quick_{key}", entry.get(key)) if quick else entry.get(key)


@dataclass
class StudyCase:
    """One case of a study: a label, a preset and its overrides.

    ``wall_limit`` (s) is the case's own wall-time limit, for a case the
    study's data says needs more than the study's per-case limit; the larger
    of the two applies.
    """

    label: str
    preset: str
    sets: list[str] = field(default_factory=list)
    wall_limit: float | None = None

    def spec(self, case_dir: Path, limit: float | None) -> CaseSpec:
        """Return the pipeline's spec: written afresh (a study never reuses an old case)."""
        load_preset(self.preset, self.sets)  # bad study data fails before anything runs
        if limit is not None and self.wall_limit is not None:
            limit = max(limit, self.wall_limit)
        return CaseSpec(
            case_dir=case_dir,
            scene=self.preset,
            overrides=tuple(self.sets),
            overwrite=True,
            max_wall_seconds=limit,
            label=self.label,
        )


def wall_limits(table: dict[str, Any], where: str, names: list[str]) -> dict[str, float]:
    """Return a study table's ``wall_limits`` (case name -> s), checked against ``names``.

    Raises
    ------
    SceneError
        A name that is not one of ``names``, or a limit that is not a number > 0.
    """
    out: dict[str, float] = {}
    for name, value in (table.get("wall_limits") or {}).items():
        field_name = f"{where}.wall_limits.{name}"
        if name not in names:
            raise SceneError(field_name, f"unknown case; allowed: {', '.join(names)}")
        if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
            raise SceneError(field_name, f"got {value!r}; allowed: wall seconds > 0")
        out[name] = float(value)
    return out


def _outcome_words(o: Outcome) -> tuple[str, str]:
    if o.ok and o.summary is not None:
        if not o.summary.get("steady"):
            return "not steady", o.summary.get("steady_reason") or ""
        # a rate that swings from step to step is a numerical oscillation, not a
        # steady discharge: its mean is no result (docs/post.md)
        swing = o.summary.get("Q_step_swing")
        if swing is not None and swing > STEP_SWING_WARNING:
            return "oscillating", (
                f"the rate swings by {swing:.1%} from one step to the next "
                f"(more than {STEP_SWING_WARNING:.0%})"
            )
        return "steady", ""
    err = o.error or {}
    kind = {
        "DivergenceError": "stopped: diverged",
        "RunTimeLimitError": "stopped: wall-time limit",
        "FoamError": "stopped: solver error",
    }.get(o.status, f"stopped: {o.status}")
    detail = err.get("output", "")[-600:] if o.status == "FoamError" else err.get("message", "")
    return kind, detail


def step_history(case_dir: Path) -> dict[str, Any]:
    """Return the steps, time reached, and time-step range and history (thinned) of a run."""
    table = Path(case_dir) / STEP_TABLE
    if not table.exists():
        return {}
    with open(table, newline="") as fh:
        rows = list(csv.DictReader(fh))
    ok = [r for r in rows if r["delta_t"] not in ("", "nan")]
    dts = [float(r["delta_t"]) for r in ok]
    pick_rows = ok[:: max(1, len(ok) // 300)]
    return {
        "steps": len(rows),
        "t_reached": float(rows[-1]["time"]) if rows else 0.0,
        "dt_min": min(dts) if dts else None,
        "dt_max": max(dts) if dts else None,
        "dt_median": float(np.median(dts)) if dts else None,
        "dt_history": [[float(r["time"]), float(r["delta_t"])] for r in pick_rows],
    }


def outcome_row(case: StudyCase, o: Outcome) -> dict[str, Any]:
    """One row of a study's table."""
    word, detail = _outcome_words(o)
    row: dict[str, Any] = {
        "label": case.label,
        "preset": case.preset,
        "sets": case.sets,
        "case_dir": str(o.spec.case_dir),
        "outcome": word,
        "detail": detail,
        "wall_s": o.wall_s,
    }
    row.update(summary_fields(o.summary or {}))
    row.update(record_fields(o.spec.case_dir))
    row.update(step_history(o.spec.case_dir))
    scene = load_preset(case.preset, case.sets)
    row["end_time"] = scene.run.end_time
    row["thickness"] = scene.silo.thickness
    return row


def summary_fields(s: dict[str, Any]) -> dict[str, Any]:
    """Return the figures of a row taken from a case's summary (``summary.json``)."""
    run = s.get("run") or {}
    return dict(
        Q=s.get("Q"),
        Q_std=s.get("Q_std"),
        Q_dimensionless=s.get("Q_dimensionless"),
        Q_from_volume=s.get("Q_from_volume"),
        flux_vs_volume_rel_diff=s.get("flux_vs_volume_rel_diff"),
        cells=s.get("cells"),
        cpu_s=run.get("cpu_seconds"),
        mass_balance=s.get("mass_balance_rel_error"),
        lost_through_top=s.get("lost_through_top_rel"),
        fill_height_end_m=s.get("fill_height_end_m"),
        simulated_time_s=s.get("simulated_time_s"),
        Q_time_error=s.get("Q_time_error"),
        Q_step_swing=s.get("Q_step_swing"),
        # the mean pore-pressure gradient over the zone above the orifice (gas scenes)
        zone_gradient_scaled=(s.get("pore_pressure") or {}).get("zone_gradient_scaled"),
    )


def record_fields(case_dir: Path) -> dict[str, Any]:
    """Return what a row takes from ``run.json`` (also a stopped run's).

    The runner's recoveries and the solver's steps taken again (at half the step,
    ``run.max_step_retakes``, or at half the divergence share,
    ``numerics.outer_growth_limit``), each as a count; and the processor the
    solver ran on (``cpu``), where the record names it.
    """
    from foamsilo.case import read_run_record

    record = read_run_record(Path(case_dir))
    if not record:
        return {}
    keys = ("recoveries", "step_retakes", "share_retakes")
    out: dict[str, Any] = {k: len(record.get(k) or []) for k in keys}
    if record.get("cpu"):
        # the machine its CPU time was measured on
        out["cpu"] = record["cpu"]
    return out


def run_rows(
    cases: list[StudyCase],
    work: Path,
    jobs: Jobs,
    limit: float | None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
    dirs: list[str] | None = None,
) -> list[dict[str, Any]]:
    """Run the cases (``jobs`` at a time, or on a backend); a row each, in order.

    Each case runs in ``work/NN``, NN its place in ``cases``, or in ``work/D``
    with ``dirs`` (a part of a study keeps its cases' places in the whole, so
    that a rerun of some rows in the same work directory overwrites no other).
    """
    names = dirs if dirs is not None else [f"{i:02d}" for i in range(len(cases))]
    specs = [c.spec(Path(work) / d, limit) for d, c in zip(names, cases, strict=True)]
    Path(work).mkdir(parents=True, exist_ok=True)  # made once, not by racing workers
    by_dir = {s.case_dir: c for s, c in zip(specs, cases, strict=True)}

    def done(o: Outcome) -> None:
        if on_row is not None:
            on_row(outcome_row(by_dir[o.spec.case_dir], o))

    outcomes = backend_of(jobs).run(specs, on_done=done)
    return [outcome_row(c, o) for c, o in zip(cases, outcomes, strict=True)]


def machine_info() -> dict[str, Any]:
    """Where a study ran (read from the machine, written into its report)."""
    import os
    import platform

    from foamsilo import __version__

    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "foamsilo": __version__,
        "date": time.strftime("%Y-%m-%d"),
    }


def git_commit() -> str | None:
    """Return the commit the studies ran at (``-dirty``: uncommitted changes to the code).

    A study reads it before its runs: a commit made while they run is not the
    code they ran.
    """
    import os

    from foamsilo.process import run_command

    def git(*args: str) -> str:
        res = run_command(["git", *args], env=dict(os.environ), cwd=Path(__file__).parent,
                          timeout=10)  # fmt: skip
        return res.output.strip() if res.returncode == 0 else ""

    try:
        commit = git("rev-parse", "--short", "HEAD")
        # the code only: a study writing its report into docs/ is no change of the code
        dirty = git("status", "--porcelain", "--untracked-files=no", "--",
                    *(f":(top){d}" for d in ("foamsilo", "templates", "solver_src")))  # fmt: skip
    except OSError:  # no git
        return None
    return (commit + ("-dirty" if dirty else "")) or None


def fmt(v: Any, spec: str) -> str:
    """Return a table cell: ``-`` for missing or non-finite values."""
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)
