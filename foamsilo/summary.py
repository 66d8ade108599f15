"""The summary of a run: the reduction, its references, the comparison, the run record.

:class:`RunSummary` is what the pipeline hands to the report and to the
command line; :meth:`RunSummary.as_json` is ``summary.json`` (written by
:func:`write_summary`, strict JSON).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from foamsilo.case import write_whole
from foamsilo.compare import Reference, reference_sections
from foamsilo.jsonio import dumps
from foamsilo.post import Reduction

SUMMARY_JSON = "summary.json"


@dataclass
class RunSummary:
    """Everything known about one run, typed.

    Attributes
    ----------
    reduction
        The run reduced (:func:`foamsilo.post.reduce_case`).
    references
        The rates that apply to the scene (:func:`foamsilo.compare.references`).
    comparison
        The case on its analytic law (:func:`foamsilo.compare.compare_runs`),
        or ``{"error": ...}`` when it has none.
    run
        The record of the last solver run (``run.json``), None if it never
        ran through foamsilo.
    """

    reduction: Reduction
    references: list[Reference] = field(default_factory=list)
    comparison: dict[str, Any] | None = None
    run: dict[str, Any] | None = None

    @property
    def case(self) -> Path:
        """The case directory."""
        return self.reduction.case

    @property
    def steady(self) -> bool:
        """Whether a stationary regime was found."""
        return self.reduction.steady.steady

    @property
    def q(self) -> float | None:
        """The steady rate, or None."""
        return self.reduction.steady.q if self.steady else None

    def as_json(self) -> dict[str, Any]:
        """Return the summary as ``summary.json`` holds it."""
        out = self.reduction.as_dict()
        out.update(reference_sections(self.reduction.scene, self.q))
        if self.run is not None:
            out["run"] = self.run
        if self.comparison is not None:
            out["compare"] = {k: v for k, v in self.comparison.items() if k != "target"}
        return out


def write_summary(summary: RunSummary) -> Path:
    """Write ``summary.json`` into the case (whole or not at all)."""
    path = summary.case / SUMMARY_JSON
    write_whole(path, dumps(summary.as_json()) + "\n")
    return path
