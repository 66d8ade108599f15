"""The scene: a validated description of a silo discharge, in SI units.

A scene is read from a TOML file (or a named preset) and turned into a
:class:`Scene`.  Every field carries its unit, its allowed range and a
one-line description; :func:`load_scene` rejects unknown keys, missing keys
and out-of-range values with a :class:`~foamsilo.errors.SceneError` that
names the field and what is allowed.

Example
-------
>>> from foamsilo.scene import load_preset
>>> scene = load_preset("zhou-planar", overrides=["mesh.cells_across=16"])
>>> scene.mesh.cells_across
16
"""

from __future__ import annotations

import copy
import dataclasses
import math
import sys
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Literal, get_args, get_origin, get_type_hints

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from foamsilo.errors import SceneError

GRAVITY = 9.81
#: Opening angle of an axisymmetric wedge mesh [deg] (OpenFOAM: at most 5)
WEDGE_ANGLE_DEG = 5.0

Representation = Literal["auto", "planar", "axisymmetric", "3d"]


def _f(
    description: str,
    unit: str = "",
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    default: Any = dataclasses.MISSING,
) -> Any:
    """Declare a scene field with its documentation and allowed range."""
    meta = {"description": description, "unit": unit, "gt": gt, "ge": ge, "lt": lt, "le": le}
    if default is dataclasses.MISSING:
        return field(metadata=meta)
    return field(default=default, metadata=meta)


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


@dataclass(frozen=True)
class Mesh:
    """Mesh resolution and representation."""

    cells_across: int = _f("cells across the silo width L (the paper uses 64)", ge=4, le=2048)
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
        "largest time step (a safety net; the Courant limits set the step); default 0.05 sqrt(L/g)",
        "s",
        gt=0,
        default=None,
    )
    n_procs: int = _f("MPI ranks (1: serial)", ge=1, le=4096, default=1)


@dataclass(frozen=True)
class Numerics:
    """Linear solvers and scheme switches (defaults measured in docs/benchmarks)."""

    u_rel_tol: float = _f(
        "relative tolerance of the momentum predictor solve (0: solve to u_tolerance)",
        "",
        ge=0,
        lt=1,
        default=0.01,
    )
    u_tolerance: float = _f("absolute tolerance of the momentum solve", "", gt=0, default=1e-9)
    p_tolerance: float = _f("absolute tolerance of the pressure solve", "", gt=0, default=1e-7)
    cache_gradients: bool | None = _f(
        "compute grad(U) once per step for the rheology and the stress; default: on in "
        "planar and axisymmetric scenes, off in 3D (a 3D box diverged with it, measured)",
        default=None,
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
    outer_correctors: int | None = _f(
        "PIMPLE outer iterations per step: each re-evaluates the mu(I) viscosity from the "
        "latest pressure and strain rate; default: 1 planar, 3 axisymmetric and 3D (the "
        "72-across axisymmetric silo diverges at t = 0.011 s with 1 and 0.034 s with 2)",
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
    def cache_gradients(self) -> bool:
        """Whether grad(U) is cached (``numerics.cache_gradients`` resolved)."""
        if self.numerics.cache_gradients is not None:
            return self.numerics.cache_gradients
        return self.representation != "3d"

    @property
    def outer_correctors(self) -> int:
        """PIMPLE outer iterations (``numerics.outer_correctors`` resolved)."""
        if self.numerics.outer_correctors is not None:
            return self.numerics.outer_correctors
        return 1 if self.representation == "planar" else 3

    @property
    def eta_max(self) -> float:
        """Viscosity cap [Pa s]."""
        m = self.material
        if m.viscosity_cap is not None:
            return m.viscosity_cap
        assert m.viscosity_cap_scaled is not None
        return m.viscosity_cap_scaled * self.rho_sqrt_gL3

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
        """Largest time step [s]."""
        if self.run.max_delta_t is not None:
            return self.run.max_delta_t
        return 0.05 * self.time_scale

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
    def cell_size(self) -> float:
        """Uniform cell size L / cells_across [m]."""
        return self.silo.width / self.mesh.cells_across

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (TOML-serialisable: None values dropped)."""
        return _drop_none(dataclasses.asdict(self))


# ---------------------------------------------------------------------------- loading


def _drop_none(d: Any) -> Any:
    if isinstance(d, dict):
        return {k: _drop_none(v) for k, v in d.items() if v is not None}
    return d


def _describe_range(meta: dict[str, Any]) -> str:
    parts = []
    if meta.get("gt") is not None:
        parts.append(f"> {meta['gt']:g}")
    if meta.get("ge") is not None:
        parts.append(f">= {meta['ge']:g}")
    if meta.get("lt") is not None:
        parts.append(f"< {meta['lt']:g}")
    if meta.get("le") is not None:
        parts.append(f"<= {meta['le']:g}")
    return " and ".join(parts)


def _check_number(name: str, value: Any, typ: type, meta: dict[str, Any]) -> float | int:
    unit = f" {meta['unit']}" if meta.get("unit") else ""
    rng = _describe_range(meta)
    allowed = f"a{'n integer' if typ is int else ' number'}{' ' + rng if rng else ''}{unit}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(name, f"got {value!r}; allowed: {allowed}")
    if typ is int and not float(value).is_integer():
        raise SceneError(name, f"got {value!r}; allowed: {allowed}")
    v = int(value) if typ is int else float(value)
    if not math.isfinite(v):
        raise SceneError(name, f"got {value!r}; allowed: {allowed}")
    bad = (
        (meta.get("gt") is not None and not v > meta["gt"])
        or (meta.get("ge") is not None and not v >= meta["ge"])
        or (meta.get("lt") is not None and not v < meta["lt"])
        or (meta.get("le") is not None and not v <= meta["le"])
    )
    if bad:
        raise SceneError(name, f"got {v:g}; allowed: {allowed}")
    return v


def _build(cls: type, data: Any, prefix: str) -> Any:
    if not isinstance(data, dict):
        raise SceneError(prefix or "scene", f"expected a table, got {data!r}")
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        where = prefix + "." if prefix else ""
        raise SceneError(
            where + unknown[0],
            f"unknown key; allowed keys{' in ' + prefix if prefix else ''}: "
            + ", ".join(sorted(fields)),
        )
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        dotted = f"{prefix}.{name}" if prefix else name
        if name not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise SceneError(dotted, f"missing; {f.metadata.get('description', '')}")
            continue
        kwargs[name] = _convert(dotted, data[name], hints[name], f.metadata)
    return cls(**kwargs)


def _convert(name: str, value: Any, typ: Any, meta: dict[str, Any]) -> Any:
    origin = get_origin(typ)
    args = get_args(typ)
    if dataclasses.is_dataclass(typ):
        return _build(typ, value, name)
    if origin is Literal:
        if value not in args:
            raise SceneError(name, f"got {value!r}; allowed: {', '.join(map(repr, args))}")
        return value
    if origin is tuple:  # tuple[float, ...]: a TOML array of numbers
        if not isinstance(value, (list, tuple)):
            raise SceneError(name, f"got {value!r}; allowed: a list of numbers")
        return tuple(_check_number(f"{name}[{i}]", v, args[0], meta) for i, v in enumerate(value))
    if args and type(None) in args:  # Optional[X]
        inner = [a for a in args if a is not type(None)][0]
        return _convert(name, value, inner, meta)
    if typ is bool:
        if not isinstance(value, bool):
            raise SceneError(name, f"got {value!r}; allowed: true, false")
        return value
    if typ in (int, float):
        return _check_number(name, value, typ, meta)
    if typ is str:
        if not isinstance(value, str):
            raise SceneError(name, f"got {value!r}; allowed: a string")
        return value
    raise SceneError(name, f"unsupported type {typ}")  # pragma: no cover


def _validate(scene: Scene) -> None:
    """Cross-field checks that a single field's range cannot express."""
    s, m, me = scene.silo, scene.material, scene.mesh
    _validate_geometry(scene)
    if s.fill_height > s.height:
        raise SceneError(
            "silo.fill_height",
            f"got {s.fill_height:g} m; allowed: > 0 and <= silo.height ({s.height:g} m)",
        )
    if (m.viscosity_cap is None) == (m.viscosity_cap_scaled is None):
        raise SceneError(
            "material.viscosity_cap",
            "give exactly one of material.viscosity_cap [Pa s] and "
            "material.viscosity_cap_scaled [x rho_p sqrt(g L^3)]",
        )
    if m.grain_diameter >= s.orifice_width:
        raise SceneError(
            "material.grain_diameter",
            f"got {m.grain_diameter:g} m; allowed: > 0 and < silo.orifice_width "
            f"({s.orifice_width:g} m)",
        )
    cells_in_orifice = s.orifice_width / scene.cell_size
    if cells_in_orifice < 2 - 1e-9:
        need = math.ceil(2 * s.width / s.orifice_width)
        raise SceneError(
            "mesh.cells_across",
            f"got {me.cells_across}: the orifice spans {cells_in_orifice:.2f} cells; "
            f"allowed: >= {need} (at least 2 cells across the orifice)",
        )
    if me.fine_height is not None and me.fine_height >= s.height:
        raise SceneError(
            "mesh.fine_height",
            f"got {me.fine_height:g} m; allowed: > 0 and < silo.height ({s.height:g} m)",
        )
    if s.fill_height < 2 * scene.cell_size:
        raise SceneError(
            "silo.fill_height",
            f"got {s.fill_height:g} m; allowed: >= two cells ({2 * scene.cell_size:g} m)",
        )
    _validate_gas(scene)
    if scene.run.write_interval > scene.run.end_time:
        raise SceneError(
            "run.write_interval",
            f"got {scene.run.write_interval:g} s; allowed: > 0 and <= run.end_time "
            f"({scene.run.end_time:g} s)",
        )
    if not scene.name or any(c in scene.name for c in "/\\ \t\n"):
        raise SceneError("name", f"got {scene.name!r}; allowed: a non-empty word without spaces")


def _validate_geometry(scene: Scene) -> None:
    """Shape, orifice and representation: the checks a mesher would trip on."""
    s, me = scene.silo, scene.mesh
    allowed = scene.allowed_representations
    if me.representation != "auto" and me.representation not in allowed:
        why = {
            "rectangular": "a rectangular silo",
            "cylindrical": "a cylinder with a centred bottom orifice"
            if "axisymmetric" in allowed
            else "a cylinder with an eccentric or lateral orifice",
            "hopper": "a hopper",
        }[s.shape]
        raise SceneError(
            "mesh.representation",
            f"got {me.representation!r}; {why} is meshed "
            + " or ".join(repr(a) for a in allowed)
            + "; allowed: 'auto', "
            + ", ".join(repr(a) for a in allowed),
        )
    rep = scene.representation
    R = s.width / 2
    shape = s.resolved_orifice_shape
    if s.orifice_position == "bottom":
        if s.orifice_width >= s.width:
            raise SceneError(
                "silo.orifice_width",
                f"got {s.orifice_width:g} m: the orifice is as wide as the wall; allowed: > 0 "
                f"and < silo.width ({s.width:g} m)",
            )
        if s.orifice_height is not None:
            raise SceneError(
                "silo.orifice_height", "only for a lateral orifice (orifice_position = 'lateral')"
            )
    else:
        if s.shape == "hopper":
            raise SceneError(
                "silo.orifice_position",
                "got 'lateral'; a hopper discharges through its outlet; allowed: 'bottom'",
            )
        if s.orifice_height is None:
            raise SceneError(
                "silo.orifice_height",
                "missing: a lateral orifice needs the height of its lower edge above the bottom "
                "(Zhou et al.: 0.02 m)",
            )
        top = s.orifice_height + s.orifice_width
        if top > s.fill_height:
            raise SceneError(
                "silo.orifice_height",
                f"got {s.orifice_height:g} m: the lateral orifice ({s.orifice_height:g} to "
                f"{top:g} m) reaches above the fill; allowed: >= 0 and <= silo.fill_height - "
                f"silo.orifice_width ({s.fill_height - s.orifice_width:g} m)",
            )
    if s.eccentricity > 0:
        if s.shape != "cylindrical" or s.orifice_position != "bottom":
            raise SceneError("silo.eccentricity", "only for a bottom orifice of a cylindrical silo")
        if s.eccentricity + s.orifice_width / 2 >= R:
            raise SceneError(
                "silo.eccentricity",
                f"got {s.eccentricity:g} m: the eccentric outlet reaches outside the bottom; "
                f"allowed: >= 0 and < silo.width/2 - silo.orifice_width/2 "
                f"({R - s.orifice_width / 2:g} m)",
            )
    if s.shape == "cylindrical":
        if s.orifice_position == "bottom" and shape != "circular":
            raise SceneError(
                "silo.orifice_shape",
                f"got {s.orifice_shape!r} for a cylinder's bottom; allowed: 'auto', 'circular'",
            )
        if s.orifice_position == "lateral" and shape == "rectangular":
            if s.orifice_length is None:
                raise SceneError(
                    "silo.orifice_length",
                    "missing: a rectangular lateral orifice on a cylinder needs its arc length W",
                )
            if s.orifice_length >= 0.5 * math.pi * R:
                raise SceneError(
                    "silo.orifice_length",
                    f"got {s.orifice_length:g} m: the orifice spans more than a quarter of the "
                    f"wall; allowed: > 0 and < pi L/8 ({0.5 * math.pi * R:g} m)",
                )
        if s.orifice_position == "lateral" and shape == "circular":
            if s.orifice_width >= 0.8 * s.width:
                raise SceneError(
                    "silo.orifice_width",
                    f"got {s.orifice_width:g} m: a circular lateral orifice as wide as the wall; "
                    f"allowed: > 0 and < 0.8 silo.width ({0.8 * s.width:g} m)",
                )
    if s.shape == "rectangular":
        if shape != "rectangular":
            raise SceneError(
                "silo.orifice_shape",
                f"got {s.orifice_shape!r} for a rectangular silo; allowed: 'auto', 'rectangular'",
            )
        if rep == "3d" and s.thickness is None:
            raise SceneError(
                "silo.thickness", "missing: a rectangular silo meshed in 3D needs its thickness W"
            )
        if s.orifice_length is not None and s.thickness is not None:
            if s.orifice_length > s.thickness:
                raise SceneError(
                    "silo.orifice_length",
                    f"got {s.orifice_length:g} m: wider than the silo; allowed: > 0 and <= "
                    f"silo.thickness ({s.thickness:g} m)",
                )
    if s.shape == "hopper":
        if s.hopper_angle is None:
            raise SceneError(
                "silo.hopper_angle",
                "missing: a hopper needs its wall half-angle from the vertical; "
                "allowed: (0, 90) deg",
            )
        two = (s.hopper_angle_upper is not None, s.transition_width is not None)
        if two[0] != two[1]:
            raise SceneError(
                "silo.transition_width",
                "a two-angle hopper needs both silo.hopper_angle_upper and silo.transition_width",
            )
        if s.transition_width is not None and not (s.orifice_width < s.transition_width < s.width):
            raise SceneError(
                "silo.transition_width",
                f"got {s.transition_width:g} m; allowed: > silo.orifice_width "
                f"({s.orifice_width:g} m) and < silo.width ({s.width:g} m)",
            )
        if s.cone_height >= s.height:
            raise SceneError(
                "silo.hopper_angle",
                f"got {s.hopper_angle:g} deg: the cone is {s.cone_height:g} m high, above the "
                f"top of the domain ({s.height:g} m); allowed: a steeper angle or a taller silo",
            )
    elif s.hopper_angle is not None or s.hopper_angle_upper is not None:
        raise SceneError("silo.hopper_angle", "only for silo.shape = 'hopper'")


def _validate_gas(scene: Scene) -> None:
    g, s, m = scene.gas, scene.silo, scene.material
    flows = [k for k in ("q_air", "q_air_lpm", "q_air_scaled") if getattr(g, k) is not None]
    if g.mode == "injection":
        if len(flows) != 1:
            raise SceneError(
                "gas.q_air",
                "injection needs exactly one of gas.q_air [m^3/s], gas.q_air_lpm [L/min], "
                f"gas.q_air_scaled; got {flows or 'none'}",
            )
        if flows[0] == "q_air_scaled" and scene.representation != "planar":
            raise SceneError("gas.q_air_scaled", "only for planar scenes; use gas.q_air")
        if flows[0] != "q_air_scaled" and scene.representation == "planar" and not s.thickness:
            raise SceneError(
                "silo.thickness",
                "missing: a planar scene needs the silo thickness W to turn gas.q_air into a "
                "flow per unit depth (or give gas.q_air_scaled)",
            )
    elif flows:
        raise SceneError(
            f"gas.{flows[0]}",
            f"an air flow is only for gas.mode = 'injection' (got mode {g.mode!r})",
        )
    if g.permeability is not None and g.permeability_scaled is not None:
        raise SceneError(
            "gas.permeability", "give gas.permeability or gas.permeability_scaled, not both"
        )
    for i, y in enumerate(g.taps):
        if y >= s.height:
            raise SceneError(
                f"gas.taps[{i}]", f"got {y:g} m; allowed: > 0 and < silo.height ({s.height:g} m)"
            )
    if g.taps and g.mode == "open-top":
        raise SceneError(
            "gas.taps",
            "an open-top silo has no pore pressure; taps need gas.mode closed-top or injection",
        )
    if m.wall_friction:
        if not s.thickness:
            raise SceneError("material.wall_friction", "needs silo.thickness (the wall gap W)")
        if scene.representation != "planar":
            raise SceneError("material.wall_friction", "only for thin planar silos")


def scene_from_dict(data: dict[str, Any]) -> Scene:
    """Build and validate a :class:`Scene` from a nested dict.

    Raises
    ------
    SceneError
        Naming the offending field and its allowed values.
    """
    scene = _build(Scene, data, "")
    _validate(scene)
    return scene


def parse_override(item: str) -> tuple[list[str], Any]:
    """Parse ``"section.key=value"`` with the value read as a TOML literal."""
    if "=" not in item:
        raise SceneError(item, "override must be of the form section.key=value")
    key, raw = item.split("=", 1)
    key = key.strip()
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()  # a bare word, e.g. representation=planar
    return key.split("."), value


def apply_overrides(data: dict[str, Any], overrides: list[str] | None) -> dict[str, Any]:
    """Return a copy of ``data`` with ``--set`` style overrides applied.

    ``section.key=value`` sets a value (a TOML literal); ``section.key=`` with
    nothing after the ``=`` removes the key, so that its default applies.
    """
    out = copy.deepcopy(data)
    for item in overrides or []:
        path, value = parse_override(item)
        node = out
        for part in path[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise SceneError(".".join(path), "is not a table")
        if value == "":  # "key=" unsets the key (its default applies)
            node.pop(path[-1], None)
        else:
            node[path[-1]] = value
    return out


def load_scene_file(path: str | Path, overrides: list[str] | None = None) -> Scene:
    """Read a scene from a TOML file.

    Parameters
    ----------
    path
        The scene file.
    overrides
        ``section.key=value`` strings applied on top of the file.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SceneError("scene", f"file not found: {path}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError("scene", f"{path} is not valid TOML: {exc}") from None
    return scene_from_dict(apply_overrides(data, overrides))


def preset_names() -> list[str]:
    """Names of the bundled presets."""
    files = resources.files("foamsilo") / "presets"
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def preset_data(name: str) -> dict[str, Any]:
    """Return the raw TOML table of a preset."""
    names = preset_names()
    if name not in names:
        raise SceneError("preset", f"unknown preset {name!r}; allowed: {', '.join(names)}")
    text = (resources.files("foamsilo") / "presets" / f"{name}.toml").read_text()
    return tomllib.loads(text)


def load_preset(name: str, overrides: list[str] | None = None) -> Scene:
    """Load a bundled preset, with optional overrides."""
    return scene_from_dict(apply_overrides(preset_data(name), overrides))


def load_scene(spec: str | Path, overrides: list[str] | None = None) -> Scene:
    """Load a scene from a preset name or a TOML file path."""
    p = Path(spec)
    if p.suffix == ".toml" or p.exists():
        return load_scene_file(p, overrides)
    return load_preset(str(spec), overrides)


def to_toml(data: dict[str, Any]) -> str:
    """Serialise a scene dict to TOML (scalars first, then one table per section)."""

    def fmt(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, float):
            return repr(v)
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(fmt(x) for x in v) + "]"
        return str(v)

    lines = [f"{k} = {fmt(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"\n[{k}]")
            lines += [f"{kk} = {fmt(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def reference_markdown() -> str:
    """Scene-file reference (Markdown), generated from the dataclasses."""
    out = ["# Scene file reference", "", "Generated from `foamsilo/scene.py`. SI units.", ""]

    def table(cls: type, prefix: str) -> None:
        hints = get_type_hints(cls)
        rows = []
        subs = []
        for f in dataclasses.fields(cls):
            typ = hints[f.name]
            if dataclasses.is_dataclass(typ):
                subs.append((typ, f"{prefix}{f.name}"))
                continue
            meta = f.metadata
            if get_origin(typ) is Literal:
                allowed = ", ".join(f"`{a}`" for a in get_args(typ))
            else:
                allowed = _describe_range(meta) or "-"
            if f.default is not dataclasses.MISSING:
                if isinstance(f.default, bool):
                    default = f"`{str(f.default).lower()}`"
                else:
                    default = "-" if f.default in (None, "", ()) else f"`{f.default}`"
            else:
                default = "required"
            rows.append(
                f"| `{f.name}` | {meta.get('unit') or '-'} | {allowed} | {default} "
                f"| {meta.get('description', '')} |"
            )
        title = f"[{prefix[:-1]}]" if prefix else "top level"
        out.extend(
            [
                f"## {title}",
                "",
                "| key | unit | allowed | default | meaning |",
                "| --- | --- | --- | --- | --- |",
                *rows,
                "",
            ]
        )
        for sub, name in subs:
            table(sub, name + ".")

    table(Scene, "")
    return "\n".join(out)
