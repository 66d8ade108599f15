"""The stationary discharge regime of Q(t), its rate and the error of that rate.

The steady window follows the experiments (Zhou et al. 2019, sec. II.B):
the mean of the instantaneous rate over the stationary regime, after the
start-up transient and before the silo runs low. It is judged on the
discharge's own time scale, T = sqrt(D/g) (the orifice's, not the silo
width's: a wide silo's plateau need not outlast sqrt(L/g)). The error of the
time average is estimated by batch means: the window cut into
``BATCHES`` equal spans, whose means are nearly independent when each span is
long against the correlation time of the fluctuations (~T); their standard
deviation over sqrt(BATCHES) is the standard error of the mean.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from foamsilo.post.discharge import Discharge
from foamsilo.scene import Scene

#: Smoothed Q must stay within this of the plateau for the window to start
STEADY_TOLERANCE = 0.02
#: Largest relative drift of Q over the window still called steady
STEADY_MAX_DRIFT = 0.03
#: Largest excursion of the smoothed Q from its mean still called steady
STEADY_MAX_EXCURSION = 0.05
#: Below this share of its initial fill the silo is near its end: a rate that
#: then leaves its plateau for good is the end of the discharge (air breaking
#: through a thin bed, the free surface nearing the orifice), cut from the window
END_OF_DISCHARGE = 0.25
#: The window opens no earlier than this many sqrt(D/g) (the start-up)
START = 1.0
#: Width of the moving average judged for the plateau, in sqrt(D/g)
SMOOTHING = 1.0
#: Shortest steady window, in sqrt(D/g): two correlation times of Q at least
MIN_WINDOW = 2.0
#: Batches of the batch-means error of the time average
BATCHES = 10
#: Step-to-step swing of a steady rate (over its mean) above which the report
#: warns: the 1% a converged rate is asked for. A rate that changes that much
#: from one step to the next is a numerical oscillation, not the flow
#: (docs/solver.md, "Q against the time step")
STEP_SWING_WARNING = 0.01


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
    q_error
        Standard error of the time average ``q`` (batch means).
    batch_span
        The span of one batch over the discharge time sqrt(D/g): the error
        assumes batches longer than the correlation time (~1).
    step_swing
        Standard deviation of the step-to-step change of Q in the window,
        over sqrt(2) and the mean: the part of ``q_std`` that changes from one
        step to the next (a slow wander does not count).
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
    q_error: float = math.nan
    batch_span: float = math.nan
    step_swing: float = math.nan


def step_swing(q: np.ndarray) -> float:
    """Return the step-to-step swing of a rate series over its mean.

    std(q[i+1] - q[i]) / sqrt(2) / mean(q): equal to std(q) / mean(q) for
    fluctuations uncorrelated from step to step, near 0 for a slow wander.
    NaN for fewer than three values or a zero mean.
    """
    mean = float(np.mean(q)) if len(q) else 0.0
    if len(q) < 3 or mean == 0:
        return math.nan
    return float(np.std(np.diff(q)) / math.sqrt(2.0) / abs(mean))


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


def batch_means_error(
    t: np.ndarray, q: np.ndarray, dt: np.ndarray, batches: int = BATCHES
) -> float:
    """Estimate the standard error of the time-weighted mean of q by batch means.

    Parameters
    ----------
    t, q, dt
        Times, rates and step lengths over the averaging window.
    batches
        Number of equal spans the window is cut into.

    Returns
    -------
    float
        Standard deviation of the batch means over sqrt(batches); NaN when a
        batch holds no step.
    """
    edges = np.linspace(t[0], t[-1], batches + 1)
    which = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, batches - 1)
    w = np.bincount(which, weights=dt, minlength=batches)
    if np.any(w <= 0):
        return math.nan
    means = np.bincount(which, weights=q * dt, minlength=batches) / w
    return float(np.std(means, ddof=1) / math.sqrt(batches))


def find_steady(d: Discharge, scene: Scene) -> SteadyState:
    """Locate the stationary regime of Q(t), average over it, and give the error of the mean."""
    T = scene.discharge_time_scale
    t, q = d.time, d.mass_flow
    area = scene.cross_section_area  # volume / area: the equivalent fill height
    h_eq = d.volume / area
    usable = (t > START * T) & (h_eq > scene.emptied_height)
    nan = SteadyState(False, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan)
    if usable.sum() < 20:
        nan.reason = (
            f"run too short (or silo emptied): fewer than 20 usable steps after {START:g} sqrt(D/g)"
        )
        return nan
    idx = np.flatnonzero(usable)
    i1 = idx[-1]
    width = SMOOTHING * T
    h_end = END_OF_DISCHARGE * d.initial_volume / area
    for _ in range(2):
        tt, qq = t[: i1 + 1], q[: i1 + 1]
        smooth = _smooth(tt, qq, width)
        later = (tt >= 0.5 * (tt[idx[0]] + tt[-1])) & (tt > START * T)
        # the plateau from the smoothed rate: the raw rate's median sits on
        # one branch of a rate that swings from step to step at a constant step
        q_ref = float(np.median(smooth[later]))
        # the end of the discharge: where the smoothed rate has left the
        # excursion band for good once the silo is nearly empty, the window
        # ends half a smoothing width before (the smoothing spreads the fall)
        off = np.abs(smooth - q_ref) > STEADY_MAX_EXCURSION * abs(q_ref)
        if not off[-1]:
            break
        k = i1
        while k > idx[0] and off[k - 1]:
            k -= 1
        cut = int(np.searchsorted(t, t[k] - width / 2)) - 1
        if h_eq[k] >= h_end or cut <= idx[0]:
            break
        i1 = cut
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
    if len(tw) < 20 or tw[-1] - tw[0] < MIN_WINDOW * T:
        nan.reason = (
            f"no stationary regime: the rate reached its plateau (within {STEADY_TOLERANCE:.0%})"
            f" only {(tw[-1] - tw[0]) / T if len(tw) else 0:.2f} sqrt(D/g) before the end "
            f"(need >= {MIN_WINDOW:g})"
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
        batch_means_error(tw, qw, dtw),
        span / BATCHES / T,
        step_swing(qw),
    )
