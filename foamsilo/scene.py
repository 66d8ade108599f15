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
    """Geometry of the silo and its orifice."""

    width: float = _f("silo width L (inner, wall to wall)", "m", gt=0)
    height: float = _f("silo height H, bottom to the open top of the domain", "m", gt=0)
    fill_height: float = _f("initial height of the granular column", "m", gt=0)
    orifice_width: float = _f("orifice width D (slot width in a planar silo)", "m", gt=0)
    shape: Literal["rectangular"] = _f("cross-section of the silo", default="rectangular")
    orifice_position: Literal["bottom"] = _f("where the orifice is", default="bottom")
    thickness: float | None = _f(
        "thickness W of a thin (quasi-2D) planar silo; needed for wall friction and to turn "
        "an air flow in m^3/s into a flow per unit depth",
        "m",
        gt=0,
        default=None,
    )


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
    cache_gradients: bool = _f(
        "compute grad(U) once per step for the rheology and the stress", default=True
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
        # A rectangular silo with a bottom slot is the planar silo of Zhou III.B
        return "planar"

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
    if s.orifice_width >= s.width:
        raise SceneError(
            "silo.orifice_width",
            f"got {s.orifice_width:g} m; allowed: > 0 and < silo.width ({s.width:g} m)",
        )
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
    if scene.representation != "planar":
        raise SceneError(
            "mesh.representation",
            f"got {me.representation!r}; a rectangular silo with a bottom slot is "
            "meshed planar; allowed: 'auto', 'planar'",
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
                    default = "-" if f.default in (None, "") else f"`{f.default}`"
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
