"""The mean pore pressure of the stationary regime (Zhou et al. 2019, Figs 5b and 6b)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.post.discharge import Discharge
from foamsilo.post.series import read_function_object, read_probes, read_vector_series
from foamsilo.post.steady import SteadyState
from foamsilo.scene import Scene

#: Picture of the mean pore pressure along the axis
PORE_PRESSURE_PNG = "pore_pressure.png"


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
    tz, gz = read_vector_series(case, "orificeZoneGradient")
    wz = (tz >= st.t_start) & (tz <= st.t_end)
    zone = float(np.mean(gz[wz, 1])) if wz.any() else math.nan
    gas = read_function_object(case, "orificeGasFlow").data
    wg = (gas[:, 0] >= st.t_start) & (gas[:, 0] <= st.t_end)
    flux = float(np.mean(gas[wg, 1]) / d.depth) if wg.any() else math.nan
    return PorePressure(
        ym, pm, g_near, g_far, c_far, y_star, g_far_fit, resistance * flux / s_o, zone, flux, taps
    )


def pore_pressure_scaled(pp: PorePressure, scene: Scene, st: SteadyState) -> dict[str, Any]:
    """Pore-pressure figures of Zhou et al. Figs 5b and 6b, dimensional and scaled."""
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
    ax.plot(
        yy / D,
        pp.gradient_far * yy + pp.far_intercept,
        "C1-",
        lw=1,
        label="far: Darcy slope over the silo section",
    )
    lo = float(np.nanmin(pp.pressure)) if pp.pressure.size else 0.0
    hi = float(np.nanmax(pp.pressure)) if pp.pressure.size else 1.0
    pad = 0.1 * max(hi - lo, 1e-9)
    ax.set_ylim(lo - pad, hi + pad)
    ax.set_xlabel("height above the orifice y/D")
    ax.set_ylabel("pore pressure p_f [Pa]")
    ax.set_title(f"{scene.name}: pore pressure on the axis ({scene.gas.mode})", fontsize=9)
    finish(fig, ax, path, legend_size=7)
