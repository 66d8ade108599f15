"""The grid error of a case's steady rate, from the same scene on two coarser grids.

A grid study (``foamsilo run SCENE --grid-error``, :func:`foamsilo.pipeline.grid_study`)
runs the case and two companions whose cells across are the case's divided
by r and r^2, and records their steady rates in the case's ``grid.json``.
From the three, :func:`foamsilo.post.convergence.grid_convergence` gives
the observed order, the extrapolated rate and the fine-grid GCI (Roache's
index with the safety factor 1.25 of a three-grid study, read as a 95%
band; Celik et al. 2008). The rate's uncertainty then combines, in
quadrature, the time-averaging error (two batch-means standard errors, also
a 95% band) and the GCI: ``U = sqrt((2 SE)^2 + (GCI Q)^2)``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from foamsilo.errors import FoamsiloError
from foamsilo.post.convergence import GridConvergence, grid_convergence
from foamsilo.scene import Scene, format_override

#: The companions' table in the case directory
GRID_JSON = "grid.json"
#: Refinement ratio between the grids of a study (cells across)
GRID_RATIO = 1.5


def coarser_cells(cells_across: int, ratio: float = GRID_RATIO) -> list[int]:
    """Cells across of the two companions of a grid of ``cells_across``, coarsest first.

    Raises
    ------
    FoamsiloError
        The coarsest would have fewer than 4 cells across, or the ratio is
        not above 1.
    """
    if ratio <= 1:
        raise FoamsiloError(f"grid ratio {ratio}: allowed: > 1")
    cells = [round(cells_across / ratio**2), round(cells_across / ratio)]
    if cells[0] < 4 or len({*cells, cells_across}) < 3:
        raise FoamsiloError(
            f"a grid study of {cells_across} cells across needs companions of {cells} "
            f"cells across; allowed: at least 4, all different (give more cells across)"
        )
    return cells


def companion_overrides(scene: Scene, cells: int) -> list[str]:
    """Return the ``--set`` values that put ``scene`` on the companion grid of ``cells``.

    A graded mesh is refined as a whole: its largest cells and its growth per
    cell follow the fine cells (``coarse_cells_across`` scaled, the growth
    rate raised to the refinement ratio, within its allowed range), so that
    the three grids are one family; with the largest cells held, the coarse
    region would not be refined and the GCI would miss its error.
    """
    sets = [format_override("mesh.cells_across", cells)]
    m = scene.mesh
    if m.graded:
        k = scene.cells_across / cells
        sets.append(format_override("mesh.coarse_cells_across",
                                    max(2, round(m.coarse_cells_across / k))))  # fmt: skip
        sets.append(format_override("mesh.growth_rate", min(1.5, m.growth_rate**k)))
    return sets


@dataclass(frozen=True)
class GridError:
    """A case's rate on its own grid and on two coarser ones, and what they give.

    Attributes
    ----------
    cells
        Cells across, coarsest first; the case's own last.
    values
        Steady rate on each grid (None: that run has no steady rate).
    cases
        The companions' case directories (coarsest first).
    convergence
        Order, extrapolation and GCI of the three (None when one is missing).
    reason
        Why there is no convergence, or None.
    """

    cells: list[int]
    values: list[float | None]
    cases: list[str]
    convergence: GridConvergence | None
    reason: str | None = None

    @property
    def relative(self) -> float | None:
        """The relative grid uncertainty of the case's rate (the GCI), or None."""
        return None if self.convergence is None else self.convergence.gci

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        return {
            "cells": self.cells,
            "values": self.values,
            "cases": self.cases,
            "convergence": None if self.convergence is None else self.convergence.as_dict(),
            "reason": self.reason,
        }


def write_grid_file(case: Path, cells: list[int], values: list[float | None],
                    cases: list[Path]) -> Path:  # fmt: skip
    """Record the companions' rates (and the case's own) in ``case/grid.json``."""
    from foamsilo.case import write_whole
    from foamsilo.jsonio import dumps

    path = Path(case) / GRID_JSON
    data = {"cells": cells, "values": values, "cases": [str(c) for c in cases]}
    write_whole(path, dumps(data) + "\n")
    return path


def read_grid_error(case: Path, q: float | None) -> GridError | None:
    """Return the grid error of ``case`` (None without ``grid.json``); ``q``: its rate now.

    The case's own rate is taken from its current reduction, not from the
    file, so a case reduced again keeps its study consistent.
    """
    path = Path(case) / GRID_JSON
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
        cells = [int(n) for n in data["cells"]]
        values = [None if v is None else float(v) for v in data["values"]]
        cases = [str(c) for c in data["cases"]]
    except (ValueError, KeyError, TypeError) as exc:
        raise FoamsiloError(f"{path}: not a grid study's table ({exc})") from exc
    values[-1] = q
    missing = [n for n, v in zip(cells, values, strict=True) if v is None]
    if missing:
        why = "no steady rate on " + ", ".join(f"{n} cells across" for n in missing)
        return GridError(cells, values, cases, None, why)
    conv = grid_convergence(cells, [float(v) for v in values if v is not None])
    return GridError(cells, values, cases, conv)


def combined_uncertainty(q: float, time_error: float, grid: GridError | None) -> dict[str, Any]:
    """Return the 95% band of a steady rate: time averaging and, where known, the grid.

    Returns
    -------
    dict
        ``time`` (2 standard errors), ``grid`` (GCI x Q, or None),
        ``combined`` (their root sum of squares; the time part alone without
        a grid study), ``relative`` (combined over Q) and ``grid_known``.
    """
    t = 2 * time_error if math.isfinite(time_error) else math.nan
    rel = grid.relative if grid is not None else None
    g = None if rel is None else rel * abs(q)
    combined = math.hypot(t, g) if g is not None else t
    return {
        "time": t,
        "grid": g,
        "combined": combined,
        "relative": combined / abs(q) if q else math.nan,
        "grid_known": g is not None,
    }
