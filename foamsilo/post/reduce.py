"""Reduce a run to the numbers of the experiments: Q(t), steady Q, mass balance, fields.

:func:`reduce_case` reads what a finished (or stopped) run left in its case
and returns a typed :class:`Reduction`; it writes the tables and pictures of
the run itself (``discharge.csv``, ``pore_pressure.png``, the field
pictures). Setting the result against the analytic laws and writing the
report are done above this stage (:mod:`foamsilo.compare`,
:mod:`foamsilo.report`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from foamsilo import __version__
from foamsilo.case import SCENE_FILE, read_metadata, time_directories
from foamsilo.errors import FoamsiloError
from foamsilo.post.discharge import DISCHARGE_CSV, Discharge, read_discharge, write_discharge_csv
from foamsilo.post.fields import FieldSummary, field_summary
from foamsilo.post.grid import GridError, combined_uncertainty, read_grid_error
from foamsilo.post.pore_pressure import (
    PORE_PRESSURE_PNG,
    PorePressure,
    plot_pore_pressure,
    pore_pressure,
    pore_pressure_scaled,
)
from foamsilo.post.steady import STEP_SWING_WARNING, SteadyState, find_steady
from foamsilo.scene import Scene, load_scene_file


@dataclass
class Reduction:
    """A run reduced: its time series, its steady regime and what the fields show.

    Attributes
    ----------
    case
        The case directory.
    scene
        The scene it ran.
    cells
        Cells of its mesh.
    discharge
        Q(t) and V(t).
    steady
        The stationary regime and its rate.
    pore_pressure
        The pore-pressure reduction (gas-coupled scenes with a steady regime).
    fields
        The field reduction, or None with ``fields_error`` saying why.
    grid
        The rate on two coarser grids and the grid error it gives (after a
        grid study, :mod:`foamsilo.post.grid`), or None.
    warnings
        What makes the numbers less than whole (output shorter than the run,
        rows dropped); shown in the summary and the report.
    """

    case: Path
    scene: Scene
    cells: int | None
    discharge: Discharge
    steady: SteadyState
    pore_pressure: PorePressure | None = None
    fields: FieldSummary | None = None
    fields_error: str | None = None
    grid: GridError | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def uncertainty(self) -> dict[str, Any] | None:
        """The steady rate's 95% band (time averaging, and the grid where studied), or None."""
        st = self.steady
        if not st.steady:
            return None
        return combined_uncertainty(st.q, st.q_error, self.grid)

    @property
    def flow_rate_scale(self) -> tuple[str, float]:
        """Name and value of the scale Q is made dimensionless with."""
        return self.scene.flow_rate_scale

    def as_dict(self) -> dict[str, Any]:
        """Return the reduction's part of ``summary.json``."""
        sc, st, d = self.scene, self.steady, self.discharge
        name, scale = self.flow_rate_scale
        planar = sc.representation == "planar"
        ok = st.steady

        def finite(x: float) -> float | None:
            return x if ok and math.isfinite(x) else None

        out: dict[str, Any] = {
            "foamsilo_version": __version__,
            "case_dir": str(self.case),
            "scene": sc.name,
            "representation": sc.representation,
            "cells": self.cells,
            "cells_across": sc.cells_across,
            "cells_across_orifice": round(sc.silo.orifice_width / sc.cell_size),
            "graded": sc.mesh.graded,
            "simulated_time_s": float(d.time[-1]),
            "steady": ok,
            "steady_reason": st.reason or None,
            "steady_window_s": [
                st.t_start if math.isfinite(st.t_start) else None,
                st.t_end if math.isfinite(st.t_end) else None,
            ],
            "Q": finite(st.q),
            "Q_std": finite(st.q_std),
            # the error of the time average (batch means); the grid error, after a
            # grid study, is combined with it in Q_uncertainty
            "Q_time_error": finite(st.q_error),
            "Q_time_error_batch_span": finite(st.batch_span),
            "Q_from_volume": finite(st.q_from_volume),
            "Q_units": "kg/(m s) per unit depth" if planar else "kg/s",
            "Q_dimensionless": finite(st.q / scale),
            "Q_std_dimensionless": finite(st.q_std / scale),
            "Q_time_error_dimensionless": finite(st.q_error / scale),
            "Q_from_volume_dimensionless": finite(st.q_from_volume / scale),
            "flux_vs_volume_rel_diff": finite(abs(st.q - st.q_from_volume) / st.q)
            if ok and st.q
            else None,
            "drift": finite(st.drift),
            "excursion": finite(st.excursion),
            "Q_step_swing": finite(st.step_swing),
            "fill_height_end_m": float(d.volume[-1] / sc.cross_section_area),
            "mass_balance_rel_error": d.mass_balance_error,
            "lost_through_top_rel": d.top_loss,
            "flow_rate_scale": {"name": name, "value": scale},
            "warnings": list(self.warnings),
        }
        band = self.uncertainty
        if band is not None:
            out["Q_uncertainty"] = {k: finite(v) if isinstance(v, float) else v
                                    for k, v in band.items()}  # fmt: skip
        if self.grid is not None:
            out["grid"] = self.grid.as_dict()
        if self.pore_pressure is not None:
            out["pore_pressure"] = pore_pressure_scaled(self.pore_pressure, sc, st)
        out["fields"] = self.fields.as_dict() if self.fields else {"error": self.fields_error}
        return out


def _coverage_warnings(case: Path, d: Discharge) -> list[str]:
    """Flag output that stops short of the run (a cut table)."""
    out = list(d.notes)
    times = [float(t) for t in time_directories(case)]
    if times:
        reached = times[-1]
        last = float(d.time[-1])
        # the tables get a row every step, so they reach the latest written time
        if last < reached * (1 - 1e-6) - 1e-12:
            out.append(
                f"the orifice-flux and volume output ends at t = {last:.6g} s but the case has "
                f"fields up to t = {reached:.6g} s (a truncated or lost postProcessing table): "
                f"the rates are from the first {last:.6g} s only"
            )
    return out


def reduce_case(case: Path) -> Reduction:
    """Reduce a run: Q(t), the steady regime, pore pressure and fields.

    Writes ``discharge.csv``, and (where they apply) ``pore_pressure.png``
    and the field tables and pictures, into the case.

    Raises
    ------
    FoamsiloError
        The case has no output to reduce.
    DamagedOutputError
        Its output is damaged (garbage, NaN).
    """
    case = Path(case).resolve()
    meta = read_metadata(case)
    scene = load_scene_file(case / SCENE_FILE)
    d = read_discharge(case, scene)
    st = find_steady(d, scene)
    red = Reduction(case, scene, meta.get("cells"), d, st, warnings=_coverage_warnings(case, d))
    red.grid = read_grid_error(case, st.q if st.steady else None)
    if st.steady and st.step_swing > STEP_SWING_WARNING:
        red.warnings.append(
            f"the steady rate swings by {st.step_swing:.1%} from one step to the next (more "
            f"than {STEP_SWING_WARNING:.0%}): a numerical oscillation, and its mean may be off "
            "by more than that"
            + (
                "; with the stress lagged, a tall column's pressure swings at small steps: "
                "numerics.stress_pressure_coupling = 'implicit' (docs/solver.md)"
                if scene.stress_pressure_coupling == "lagged"
                else ""
            )
        )
    if scene.gas_coupled and st.steady:
        red.pore_pressure = pore_pressure(case, scene, d, st)
        plot_pore_pressure(red.pore_pressure, scene, case / PORE_PRESSURE_PNG)
    try:
        red.fields = field_summary(case)
    except (FoamsiloError, ValueError, KeyError, OSError) as exc:
        # field reduction must not lose the rates: the reason is reported
        red.fields_error = str(exc)
    write_discharge_csv(d, scene, case / DISCHARGE_CSV)
    return red
