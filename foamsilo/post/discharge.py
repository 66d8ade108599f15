"""Q(t) and V(t) of a run, from the orifice-flux and granular-volume function objects.

Two independent estimates of the discharge rate come from them: the granular
volume flux through the orifice (``alphaPhi0.granular``, the MULES flux
actually applied over each step), and the decrease of the granular volume in
the silo. Both are per unit depth for a planar scene.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from foamsilo.errors import FoamsiloError
from foamsilo.post.series import read_function_object
from foamsilo.scene import Scene

#: Q(t) table written into the case
DISCHARGE_CSV = "discharge.csv"


@dataclass
class Discharge:
    """Time series of one run (per unit depth for a planar scene).

    Attributes
    ----------
    time
        Simulated time at the end of each step [s].
    delta_t
        Step lengths [s].
    volume_flux
        Granular volume flux out through the orifice over each step
        [m^3/s, or m^2/s per unit depth for planar].
    volume
        Granular volume in the domain [m^3, or m^2].
    initial_volume
        Volume before the first step.
    density
        Grain density [kg/m^3] (Q = density * volume_flux).
    depth
        Depth the planar fluxes were divided by [m] (1 for 3D).
    top_flux
        Granular volume flux out through the open top (None: not recorded).
    notes
        What was dropped reading the output (see :class:`~foamsilo.post.series.Series`).
    """

    time: np.ndarray
    delta_t: np.ndarray
    volume_flux: np.ndarray
    volume: np.ndarray
    initial_volume: float
    density: float
    depth: float
    top_flux: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def mass_flow(self) -> np.ndarray:
        """Q(t) [kg/s, or kg/(m s) per unit depth]."""
        return self.density * self.volume_flux

    @property
    def top_loss(self) -> float:
        """Granular volume that left through the open top, over V0."""
        if self.top_flux is None:
            return 0.0
        return float(np.sum(self.top_flux * self.delta_t) / self.initial_volume)

    @property
    def mass_balance_error(self) -> float:
        """Maximum of |V(t) + outflow(0..t) - V0| / V0 (orifice and top) over the run."""
        flux = self.volume_flux + (self.top_flux if self.top_flux is not None else 0.0)
        out = np.cumsum(flux * self.delta_t)
        return float(np.max(np.abs(self.volume + out - self.initial_volume)) / self.initial_volume)


def _rebin(t_src: np.ndarray, rate: np.ndarray, t_dst: np.ndarray) -> np.ndarray:
    """Re-bin a per-step rate onto the steps ending at ``t_dst`` (a subset of ``t_src``).

    The integral over every kept step is preserved: a step missing from
    ``t_dst`` has its outflow added to the next kept one.
    """
    dt = np.diff(np.concatenate([[0.0], t_src]))
    cum = np.concatenate([[0.0], np.cumsum(rate * dt)])
    idx = np.searchsorted(t_src, t_dst, side="right")  # t_src[idx - 1] == t_dst
    c = cum[idx]
    return np.diff(np.concatenate([[0.0], c])) / np.diff(np.concatenate([[0.0], t_dst]))


def read_discharge(case: Path, scene: Scene) -> Discharge:
    """Q(t) and V(t) of a case from its function-object output.

    The flux and volume series are kept on their common times: a run killed
    between the two function objects' writes leaves one row more in one of
    them, and a restart goes on from the last complete time. The flux of a
    step present only in the flux output is added to the next common step,
    so the mass balance stays exact.
    """
    flux_s = read_function_object(case, "orificeFlow")
    vol_s = read_function_object(case, "granularVolume")
    flux, vol = flux_s.data, vol_s.data
    t, i_f, i_v = np.intersect1d(flux[:, 0], vol[:, 0], return_indices=True)
    if len(t) < 0.9 * min(len(flux), len(vol)):
        raise FoamsiloError(f"{case}: flux and volume outputs are not on the same times")
    dt = np.diff(np.concatenate([[0.0], t]))
    depth = scene.mesh_fraction
    q = _rebin(flux[:, 0], flux[:, 1], t) / depth
    v = vol[i_v, 1] / depth
    top = None
    if (Path(case) / "postProcessing" / "topFlow").is_dir():
        tf = read_function_object(case, "topFlow").data
        if len(np.intersect1d(tf[:, 0], t)) == len(t):
            top = _rebin(tf[:, 0], tf[:, 1], t) / depth
    v0 = float(v[0] + (q[0] + (top[0] if top is not None else 0.0)) * dt[0])
    d = Discharge(t, dt, q, v, v0, scene.material.density, depth, top)
    d.notes = flux_s.notes + vol_s.notes
    return d


def write_discharge_csv(d: Discharge, scene: Scene, path: Path) -> None:
    """Q(t) table: time, dimensionless time, Q, Q dimensionless, volume, fill height."""
    _, scale = scene.flow_rate_scale
    planar = scene.representation == "planar"
    tmp = path.with_suffix(".csv.tmp")
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(
            [
                "t_s",
                "t_over_sqrt_L_g",
                "Q_kg_per_m_s" if planar else "Q_kg_per_s",
                "Q_over_rho_sqrt_gL3" if planar else "Q_over_rho_sqrt_g_D5_2",
                "granular_volume_m2" if planar else "granular_volume_m3",
                "fill_height_m",
            ]
        )
        for i in range(len(d.time)):
            w.writerow(
                [
                    f"{d.time[i]:.9g}",
                    f"{d.time[i] / scene.time_scale:.6g}",
                    f"{d.mass_flow[i]:.9g}",
                    f"{d.mass_flow[i] / scale:.6g}",
                    f"{d.volume[i]:.9g}",
                    f"{d.volume[i] / scene.cross_section_area:.6g}",
                ]
            )
    os.replace(tmp, path)
