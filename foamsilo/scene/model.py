"""The scene model: a validated description of a silo discharge, in SI units.

Every field carries its unit, its allowed range and a one-line description
(:func:`foamsilo.scene.schema.field_spec`); the derived properties (the
representation, the viscosity cap, the permeabilities, the scales) are the
single place where defaults that depend on other fields are resolved.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

from foamsilo.analytic.exact import hydraulic_radius
from foamsilo.analytic.rheology import BARKER_GRAY_ALPHA, FrictionLaw
from foamsilo.scene.schema import field_spec as _f

GRAVITY = 9.81
#: Opening angle of an axisymmetric wedge mesh [deg] (OpenFOAM: at most 5)
WEDGE_ANGLE_DEG = 5.0
#: Fill height over the cross-section's area per unit length of wall (A/P:
#: L/2 for a planar silo, D/4 for a cylinder; Janssen's length without K mu_w)
#: above which a planar or 3D column gets the implicit stress-pressure coupling
#: by default: there the lagged wall stress carries the last iterate's pressure
#: down the column and the rate swings from step to step, or the run diverges
#: (docs/solver.md, "Tall columns"). 20: a planar column of 10 widths
TALL_COLUMN = 20.0
#: Equivalent fill height, in silo widths, below which the discharge is over
#: (Scene.emptied_height)
EMPTIED_FILL = 0.5
#: With the implicit stress-pressure coupling, a step whose last outer
#: iteration changes the grains' velocity more than this many times the one
#: before is taken again with half the divergence share by default
#: (Scene.outer_growth_limit; the choice and its effect on the suite's rows:
#: docs/solver.md, "Half the share for a step whose outer iterations grow")
OUTER_GROWTH_LIMIT = 2.0
#: ... or whose last outer iteration moves a grain by more than this share of
#: the fastest grain's speed (Scene.outer_change_limit; the choice and its
#: effect: docs/solver.md, "Bursts in the uniform 96-across lab silo")
OUTER_CHANGE_LIMIT = 0.05

Representation = Literal["auto", "planar", "axisymmetric", "3d"]


#: Absolute tolerance of the pressure solve of a free discharge, and of one
#: through a feeder (Scene.p_tolerance)
P_TOLERANCE = 1e-7
FEEDER_P_TOLERANCE = 1e-10
#: The light phase's density in the volume-of-fluid mixture of a planar or
#: axisymmetric scene, as a fraction of the grains' (Scene.void_density;
#: why not air's own: docs/solver.md, "The light phase's density")
VOID_DENSITY_FRACTION = 0.01


@dataclass(frozen=True)
class Silo:
    """Geometry of the silo and its orifice.

    The silo stands on y = 0 with gravity along -y; a 3D silo has its axis
    (cylinder, hopper) or its wall-to-wall width (rectangular box) along x,
    its thickness along z.
    """

    width: float = _f(
        "silo width L: wall to wall (rectangular), inner diameter (cylindrical), diameter "
        "of the upper cylindrical section (hopper)",
        "m",
        gt=0,
    )
    height: float = _f("silo height H, bottom to the open top of the domain", "m", gt=0)
    fill_height: float = _f("initial height of the granular column", "m", gt=0)
    orifice_width: float = _f(
        "orifice size D: slot width (planar), disk diameter, height of a lateral orifice, "
        "outlet width or diameter of a hopper",
        "m",
        gt=0,
    )
    shape: Literal["rectangular", "cylindrical", "hopper"] = _f(
        "rectangular box, flat-bottomed cylinder, or conical (wedge-shaped if planar) hopper "
        "below a cylindrical section",
        default="rectangular",
    )
    orifice_position: Literal["bottom", "lateral"] = _f(
        "bottom, or lateral (on the wall at x = +L/2 of a cylinder, x = L of a box)",
        default="bottom",
    )
    orifice_shape: Literal["auto", "circular", "rectangular"] = _f(
        "auto: circular in a cylinder's bottom or a hopper, rectangular otherwise",
        default="auto",
    )
    orifice_length: float | None = _f(
        "second side W of a rectangular orifice: across the thickness of a box (default: "
        "the whole thickness), arc length on a cylinder wall",
        "m",
        gt=0,
        default=None,
    )
    orifice_height: float | None = _f(
        "height of the lower edge of a lateral orifice above the bottom (Zhou: 0.02)",
        "m",
        ge=0,
        default=None,
    )
    eccentricity: float = _f(
        "distance e of a bottom orifice's centre from the silo axis (cylindrical)",
        "m",
        ge=0,
        default=0.0,
    )
    hopper_angle: float | None = _f(
        "hopper half-angle theta_w from the vertical at the outlet",
        "deg",
        gt=0,
        lt=90,
        default=None,
    )
    hopper_angle_upper: float | None = _f(
        "half-angle Theta_w of an upper cone (two-angle hopper, Gremaud & Matthews Fig. 8)",
        "deg",
        gt=0,
        lt=90,
        default=None,
    )
    transition_width: float | None = _f(
        "width (diameter) of a two-angle hopper where the wall angle changes",
        "m",
        gt=0,
        default=None,
    )
    feeder_flow_rate: float | None = _f(
        "volumetric outflow a feeder imposes at the orifice (Venier et al. Test 2: 8.35 m^3/h "
        "= 2.32e-3 m^3/s); default: free discharge",
        "m^3/s",
        gt=0,
        default=None,
    )
    thickness: float | None = _f(
        "thickness W of a rectangular silo (a 3D box; a thin planar silo's wall gap for wall "
        "friction and to turn an air flow in m^3/s into a flow per unit depth)",
        "m",
        gt=0,
        default=None,
    )

    # ------------------------------------------------------------------ derived
    @property
    def resolved_orifice_shape(self) -> Literal["circular", "rectangular"]:
        """Orifice shape with ``auto`` resolved."""
        if self.orifice_shape != "auto":
            return self.orifice_shape
        if self.shape == "hopper" or (
            self.shape == "cylindrical" and self.orifice_position == "bottom"
        ):
            return "circular"
        return "rectangular"

    @property
    def lateral_arc_length(self) -> float | None:
        """Arc length of the wall a lateral orifice on a cylinder spans at its widest [m].

        A rectangle: its ``orifice_length``. A circular hole (drilled along the
        radius): 2 R asin(r/R) at its centre height, r = D/2.
        """
        if self.orifice_position != "lateral" or self.shape != "cylindrical":
            return None
        if self.resolved_orifice_shape == "rectangular":
            return self.orifice_length
        R, r = self.width / 2, self.orifice_width / 2
        return 2 * R * math.asin(min(1.0, r / R))

    def wall_radius(self, y: float) -> float:
        """Half-width (radius) of the silo wall at height y [m]."""
        return float(_interp(y, *zip(*self.profile, strict=True)))

    @property
    def profile(self) -> list[tuple[float, float]]:
        """Wall corners (y, half-width) from the bottom to the top."""
        R = self.width / 2
        if self.shape != "hopper":
            return [(0.0, R), (self.height, R)]
        assert self.hopper_angle is not None
        r = self.orifice_width / 2
        pts = [(0.0, r)]
        y = 0.0
        if self.hopper_angle_upper is not None and self.transition_width is not None:
            rt = self.transition_width / 2
            y += (rt - r) / math.tan(math.radians(self.hopper_angle))
            pts.append((y, rt))
            y += (R - rt) / math.tan(math.radians(self.hopper_angle_upper))
        else:
            y += (R - r) / math.tan(math.radians(self.hopper_angle))
        pts.append((y, R))
        if y < self.height:
            pts.append((self.height, R))
        return pts

    @property
    def cone_height(self) -> float:
        """Height of the top of the converging section (0 for a flat bottom) [m]."""
        if self.shape != "hopper":
            return 0.0
        return next(y for y, r in self.profile if r >= self.width / 2 - 1e-15)


def _interp(x: float, xs: tuple[float, ...], ys: tuple[float, ...]) -> float:
    for i in range(len(xs) - 1):
        if x <= xs[i + 1] or i == len(xs) - 2:
            t = (x - xs[i]) / (xs[i + 1] - xs[i]) if xs[i + 1] > xs[i] else 0.0
            return ys[i] + t * (ys[i + 1] - ys[i])
    return ys[-1]


@dataclass(frozen=True)
class Material:
    """The granular material and its mu(I) rheology (Zhou et al. eq. 9)."""

    grain_diameter: float = _f("grain diameter d", "m", gt=0)
    density: float = _f("grain (phase) density rho_p", "kg/m^3", gt=0)
    mu_s: float = _f("static friction coefficient mu_s", "", ge=0, le=2)
    delta_mu: float = _f("mu_2 - mu_s", "", ge=0, le=2)
    i0: float = _f("inertial-number scale I0", "", gt=0, le=10)
    rheology: Literal["mu-i", "barker-gray"] = _f(
        "friction law: mu-i, the plain mu(I), ill-posed below an I1 and above an I2 "
        "(Barker et al. 2015; I1 = 0.031, I2 = 1.08 for mu_s 0.4, delta_mu 0.28, I0 0.4); "
        "barker-gray, its partial regularisation (Barker & Gray 2017): "
        "sqrt(alpha / ln(A / I)) below I1, well posed there",
        default="mu-i",
    )
    mu_inf: float | None = _f(
        "high-I term mu_inf I^2 / (I0 + I) of the barker-gray law (Barker & Gray 2017; "
        "it widens the well-posed range at high I); default 0, the plain law above I1",
        "",
        ge=0,
        le=2,
        default=None,
    )
    regularisation_alpha: float | None = _f(
        "alpha of the barker-gray low-I curve; default 1.9 (Barker & Gray)",
        "",
        gt=0,
        lt=2,
        default=None,
    )
    viscosity_cap: float | None = _f(
        "viscosity cap eta_max; give this or viscosity_cap_scaled", "Pa s", gt=0, default=None
    )
    viscosity_cap_scaled: float | None = _f(
        "viscosity cap as a multiple of rho_p sqrt(g L^3) (Zhou: 100)", "", gt=0, default=None
    )
    pressure_floor: float | None = _f(
        "floor p_min of the granular pressure in mu(I); default 1e-4 rho_p g L",
        "Pa",
        gt=0,
        default=None,
    )
    wall_friction: float | None = _f(
        "Coulomb friction mu_w on the front and back walls of a thin planar silo "
        "(Zhou eq. 14; needs silo.thickness)",
        "",
        ge=0,
        le=2,
        default=None,
    )

    @property
    def friction_law(self) -> FrictionLaw:
        """The friction law mu(I) the solver uses, resolved."""
        if self.rheology == "mu-i":
            return FrictionLaw(self.mu_s, self.delta_mu, self.i0)
        alpha = (
            BARKER_GRAY_ALPHA if self.regularisation_alpha is None else self.regularisation_alpha
        )
        return FrictionLaw(self.mu_s, self.delta_mu, self.i0, self.mu_inf or 0.0, alpha)


@dataclass(frozen=True)
class Air:
    """The interstitial / surrounding gas (the light VOF phase)."""

    density: float = _f("gas density rho_f", "kg/m^3", gt=0, default=1.2)
    viscosity: float = _f("gas dynamic viscosity eta_f", "Pa s", gt=0, default=1.8e-5)


@dataclass(frozen=True)
class Gas:
    """Gas coupling (Zhou et al. 2019): modes named as the paper names them."""

    mode: Literal["open-top", "closed-top", "injection"] = _f(
        "open-top: no coupling (no pore pressure at all); closed-top: Q_air = 0, air drawn "
        "in through the orifice; injection: air injected at the top at Q_air",
        default="open-top",
    )
    q_air: float | None = _f("injected air flow (injection mode)", "m^3/s", gt=0, default=None)
    q_air_lpm: float | None = _f("injected air flow (injection mode)", "L/min", gt=0, default=None)
    q_air_scaled: float | None = _f(
        "injected air flow per unit depth over sqrt(g L^3) (planar scenes, Zhou Fig. 4b)",
        "",
        gt=0,
        default=None,
    )
    permeability: float | None = _f(
        "Darcy permeability kappa_v of the grains; default Ergun at packing_fraction",
        "m^2",
        gt=0,
        default=None,
    )
    permeability_scaled: float | None = _f(
        "Zhou's dimensionless permeability zeta = kappa_v rho_p sqrt(g/L)/eta_f (their "
        "simulations: 1); replaces permeability",
        "",
        gt=0,
        default=None,
    )
    inertial: bool = _f("Forchheimer term (kappa_i, Ergun) on; off: Darcy only", default=True)
    packing_fraction: float = _f(
        "volume fraction phi in the Ergun permeabilities", "", gt=0, lt=1, default=0.6
    )
    permeability_ratio: float = _f(
        "how much more permeable the gas region is (Zhou: zeta_inf = 100)",
        "",
        ge=1,
        le=1e6,
        default=100.0,
    )
    taps: tuple[float, ...] = _f(
        "heights of pore-pressure taps on the silo axis above the floor (each < silo.height); "
        "their mean pressure over the steady regime is reported",
        "m",
        gt=0,
        default=(),
    )


#: Most cells across the silo width a scene may ask for
CELLS_ACROSS_MAX = 2048


@dataclass(frozen=True)
class Mesh:
    """Mesh resolution and representation."""

    cells_across: int | None = _f(
        "cells across the silo width L (the paper uses 64); give this or cells_across_orifice",
        ge=4,
        le=CELLS_ACROSS_MAX,
        default=None,
    )
    cells_across_orifice: int | None = _f(
        "cells across the orifice D, the resolution that sets Q; the cells across L follow "
        "as round(n L / D)",
        ge=2,
        le=512,
        default=None,
    )
    representation: Representation = _f(
        "planar (one cell thick), axisymmetric (wedge), 3d, or auto (cheapest faithful)",
        default="auto",
    )
    top_cell_ratio: float = _f(
        "height of the topmost cell over the cell width; cells grow geometrically above "
        "fine_height (1: uniform mesh)",
        "",
        ge=1,
        le=8,
        default=3.0,
    )
    fine_height: float | None = _f(
        "height up to which cells stay square when graded; default: the silo width",
        "m",
        gt=0,
        default=None,
    )
    growth_rate: float = _f(
        "graded mesh: largest size ratio of neighbouring cells away from the orifice region "
        "(1: uniform cells of L / cells_across; centred bottom orifices, lateral ones of "
        "planar silos and of 3D cylinders, whose rows alone are graded)",
        "",
        ge=1,
        le=1.5,
        default=1.0,
    )
    orifice_region: float = _f(
        "graded mesh: cells of the orifice's size reach this many orifice widths D beyond "
        "the orifice's edges and above the floor (a lateral orifice: above and below it)",
        "",
        ge=0.25,
        le=10,
        default=1.0,
    )
    orifice_edge_refinement: float = _f(
        "graded mesh: the columns (3D: the radial cells; a lateral orifice: the rows) at the "
        "orifice's edges are this many "
        "times narrower than the orifice's cells, and widen by at most growth_rate per cell "
        "to them on both sides (the flow turns round the edge; 1: no refinement)",
        "",
        ge=1,
        le=32,
        default=1.0,
    )
    orifice_exit_refinement: float = _f(
        "graded mesh, bottom orifice: the rows at the floor (the orifice's exit) are this "
        "many times lower than the orifice's cells, and grow by at most growth_rate per cell "
        "to them upwards (the grains leave through the exit row; the step shrinks with it; "
        "1: no refinement)",
        "",
        ge=1,
        le=8,
        default=1.0,
    )
    coarse_cells_across: int = _f(
        "graded mesh: the largest cells are L / coarse_cells_across wide and tall (never "
        "smaller than the orifice's cells; capped so that the headspace keeps two cells)",
        "",
        ge=2,
        le=512,
        default=16,
    )

    @property
    def graded(self) -> bool:
        """Whether cells grow away from the orifice region (``growth_rate`` > 1)."""
        return self.growth_rate > 1.0 + 1e-12


@dataclass(frozen=True)
class Run:
    """Time integration and output."""

    end_time: float = _f("simulated time at which the run stops", "s", gt=0)
    write_interval: float = _f("interval between written time directories", "s", gt=0)
    max_courant: float = _f("Courant number limit over all cells", "", gt=0, le=10, default=0.5)
    max_interface_courant: float = _f(
        "Courant number limit at the free surface", "", gt=0, le=1, default=0.5
    )
    max_granular_courant: float = _f(
        "Courant number limit over the grains only (0: not used)", "", ge=0, le=10, default=0.0
    )
    max_delta_t: float | None = _f(
        "largest time step (a safety net; the Courant limits set the step); default 0.05 "
        "sqrt(L/g), and with gas coupling at most the grains' drag relaxation time rho kappa/mu",
        "s",
        gt=0,
        default=None,
    )
    n_procs: int = _f("MPI ranks (1: serial)", ge=1, le=4096, default=1)
    stop_when_empty: bool = _f(
        "end the run once the silo holds less than half a width of grains (an equivalent "
        "fill height below 0.5 L: the end of the discharge, which no steady window reaches)",
        default=True,
    )
    max_recoveries: int = _f(
        "times a diverged run goes back to its latest complete time with the step halved "
        "before it is given up (0: stop at the first divergence)",
        ge=0,
        le=20,
        default=3,
    )
    max_step_retakes: int = _f(
        "times, within any one discharge time sqrt(D/g), the solver takes a step again from "
        "its start with half the step when its outer iterations diverge (the volume fraction "
        "leaves [-0.5, 1.5] or the Courant number reaches 20 times its limit; not in the first "
        "discharge time of a scene that iterates each step), before the run stops (then "
        "run.max_recoveries applies)",
        ge=0,
        le=10,
        default=4,
    )
    retake_check_interval: int = _f(
        "diagnostic: every this many steps the solver takes a step that passed again from its "
        "saved start with the same step and stops with an error unless it ends on the same "
        "fields to the last digit (a check that a retake puts back all a step carries over); "
        "0: never",
        ge=0,
        le=1000000,
        default=0,
    )


@dataclass(frozen=True)
class Numerics:
    """Linear solvers and scheme switches (their defaults' measurements: docs/benchmarks)."""

    u_rel_tol: float = _f(
        "relative tolerance of the momentum predictor solve (0: solve to u_tolerance)",
        "",
        ge=0,
        lt=1,
        default=0.01,
    )
    u_tolerance: float = _f("absolute tolerance of the momentum solve", "", gt=0, default=1e-9)
    p_tolerance: float | None = _f(
        "absolute tolerance of the pressure solve; default 1e-7, and 1e-10 with a feeder, "
        "whose imposed outflow leaves the solve's error in the fluxes at the orifice "
        "(docs/solver.md)",
        "",
        gt=0,
        default=None,
    )
    void_density: float | None = _f(
        "density of the light phase above the grains in the volume-of-fluid mixture; "
        "default material.density/100 in planar and axisymmetric scenes, air.density "
        "in 3D ones (why: docs/solver.md, 'The light phase's density'); "
        "at most material.density/10. The pore pressure keeps air.density",
        "kg/m^3",
        gt=0,
        default=None,
    )
    cache_gradients: bool = _f(
        "compute grad(U) once per step for the rheology and the stress (the runs with and "
        "without it are the same to the last digit: docs/benchmarks/solver.md)",
        default=True,
    )
    friction_relaxation: float = _f(
        "weight of the new wall-friction drag coefficient each step (1: none); the drag "
        "follows the pressure, which follows the drag: thin silos oscillate without it",
        "",
        gt=0,
        le=1,
        default=0.2,
    )
    ddt_correction: bool = _f(
        "Rhie-Chow ddtCorr in the projection (off: more robust above Courant 0.5)",
        default=True,
    )
    open_boundary_acceleration: Literal["cell", "face"] = _f(
        "old pressure acceleration on the orifice and the open top in the projection: the "
        "cell's, extrapolated (the scheme so far), or the face's own, which removes a part "
        "of the outflow that grows with the step (docs/solver.md)",
        default="cell",
    )
    rhie_chow_scale: float = _f(
        "a diagnostic: the face flux's pressure smoothing (the Rhie-Chow part of the "
        "projection, proportional to the step) scaled by this factor, so that a run shows "
        "how much of its rate that term sets at a given step (docs/solver.md); 1: the scheme "
        "itself; the added part is lagged, stable below 2",
        "",
        gt=0,
        lt=2,
        default=1.0,
    )
    face_smoothing: Literal["step", "courant"] = _f(
        "size of the face flux's pressure smoothing (the Rhie-Chow part of the projection): "
        "the step taken (the scheme so far: a capped or recovered run's steady rate moves "
        "with its cap), or the step at which the all-cell Courant number would be "
        "face_smoothing_courant, so that the steady rate does not depend on the caps "
        "(docs/solver.md)",
        default="step",
    )
    face_smoothing_courant: float = _f(
        "with face_smoothing = 'courant': the Courant number whose step sizes the smoothing "
        "(never less than the step taken)",
        "",
        gt=0,
        le=10,
        default=0.5,
    )
    face_smoothing_max_ratio: float = _f(
        "with face_smoothing = 'courant': the largest smoothing step in steps taken (the "
        "pressure relaxes by the step's share of it per step)",
        "",
        ge=1,
        le=100,
        default=4.0,
    )
    viscosity_interpolation: Literal["linear", "harmonic"] = _f(
        "the granular viscosity on a face of the stress (its implicit part and the explicit "
        "transpose): the linear or the harmonic mean of its two cells' (the harmonic one is "
        "the stress of the two halves in series, exact for a viscosity constant in each "
        "cell, and keeps the stagnant zone's capped viscosity out of the faces of the "
        "flowing cells beside it); a diagnostic: the harmonic mean fails the code "
        "verification at a free surface (docs/solver.md)",
        default="linear",
    )
    start_up_viscosity_interpolation: Literal["linear", "harmonic"] | None = _f(
        "the same mean in the start-up only (the steps that start within the first "
        "discharge time sqrt(D/g), which the steady window leaves out); after it the faces "
        "take viscosity_interpolation's. Harmonic keeps the capped cells' viscosity out of "
        "the faces of the yielding cells beside them while the flow starts. Default: "
        "harmonic in axisymmetric scenes, linear in planar and 3D ones (why: "
        "docs/solver.md, 'The start-up's face mean')",
        default=None,
    )
    stress_pressure_coupling: Literal["implicit", "lagged"] | None = _f(
        "the granular stress's share of a pressure change in the projection: taken "
        "implicitly (d tau/d p in the pressure equation), or lagged to the next outer "
        "iteration, where a tall column's wall stress feeds the pressure back; default: "
        "implicit in axisymmetric scenes, ones with quasi-2D wall friction and tall "
        "columns (filled higher than 20 times the cross-section's area per unit length "
        "of wall: 10 widths planar, 5 diameters in a cylinder), lagged in other planar "
        "and 3D ones (why: docs/solver.md, 'Tall columns')",
        default=None,
    )
    stress_pressure_divergence: float = _f(
        "with the implicit stress-pressure coupling: the share of its divergence part (the "
        "stress's change with the pressure, div(M dp), beside n.M.n in the Laplacian) "
        "taken in the projection; 1: the whole linearisation; less: fewer bursts in fine "
        "axisymmetric meshes (the lab silo's preset takes 0.5), what each share does to "
        "which scene in docs/solver.md; no effect on a converged step",
        "",
        gt=0,
        le=1,
        default=1.0,
    )
    outer_growth_limit: float | None = _f(
        "with the implicit stress-pressure coupling: a step whose last outer iteration "
        "changes the grains' velocity (rms) more than this many times the iteration before "
        "(the Picard iteration diverging) is taken again from its start at the same step with "
        "half the divergence share (numerics.stress_pressure_divergence) and four times the "
        "outer iterations; not in the first discharge time; a step that then fails is taken "
        "as the whole share took it, and no step is taken again so for one discharge time "
        "after it; 0: never, else above 1 (what it does: docs/solver.md); default: 2 with "
        "the implicit coupling, else 0",
        "",
        ge=0,
        le=100,
        default=None,
    )
    outer_change_limit: float | None = _f(
        "with the implicit stress-pressure coupling: a step whose last outer iteration "
        "moves a grain (a cell with alpha > 1/2) by more than this share of the fastest "
        "grain's speed (a burst starting in a few cells, which the rms growth of "
        "numerics.outer_growth_limit hardly sees) is taken again as that key takes it; "
        "0: never, else <= 1 (what it does: docs/solver.md); default: 0.05 with the "
        "implicit coupling, else 0",
        "",
        ge=0,
        le=1,
        default=None,
    )
    outer_correctors: int | None = _f(
        "PIMPLE outer iterations per step: each re-evaluates the mu(I) viscosity from the "
        "latest pressure and strain rate; default: 1 in planar scenes and in dry 3D ones "
        "with a bottom orifice and the lagged stress-pressure coupling, else 3 (why: "
        "docs/geometry.md)",
        ge=1,
        le=20,
        default=None,
    )


@dataclass(frozen=True)
class Scene:
    """A complete, validated silo discharge scene (SI units)."""

    name: str = _f("short name of the scene (used for directory names)")
    silo: Silo = _f("geometry")
    material: Material = _f("granular material")
    mesh: Mesh = _f("mesh")
    run: Run = _f("run control")
    description: str = _f("one-line description", default="")
    air: Air = _f("gas phase", default=Air())
    numerics: Numerics = _f("linear solvers and scheme switches", default=Numerics())
    gas: Gas = _f("gas coupling: open top, closed top or injection", default=Gas())
    gravity: float = _f(
        "magnitude of the gravitational acceleration", "m/s^2", gt=0, le=100, default=GRAVITY
    )

    # ------------------------------------------------------------------ derived
    @property
    def representation(self) -> Literal["planar", "axisymmetric", "3d"]:
        """Representation actually used (``auto`` resolved)."""
        rep = self.mesh.representation
        if rep != "auto":
            return rep
        return self.allowed_representations[0]

    @property
    def allowed_representations(self) -> list[Literal["planar", "axisymmetric", "3d"]]:
        """Representations faithful to the silo, cheapest first."""
        s = self.silo
        if s.shape == "rectangular":
            return ["planar", "3d"]
        if s.shape == "hopper":
            return ["axisymmetric", "planar", "3d"]
        centred = s.orifice_position == "bottom" and s.eccentricity == 0.0
        return ["axisymmetric", "3d"] if centred else ["3d"]

    @property
    def mesh_fraction(self) -> float:
        """Fraction of the silo the mesh holds (fluxes and volumes divide by it).

        The depth of the planar slab [m], the wedge's share of the full
        circle, or 1 in 3D.
        """
        rep = self.representation
        if rep == "planar":
            return self.cell_size
        if rep == "axisymmetric":
            # the wedge's faces are planar: its cross-section is the triangle
            # r^2 sin(a)/2, not the sector r^2 a/2
            return math.sin(math.radians(WEDGE_ANGLE_DEG)) / (2 * math.pi)
        return 1.0

    @property
    def emptied_height(self) -> float:
        """Equivalent fill height [m] below which the discharge is over.

        Half a silo width: below it the free surface dips into the orifice's
        region and what is left is the end of the discharge (and the heaps in
        a flat bottom's corners); no steady window reaches it, and a run with
        ``run.stop_when_empty`` ends there.
        """
        return EMPTIED_FILL * self.silo.width

    @property
    def cross_section_area(self) -> float:
        """Area of the silo's (upper) cross-section [m^2] (planar: L, per unit depth)."""
        s = self.silo
        if self.representation == "planar":
            return s.width
        if s.shape == "rectangular":
            assert s.thickness is not None
            return s.width * s.thickness
        return math.pi * s.width**2 / 4

    @property
    def wall_length_scale(self) -> float:
        """Cross-section area per unit length of wall, A/P [m] (the hydraulic radius).

        Planar: L/2 (two walls per unit depth); a box: L W / (2 (L + W)); a
        cylinder or a hopper: D/4. The wall stress's reach down a column
        (Janssen) scales with it.
        """
        s = self.silo
        if self.representation == "planar":
            return hydraulic_radius("slot", s.width)
        if s.shape == "rectangular":
            return hydraulic_radius("box", s.width, s.thickness)
        return hydraulic_radius("cylinder", s.width)

    @property
    def flow_rate_scale(self) -> tuple[str, float]:
        """Name and value of the scale Q is made dimensionless with.

        Planar: rho sqrt(g L^3) (Zhou et al. 2019); otherwise the Beverloo
        scale rho sqrt(g) D^(5/2).
        """
        if self.representation == "planar":
            return "rho sqrt(g L^3)", self.rho_sqrt_gL3
        rho, D = self.material.density, self.silo.orifice_width
        return "rho sqrt(g) D^(5/2)", rho * math.sqrt(self.gravity) * D**2.5

    @property
    def stress_pressure_coupling(self) -> str:
        """``numerics.stress_pressure_coupling`` resolved."""
        if self.numerics.stress_pressure_coupling is not None:
            return self.numerics.stress_pressure_coupling
        # where a tall column's wall stress carries the pressure (docs/solver.md)
        tall = self.silo.fill_height > TALL_COLUMN * self.wall_length_scale
        implicit = self.representation == "axisymmetric" or self.wall_friction or tall
        return "implicit" if implicit else "lagged"

    @property
    def outer_growth_limit(self) -> float:
        """``numerics.outer_growth_limit`` resolved: 0 (never) without the implicit coupling."""
        if self.numerics.outer_growth_limit is not None:
            return self.numerics.outer_growth_limit
        return OUTER_GROWTH_LIMIT if self.stress_pressure_coupling == "implicit" else 0.0

    @property
    def outer_change_limit(self) -> float:
        """``numerics.outer_change_limit`` resolved: 0 (never) without the implicit coupling."""
        if self.numerics.outer_change_limit is not None:
            return self.numerics.outer_change_limit
        return OUTER_CHANGE_LIMIT if self.stress_pressure_coupling == "implicit" else 0.0

    @property
    def outer_correctors(self) -> int:
        """PIMPLE outer iterations (``numerics.outer_correctors`` resolved)."""
        if self.numerics.outer_correctors is not None:
            return self.numerics.outer_correctors
        # one pass in a dry 3D silo emptied through its floor with the
        # stress's share of a pressure change lagged: the same rate as three at
        # a third of the cost; the one lateral 3D silo measured at one pass
        # had its step, set by the air, collapse (docs/geometry.md)
        one_pass_3d = (
            self.representation == "3d"
            and self.stress_pressure_coupling == "lagged"
            and self.silo.orifice_position == "bottom"
            and not self.gas_coupled
        )
        return 1 if self.representation == "planar" or one_pass_3d else 3

    @property
    def eta_max(self) -> float:
        """Viscosity cap [Pa s]."""
        m = self.material
        if m.viscosity_cap is not None:
            return m.viscosity_cap
        assert m.viscosity_cap_scaled is not None
        return m.viscosity_cap_scaled * self.rho_sqrt_gL3

    @property
    def feeder_flux(self) -> float:
        """The feeder's outflow through the orifice patch of this mesh [m^3/s] (0: free).

        Planar: the flow per unit thickness times the slab's depth; a wedge:
        its share of the full circle; 3D: all of it.
        """
        q = self.silo.feeder_flow_rate
        if q is None:
            return 0.0
        if self.representation == "planar":
            assert self.silo.thickness is not None
            return q / self.silo.thickness * self.cell_size
        return q * self.mesh_fraction

    @property
    def void_density(self) -> float:
        """Density of the mixture's light phase (``numerics.void_density`` resolved).

        The phase above the grains is passive (the pore pressure's gas keeps
        ``air.density`` whatever this is); its density only has to be small
        beside the grains'. With air's own the projection's coefficient 1/rho
        spans three decades, and the pressure solve's absolute tolerance
        leaves the grains' pressure off. 3D scenes keep air's. Why, and
        what each choice was measured to do: docs/solver.md, "The light
        phase's density".
        """
        if self.numerics.void_density is not None:
            return self.numerics.void_density
        if self.representation == "3d":
            return self.air.density
        return VOID_DENSITY_FRACTION * self.material.density

    @property
    def start_up_viscosity_interpolation(self) -> str:
        """The start-up's face mean (``numerics.start_up_viscosity_interpolation`` resolved).

        Harmonic in axisymmetric scenes, linear in planar and 3D ones. Why,
        and what each choice was measured to do: docs/solver.md, "The
        start-up's face mean".
        """
        if self.numerics.start_up_viscosity_interpolation is not None:
            return self.numerics.start_up_viscosity_interpolation
        return "harmonic" if self.representation == "axisymmetric" else "linear"

    @property
    def p_tolerance(self) -> float:
        """Absolute tolerance of the pressure solve (``numerics.p_tolerance`` resolved).

        With a free orifice the pressure imposed there takes up the solve's
        error; with a feeder the outflow is imposed and the only imposed
        pressure is the open top's, so the error reaches the face fluxes at
        the orifice, where the volume fraction then leaves its bounds (Venier
        Test 2 diverged after it; docs/solver.md, "The feeder's pressure
        tolerance").
        """
        if self.numerics.p_tolerance is not None:
            return self.numerics.p_tolerance
        if self.silo.feeder_flow_rate is not None:
            return FEEDER_P_TOLERANCE
        return P_TOLERANCE

    @property
    def gas_coupled(self) -> bool:
        """Whether the scene has a pore pressure (closed top or injection)."""
        return self.gas.mode != "open-top"

    @property
    def wall_friction(self) -> bool:
        """Whether the quasi-2D wall friction term is on."""
        return bool(self.material.wall_friction)

    @property
    def q_air_per_depth(self) -> float:
        """Injected air flow per unit depth of a planar scene [m^2/s] (0: none)."""
        g = self.gas
        if g.mode != "injection":
            return 0.0
        if g.q_air_scaled is not None:
            return g.q_air_scaled * math.sqrt(self.gravity * self.silo.width**3)
        assert self.silo.thickness is not None
        return self.q_air / self.silo.thickness

    @property
    def q_air(self) -> float:
        """Injected air flow [m^3/s] (0: none); planar scaled flows use the thickness."""
        g = self.gas
        if g.mode != "injection":
            return 0.0
        if g.q_air is not None:
            return g.q_air
        if g.q_air_lpm is not None:
            return g.q_air_lpm * 1e-3 / 60
        return self.q_air_per_depth * (self.silo.thickness or 1.0)

    @property
    def permeability(self) -> float:
        """Darcy permeability kappa_v of the grains [m^2]."""
        g = self.gas
        if g.permeability is not None:
            return g.permeability
        if g.permeability_scaled is not None:
            rho = self.material.density
            return (
                g.permeability_scaled
                * self.air.viscosity
                / (rho * math.sqrt(self.gravity / self.silo.width))
            )
        phi, d = g.packing_fraction, self.material.grain_diameter
        return (1 - phi) ** 3 * d**2 / (150 * phi**2)  # Ergun

    @property
    def inertial_permeability(self) -> float | None:
        """Forchheimer permeability kappa_i [m^2] (Ergun), None for Darcy only."""
        g = self.gas
        if not g.inertial:
            return None
        phi, d = g.packing_fraction, self.material.grain_diameter
        return (1 - phi) ** 3 * d**2 / (1.75 * phi)

    @property
    def delta_t_max(self) -> float:
        """Largest time step [s]: ``run.max_delta_t``, or 0.05 sqrt(L/g) and the gas relaxation."""
        if self.run.max_delta_t is not None:
            return self.run.max_delta_t
        dt = self.default_step_cap
        tau = self.gas_relaxation_time
        return dt if tau is None else min(dt, tau)

    @property
    def default_step_cap(self) -> float:
        """The step cap of a scene without gas coupling [s]: 0.05 sqrt(L/g).

        Also the largest face-smoothing step (``numerics.face_smoothing =
        'courant'``), which no other cap (gas, ``run.max_delta_t``, a
        recovery's) lowers.
        """
        return 0.05 * self.time_scale

    @property
    def gas_relaxation_time(self) -> float | None:
        """Time [s] the Darcy drag takes to bring the grains to the air's pace: rho kappa / mu_air.

        The pore pressure's force on the grains is taken from the step before:
        a step longer than this relaxation time leaves an oscillation of the
        rate with a period of ~8 steps (docs/gas.md, "The gas coupling's time
        step"). None without gas coupling.
        """
        if not self.gas_coupled:
            return None
        return self.material.density * self.permeability / self.air.viscosity

    @property
    def p_min(self) -> float:
        """Granular pressure floor [Pa]."""
        if self.material.pressure_floor is not None:
            return self.material.pressure_floor
        return 1e-4 * self.material.density * self.gravity * self.silo.width

    @property
    def rho_sqrt_gL3(self) -> float:
        """Flow-rate scale rho_p sqrt(g L^3) of a planar silo [kg/(m s)]."""
        return self.material.density * math.sqrt(self.gravity * self.silo.width**3)

    @property
    def time_scale(self) -> float:
        """sqrt(L/g) [s]."""
        return math.sqrt(self.silo.width / self.gravity)

    @property
    def discharge_time_scale(self) -> float:
        """sqrt(D/g) [s]: the time of the flow through the orifice, what sets Q's dynamics."""
        return math.sqrt(self.silo.orifice_width / self.gravity)

    @property
    def cells_across(self) -> int:
        """Cells across the silo width L: ``mesh.cells_across``, or from the orifice's."""
        me = self.mesh
        if me.cells_across is not None:
            return me.cells_across
        assert me.cells_across_orifice is not None
        return max(4, round(me.cells_across_orifice * self.silo.width / self.silo.orifice_width))

    @property
    def cell_size(self) -> float:
        """Cell size at the orifice, L / cells_across [m] (the uniform mesh's)."""
        return self.silo.width / self.cells_across

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (TOML-serialisable: None values dropped)."""
        return drop_none(dataclasses.asdict(self))


def drop_none(d: Any) -> Any:
    """Drop the None values of nested dicts (TOML has no null)."""
    if isinstance(d, dict):
        return {k: drop_none(v) for k, v in d.items() if v is not None}
    return d
