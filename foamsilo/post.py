"""Reduce a run to the numbers of the experiments: Q(t), steady Q, mass balance.

Sources are the function-object outputs the case writes every time step
(``postProcessing/orificeFlow`` and ``postProcessing/granularVolume``), merged
across restarts.  Two independent estimates of the discharge rate are made:

* from the granular volume flux through the orifice (``alphaPhi0.granular``,
  the MULES flux actually applied over each step), and
* from the decrease of the granular volume in the silo (a linear fit of V(t)
  over the steady window).

The steady window follows the experiments (Zhou et al. 2019, sec. II.B):
the mean of the instantaneous rate over the stationary regime, after the
start-up transient and before the silo runs low.
"""

from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo import __version__
from foamsilo.analytic.beverloo import (
    ZHOU_PLANAR_Q,
    ZHOU_PLANAR_Q_SPREAD,
    beverloo_2d,
    beverloo_2d_constant,
)
from foamsilo.case import SCENE_FILE, read_metadata, write_whole
from foamsilo.errors import FoamsiloError
from foamsilo.scene import Scene, load_scene_file

DISCHARGE_CSV = "discharge.csv"
DISCHARGE_PNG = "discharge.png"
SUMMARY_JSON = "summary.json"

#: Smoothed Q must stay within this of the plateau for the window to start
STEADY_TOLERANCE = 0.02
#: Largest relative drift of Q over the window still called steady
STEADY_MAX_DRIFT = 0.03
#: Largest excursion of the smoothed Q from its mean still called steady
STEADY_MAX_EXCURSION = 0.05
#: Window ends when the equivalent fill height drops below this many L
LOW_FILL = 0.5


def read_function_object(case: Path, name: str) -> tuple[list[str], np.ndarray]:
    """Read ``postProcessing/<name>/<t0>/*.dat``, merged over restarts.

    A restart from t0 writes a new ``<t0>`` directory; its rows replace the
    earlier ones from t0 on.

    Returns
    -------
    columns, data
        Column names (first is ``Time``) and the rows, sorted by time.
    """
    root = Path(case) / "postProcessing" / name
    if not root.is_dir():
        raise FoamsiloError(f"no function-object output {root} (has the case run?)")
    starts = sorted((p for p in root.iterdir() if p.is_dir()), key=lambda p: float(p.name))
    columns: list[str] = []
    data = np.empty((0, 0))
    for start in starts:
        # a rerun from the same time writes <name>_<time>.dat beside the old
        # file: the newest one is this run's
        files = sorted(start.glob("*.dat"), key=lambda f: f.stat().st_mtime)
        if not files:
            continue
        text = files[-1].read_text()
        lines = text.splitlines()
        if lines and not text.endswith("\n"):
            lines = lines[:-1]  # a run killed mid-line: the last row is cut short
        header = [ln for ln in lines if ln.startswith("#")]
        cols = header[-1].lstrip("#").split("\t") if header else []
        cols = [c.strip() for c in cols if c.strip()]
        rows = [ln.split() for ln in lines if ln.strip() and not ln.startswith("#")]
        if not rows:
            continue
        block = np.array([[float(x) for x in r] for r in rows if len(r) == len(rows[0])])
        columns = cols or columns
        if data.size:
            data = data[data[:, 0] < block[0, 0] - 1e-12]
            data = np.vstack([data, block])
        else:
            data = block
    if not data.size:
        raise FoamsiloError(f"function-object output {root} is empty")
    return columns, data


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
    """

    time: np.ndarray
    delta_t: np.ndarray
    volume_flux: np.ndarray
    volume: np.ndarray
    initial_volume: float
    density: float
    depth: float
    top_flux: np.ndarray | None = None

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
    _, flux = read_function_object(case, "orificeFlow")
    _, vol = read_function_object(case, "granularVolume")
    t, i_f, i_v = np.intersect1d(flux[:, 0], vol[:, 0], return_indices=True)
    if len(t) < 0.9 * min(len(flux), len(vol)):
        raise FoamsiloError(f"{case}: flux and volume outputs are not on the same times")
    dt = np.diff(np.concatenate([[0.0], t]))
    depth = scene.mesh_fraction
    q = _rebin(flux[:, 0], flux[:, 1], t) / depth
    v = vol[i_v, 1] / depth
    top = None
    if (Path(case) / "postProcessing" / "topFlow").is_dir():
        _, tf = read_function_object(case, "topFlow")
        if len(np.intersect1d(tf[:, 0], t)) == len(t):
            top = _rebin(tf[:, 0], tf[:, 1], t) / depth
    v0 = float(v[0] + (q[0] + (top[0] if top is not None else 0.0)) * dt[0])
    return Discharge(t, dt, q, v, v0, scene.material.density, depth, top)


@dataclass
class SteadyState:
    """The stationary discharge regime and its rate.

    Attributes
    ----------
    steady
        A stationary regime was found (long enough, drift below the limit).
    t_start, t_end
        The window [s].
    q, q_std
        Time-weighted mean and standard deviation of Q over the window.
    q_from_volume
        -rho dV/dt fitted over the window (independent estimate).
    drift
        Relative change of Q over the window (linear fit).
    reason
        Why it is not steady, when it is not.
    excursion
        Largest deviation of the smoothed rate from its mean in the window.
    """

    steady: bool
    t_start: float
    t_end: float
    q: float
    q_std: float
    q_from_volume: float
    drift: float
    reason: str = ""
    excursion: float = math.nan


def _smooth(t: np.ndarray, y: np.ndarray, width: float) -> np.ndarray:
    """Average over a moving time window (handles variable steps)."""
    w = np.diff(np.concatenate([[t[0]], t]))
    cy = np.concatenate([[0.0], np.cumsum(y * w)])
    cw = np.concatenate([[0.0], np.cumsum(w)])
    lo = np.searchsorted(t, t - width / 2, side="left")
    hi = np.searchsorted(t, t + width / 2, side="right")
    num = cy[hi] - cy[lo]
    den = cw[hi] - cw[lo]
    return np.where(den > 0, num / np.where(den > 0, den, 1), y)


def find_steady(d: Discharge, scene: Scene) -> SteadyState:
    """Locate the stationary regime of Q(t) and average over it."""
    T = scene.time_scale
    t, q = d.time, d.mass_flow
    area = scene.cross_section_area  # volume / area: the equivalent fill height
    h_eq = d.volume / area
    usable = (t > 0.5 * T) & (h_eq > LOW_FILL * scene.silo.width)
    nan = SteadyState(False, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan)
    if usable.sum() < 20:
        nan.reason = (
            "run too short (or silo emptied): fewer than 20 usable steps after 0.5 sqrt(L/g)"
        )
        return nan
    idx = np.flatnonzero(usable)
    i1 = idx[-1]
    tt, qq = t[: i1 + 1], q[: i1 + 1]
    width = 0.5 * T
    smooth = _smooth(tt, qq, width)
    later = (tt >= 0.5 * (tt[idx[0]] + tt[-1])) & (tt > 0.5 * T)
    q_ref = float(np.median(qq[later]))
    # the window opens when the smoothed rate first comes within the band of
    # the plateau (the end of the start-up transient) and no longer leaves
    # the wider excursion band: an overshooting start-up crosses the plateau
    # before it settles, while a noisy plateau wanders a little (2-5%) and
    # must not push the start back. Only complete smoothing windows are
    # judged for excursions (the last half-width is averaged short).
    dev = np.abs(smooth - q_ref)
    usable_now = tt >= tt[idx[0]]
    near = np.flatnonzero((dev <= STEADY_TOLERANCE * abs(q_ref)) & usable_now)
    i0 = int(near[0]) if near.size else i1
    judged = usable_now & (tt <= tt[-1] - width / 2)
    wild = np.flatnonzero(judged & (dev > STEADY_MAX_EXCURSION * abs(q_ref)))
    if wild.size and near.size:
        later_near = near[near > wild[-1]]
        i0 = int(later_near[0]) if later_near.size else i1
    win = slice(i0, i1 + 1)
    tw, qw, dtw, vw = t[win], q[win], d.delta_t[win], d.volume[win]
    if len(tw) < 20 or tw[-1] - tw[0] < 1.0 * T:
        nan.reason = (
            f"no stationary regime: the rate reached its plateau (within {STEADY_TOLERANCE:.0%})"
            f" only {(tw[-1] - tw[0]) / T if len(tw) else 0:.2f} sqrt(L/g) before the end "
            "(need >= 1)"
        )
        nan.t_start, nan.t_end = float(t[i0]) if i0 < len(t) else math.nan, float(t[i1])
        return nan
    mean = float(np.sum(qw * dtw) / np.sum(dtw))
    std = float(np.sqrt(np.sum((qw - mean) ** 2 * dtw) / np.sum(dtw)))
    slope = np.polyfit(tw, qw, 1)[0]
    drift = float(slope * (tw[-1] - tw[0]) / mean) if mean else math.nan
    # standard error of that drift: the rate's fluctuations are correlated
    # over about one smoothing width, so the window holds ~span/width
    # independent samples, not one per time step
    span = tw[-1] - tw[0]
    n_eff = max(span / width, 2.0)
    drift_se = float(std * math.sqrt(12.0 / n_eff) / abs(mean)) if mean else math.nan
    q_vol = float(-np.polyfit(tw, vw, 1)[0] * d.density)
    # largest excursion of the smoothed rate, where its window is complete
    complete = (tt >= tw[0]) & (tt <= tt[-1] - width / 2)
    band = float(np.max(np.abs(smooth[complete] - mean)) / mean) if complete.any() else 0.0
    reasons = []
    # a drift counts when it is both large and more than the noise explains
    if abs(drift) >= STEADY_MAX_DRIFT and abs(drift) > 2 * drift_se:
        reasons.append(f"Q drifts by {drift:.1%} over the window (noise: {drift_se:.1%})")
    if band >= STEADY_MAX_EXCURSION:
        reasons.append(f"the smoothed rate wanders by {band:.1%}")
    return SteadyState(
        not reasons,
        float(tw[0]),
        float(tw[-1]),
        mean,
        std,
        q_vol,
        drift,
        "; ".join(reasons),
        band,
    )


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


def plot_discharge(d: Discharge, st: SteadyState, scene: Scene, path: Path) -> None:
    """Q/(rho sqrt(g L^3)) against t/sqrt(L/g), with the steady band and references."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scale_name, scale = scene.flow_rate_scale
    planar = scene.representation == "planar"
    T = scene.time_scale
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=120)
    ax.plot(d.time / T, d.mass_flow / scale, lw=1.2, color="C0", label="simulation, orifice flux")
    if st.steady:
        ax.axvspan(st.t_start / T, st.t_end / T, color="C0", alpha=0.08, label="steady window")
        ax.axhline(st.q / scale, color="C0", ls="--", lw=1, label=f"steady Q = {st.q / scale:.4f}")
    if planar:
        ax.axhspan(
            ZHOU_PLANAR_Q - ZHOU_PLANAR_Q_SPREAD,
            ZHOU_PLANAR_Q + ZHOU_PLANAR_Q_SPREAD,
            color="C1",
            alpha=0.15,
            label="Zhou et al. 2019, 0.16 +- 0.01",
        )
        bev = float(beverloo_2d(scene.silo.orifice_width, scene.material.density, scene.gravity))
        ax.axhline(
            bev / scale,
            color="C2",
            ls=":",
            lw=1.5,
            label=f"2D Beverloo, C = {beverloo_2d_constant():.2f}: {bev / scale:.3f}",
        )
    ref = reference_rate(scene)
    if not planar and ref is not None:
        ax.axhline(ref["Q"] / scale, color="C1", ls=":", lw=1.5, label=ref["label"])
    ax.set_xlabel(r"$t/\sqrt{L/g}$")
    ax.set_ylabel(r"$Q/(\rho\sqrt{gL^3})$" if planar else r"$Q/(\rho\sqrt{g}D^{5/2})$")
    ax.set_title(f"{scene.name}: {scene.mesh.cells_across} cells across L")
    ax.set_ylim(0, max(0.25 if planar else 0.1, 1.2 * float(np.max(d.mass_flow / scale))))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    os.replace(tmp, path)


def reference_rate(scene: Scene) -> dict[str, Any] | None:
    """Return the published law a non-planar scene's steady rate is compared with.

    A flat-bottomed cylinder with a centred bottom orifice: Zhou et al. 2019
    eq. 1 with the Table I constants of the cylindrical silo (the phase
    density is the bulk density phi_b rho_p).  None for other shapes.
    """
    s = scene.silo
    if scene.representation == "planar" or s.shape != "cylindrical":
        return None
    if s.orifice_position != "bottom":
        return None
    from foamsilo.analytic.zhou import config
    from foamsilo.compare import zhou_eq1

    c = config("cyl-bottom")
    q = zhou_eq1(scene, s.orifice_width)
    return {"Q": q, "label": f"Zhou et al. 2019 eq. 1, C0 = {c.C0}: {q * 1e3:.2f} g/s"}


def summarize(case: Path, run_info: dict[str, Any] | None = None) -> dict[str, Any]:
    """Reduce a run: write ``discharge.csv``, ``discharge.png``, ``summary.json``.

    Parameters
    ----------
    case
        The case directory.
    run_info
        Extra figures of the run (wall time, steps) to keep in the summary.

    Returns
    -------
    dict
        The summary (as written to ``summary.json``).
    """
    case = Path(case).resolve()
    meta = read_metadata(case)
    scene = load_scene_file(case / SCENE_FILE)
    d = read_discharge(case, scene)
    st = find_steady(d, scene)
    scale_name, scale = scene.flow_rate_scale
    planar = scene.representation == "planar"
    bev = float(beverloo_2d(scene.silo.orifice_width, scene.material.density, scene.gravity))
    steady_star = st.q / scale if st.steady else None
    summary: dict[str, Any] = {
        "foamsilo_version": __version__,
        "case_dir": str(case),
        "scene": scene.name,
        "representation": meta.get("representation"),
        "cells": meta.get("cells"),
        "cells_across": scene.mesh.cells_across,
        "simulated_time_s": float(d.time[-1]),
        "steady": st.steady,
        "steady_reason": st.reason or None,
        "steady_window_s": [st.t_start, st.t_end],
        "Q": st.q if st.steady else None,
        "Q_std": st.q_std if st.steady else None,
        "Q_from_volume": st.q_from_volume if st.steady else None,
        "Q_units": "kg/(m s) per unit depth" if planar else "kg/s",
        "Q_dimensionless": steady_star,
        "Q_std_dimensionless": st.q_std / scale if st.steady else None,
        "Q_from_volume_dimensionless": st.q_from_volume / scale if st.steady else None,
        "flux_vs_volume_rel_diff": (abs(st.q - st.q_from_volume) / st.q if st.steady else None),
        "drift": st.drift if st.steady else None,
        "excursion": st.excursion if st.steady else None,
        "fill_height_end_m": float(d.volume[-1] / scene.cross_section_area),
        "mass_balance_rel_error": d.mass_balance_error,
        "lost_through_top_rel": d.top_loss,
        "flow_rate_scale": {"name": scale_name, "value": scale},
    }
    if planar:
        summary["reference"] = {
            "source": "Zhou et al. 2019, sec. III.B (open top), converged continuum rate",
            "Q_dimensionless": ZHOU_PLANAR_Q,
            "spread": ZHOU_PLANAR_Q_SPREAD,
            "rel_diff": (steady_star - ZHOU_PLANAR_Q) / ZHOU_PLANAR_Q if steady_star else None,
        }
        summary["beverloo_2d"] = {
            "law": "Q = C rho sqrt(g) D^(3/2) (k = 0, continuum)",
            "C": beverloo_2d_constant(),
            "Q_dimensionless": bev / scale,
            "rel_diff": (st.q - bev) / bev if st.steady else None,
        }
    else:
        ref = reference_rate(scene)
        if ref is not None:
            summary["reference"] = {
                "source": ref["label"],
                "Q": ref["Q"],
                "Q_dimensionless": ref["Q"] / scale,
                "rel_diff": (st.q - ref["Q"]) / ref["Q"] if st.steady else None,
            }
    if scene.gas_coupled and st.steady:
        summary["pore_pressure"] = _pore_pressure_summary(case, scene, d, st)
    try:
        from foamsilo.fields import field_summary

        summary["fields"] = field_summary(case)
    except Exception as exc:  # noqa: BLE001 -- field reduction must not lose the rates
        summary["fields"] = {"error": str(exc)}
    if run_info:
        summary["run"] = run_info
    write_discharge_csv(d, scene, case / DISCHARGE_CSV)
    plot_discharge(d, st, scene, case / DISCHARGE_PNG)
    _write_summary(case, summary)
    _compare_and_report(case, summary)
    _write_summary(case, summary)  # now with the comparison
    return summary


def _write_summary(case: Path, summary: dict[str, Any]) -> None:
    write_whole(case / SUMMARY_JSON, json.dumps(summary, indent=2, default=float))


def _compare_and_report(case: Path, summary: dict[str, Any]) -> None:
    """Set the case on its analytic law (when it has one) and write ``report.md``."""
    from foamsilo.compare import COMPARE_MD, compare
    from foamsilo.report import case_report

    try:
        summary["compare"] = {k: v for k, v in compare(case).items() if k != "target"}
    except FoamsiloError as exc:  # no law for this geometry, or no steady rate
        (case / COMPARE_MD).unlink(missing_ok=True)
        summary["compare"] = {"error": str(exc)}
    case_report(case, summary)


__all__ = [
    "Discharge",
    "SteadyState",
    "asdict",
    "find_steady",
    "read_discharge",
    "read_function_object",
    "summarize",
]


# ------------------------------------------------------------- pore pressure


def read_probes(case: Path, name: str, field: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Probe locations, times and values of ``postProcessing/<name>/<t0>/<field>``.

    Returns
    -------
    locations (n, 3), times (m,), values (m, n), merged over restarts.
    """
    root = Path(case) / "postProcessing" / name
    if not root.is_dir():
        raise FoamsiloError(f"no probe output {root}")
    locs: list[list[float]] = []
    blocks: list[np.ndarray] = []
    for start in sorted((p for p in root.iterdir() if p.is_dir()), key=lambda p: float(p.name)):
        files = sorted(start.glob(f"{field}*"), key=lambda f: f.stat().st_mtime)
        if not files:
            continue
        text = files[-1].read_text().splitlines()
        locs = [
            [float(v) for v in ln.split("(")[1].split(")")[0].split()]
            for ln in text
            if ln.startswith("# Probe ") and "(" in ln
        ] or locs
        rows = [ln.split() for ln in text if ln.strip() and not ln.startswith("#")]
        if not rows:
            continue
        block = np.array([[float(x) for x in r] for r in rows if len(r) == len(rows[0])])
        if blocks and len(block):
            blocks = [b[b[:, 0] < block[0, 0] - 1e-12] for b in blocks]
        blocks.append(block)
    if not blocks:
        raise FoamsiloError(f"probe output {root} is empty")
    data = np.vstack(blocks)
    return np.array(locs), data[:, 0], data[:, 1:]


def _vector_series(case: Path, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Read the times and (n, 3) vectors of a volFieldValue of a vector field."""
    root = Path(case) / "postProcessing" / name
    starts = sorted((p for p in root.iterdir() if p.is_dir()), key=lambda p: float(p.name))
    ts: list[float] = []
    vs: list[list[float]] = []
    for start in starts:
        files = sorted(start.glob("*.dat"), key=lambda f: f.stat().st_mtime)
        if not files:
            continue
        for ln in files[-1].read_text().splitlines():
            if ln.startswith("#") or not ln.strip():
                continue
            t, rest = ln.split(None, 1)
            vec = [float(v) for v in rest.replace("(", " ").replace(")", " ").split()[:3]]
            if ts and float(t) <= ts[-1]:  # a restart: its rows replace the later ones
                keep = [i for i, x in enumerate(ts) if x < float(t)]
                ts, vs = [ts[i] for i in keep], [vs[i] for i in keep]
            ts.append(float(t))
            vs.append(vec)
    return np.array(ts), np.array(vs)


@dataclass
class PorePressure:
    """Mean pore pressure of the stationary regime (Zhou et al. 2019, Figs 5b, 6b).

    The lines of the paper's Fig. 5b: near the orifice, eq. 20 at the orifice,
    slope eta_f/(kappa_v S_o)(Q_air - Q/rho); far from it, the slope with the
    silo section S_b in place of S_o and an intercept fitted by least squares.
    They cross at ``slope_change_height`` (the paper: ~0.42 D).

    Attributes
    ----------
    y, pressure
        Heights of the taps on the axis [m] and their mean pore pressure over
        the steady window while inside the granular bed [Pa].
    gradient_near, gradient_far
        The two slopes [Pa/m] (theory, from the relative gas flux).
    far_intercept
        Intercept of the far line, fitted [Pa].
    slope_change_height
        Where the two lines cross [m].
    gradient_far_fit
        Free least-squares slope of the far taps [Pa/m] (a measurement).
    gradient_orifice_measured
        Mean gradient over the orifice from the measured gas flux [Pa/m].
    zone_gradient
        Mean dp_f/dz over the zone of radius D/2 above the orifice [Pa/m].
    gas_flux
        Mean relative gas flux out through the orifice [m^3/s, per unit
        depth for planar]; negative: air drawn in.
    taps
        The scene's taps (``gas.taps``): height [m] and mean pore pressure
        [Pa] (None where the tap was above the grains for most of the window).
    """

    y: np.ndarray
    pressure: np.ndarray
    gradient_near: float
    gradient_far: float
    far_intercept: float
    slope_change_height: float
    gradient_far_fit: float
    gradient_orifice_measured: float
    zone_gradient: float
    gas_flux: float
    taps: list[dict[str, float | None]]

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        d = dict(self.__dict__)
        d["y"] = self.y.tolist()
        d["pressure"] = self.pressure.tolist()
        return d


def pore_pressure(case: Path, scene: Scene, d: Discharge, st: SteadyState) -> PorePressure:
    """Reduce the pore-pressure outputs over the steady window."""
    L, D = scene.silo.width, scene.silo.orifice_width
    planar = scene.representation == "planar"
    s_o = D if planar else math.pi * D**2 / 4
    s_b = L if planar else math.pi * L**2 / 4
    resistance = scene.air.viscosity / scene.permeability
    locs, t, p = read_probes(case, "porePressureAxis", "pf")
    y = locs[:, 1]
    win = (t >= st.t_start) & (t <= st.t_end)
    # equivalent fill height at each probe time, from the granular volume
    h = np.interp(t, d.time, d.volume / (L if planar else s_b))
    margin = 0.25 * L  # keep clear of the crater at the free surface
    inside = win[:, None] & (y[None, :] < (h[:, None] - margin))
    counts = inside.sum(axis=0)
    ok = counts > 0.2 * max(1, win.sum())
    mean = np.where(ok, np.sum(np.where(inside, p, 0.0), axis=0) / np.maximum(counts, 1), np.nan)
    ym, pm = y[ok], mean[ok]
    taps: list[dict[str, float | None]] = []
    for tap in scene.gas.taps:
        k = int(np.argmin(np.abs(y - tap)))
        taps.append({"y": float(y[k]), "pressure": float(mean[k]) if ok[k] else None})
    # relative gas flux through the orifice, from the mass balance
    q_air = scene.q_air_per_depth if planar else scene.q_air
    relative = q_air - st.q / scene.material.density
    g_near = resistance * relative / s_o
    g_far = resistance * relative / s_b
    far = ym > 1.5 * D
    c_far = float(np.mean(pm[far] - g_far * ym[far])) if far.any() else math.nan
    y_star = c_far / (g_near - g_far) if g_near != g_far else math.nan
    g_far_fit = float(np.polyfit(ym[far], pm[far], 1)[0]) if far.sum() >= 2 else math.nan
    tz, gz = _vector_series(case, "orificeZoneGradient")
    wz = (tz >= st.t_start) & (tz <= st.t_end)
    zone = float(np.mean(gz[wz, 1])) if wz.any() else math.nan
    _, gas = read_function_object(case, "orificeGasFlow")
    wg = (gas[:, 0] >= st.t_start) & (gas[:, 0] <= st.t_end)
    flux = float(np.mean(gas[wg, 1]) / d.depth) if wg.any() else math.nan
    return PorePressure(
        ym, pm, g_near, g_far, c_far, y_star, g_far_fit, resistance * flux / s_o, zone, flux, taps
    )


def _pore_pressure_summary(
    case: Path, scene: Scene, d: Discharge, st: SteadyState
) -> dict[str, Any]:
    """Pore-pressure figures of Zhou et al. Figs 5b and 6b, dimensional and scaled."""
    pp = pore_pressure(case, scene, d, st)
    plot_pore_pressure(pp, scene, Path(case) / PORE_PRESSURE_PNG)
    rho_g = scene.material.density * scene.gravity
    L, D = scene.silo.width, scene.silo.orifice_width
    q_air = scene.q_air_per_depth if scene.representation == "planar" else scene.q_air
    relative = q_air - st.q / scene.material.density  # Q_air - Q/rho
    return {
        **pp.as_dict(),
        "pressure_scaled": (pp.pressure / (rho_g * L)).tolist(),
        "y_over_L": (pp.y / L).tolist(),
        "gradient_near_scaled": pp.gradient_near / rho_g,
        "gradient_far_scaled": pp.gradient_far / rho_g,
        "far_intercept_scaled": pp.far_intercept / (rho_g * L),
        "gradient_far_fit_scaled": pp.gradient_far_fit / rho_g,
        "gradient_orifice_measured_scaled": pp.gradient_orifice_measured / rho_g,
        "gradient_ratio": pp.gradient_near / pp.gradient_far,
        "slope_change_over_D": pp.slope_change_height / D,
        "zone_gradient_scaled": pp.zone_gradient / rho_g,
        "relative_gas_flux": relative,
        "relative_gas_flux_measured": pp.gas_flux,
        # Fig. 6b abscissa: eta_f/(rho g kappa_v S_o) (Q_air - Q/rho) = near slope / rho g
        "fig6b_abscissa": pp.gradient_near / rho_g,
    }


PORE_PRESSURE_PNG = "pore_pressure.png"


def plot_pore_pressure(pp: PorePressure, scene: Scene, path: Path) -> None:
    """Mean pore pressure along the axis with the two lines of Zhou Fig. 5b (PNG)."""
    from foamsilo.plots import finish, subplots

    D = scene.silo.orifice_width
    fig, ax = subplots()
    ax.plot(pp.y / D, pp.pressure, "k.", ms=4, label="axis probes (mean over the steady window)")
    tap_y = [t["y"] for t in pp.taps if t["pressure"] is not None]
    tap_p = [t["pressure"] for t in pp.taps if t["pressure"] is not None]
    if tap_y:
        ax.plot(np.array(tap_y) / D, tap_p, "C3s", ms=7, mfc="none", label="taps (gas.taps)")
    yy = np.linspace(0, float(pp.y.max()) if pp.y.size else D, 100)
    ax.plot(yy / D, pp.gradient_near * yy, "C0--", lw=1, label="near orifice: eq. 20 slope")
    ax.plot(yy / D, pp.gradient_far * yy + pp.far_intercept, "C1-", lw=1,
            label="far: Darcy slope over the silo section")  # fmt: skip
    lo = float(np.nanmin(pp.pressure)) if pp.pressure.size else 0.0
    hi = float(np.nanmax(pp.pressure)) if pp.pressure.size else 1.0
    pad = 0.1 * max(hi - lo, 1e-9)
    ax.set_ylim(lo - pad, hi + pad)
    ax.set_xlabel("height above the orifice y/D")
    ax.set_ylabel("pore pressure p_f [Pa]")
    ax.set_title(f"{scene.name}: pore pressure on the axis ({scene.gas.mode})", fontsize=9)
    finish(fig, ax, path, legend_size=7)
