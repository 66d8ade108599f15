"""Cross-field rules of a scene: what one field's range cannot express.

Each rule raises :class:`~foamsilo.errors.SceneError` naming the field and
what is allowed, given the values of the others.
"""

from __future__ import annotations

import math
import re

from foamsilo.errors import FoamsiloError, SceneError
from foamsilo.scene.model import Scene

#: What a scene name may hold (it names case directories)
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


def validate(scene: Scene) -> None:
    """Raise :class:`SceneError` if the scene breaks a cross-field rule."""
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
    _validate_rheology(scene)
    void = scene.void_density
    if void > 0.1 * m.density:
        raise SceneError(
            "numerics.void_density",
            f"got {void:g} kg/m^3; allowed: > 0 and <= material.density/10 "
            f"({0.1 * m.density:g} kg/m^3): the light phase must stay light beside the grains",
        )
    growth = scene.outer_growth_limit
    if growth and (growth <= 1 or scene.stress_pressure_coupling != "implicit"):
        raise SceneError(
            "numerics.outer_growth_limit",
            f"got {growth:g}: allowed: 0 (never) or > 1 and <= 100, with "
            "numerics.stress_pressure_coupling = 'implicit' (the share it halves); this scene's "
            f"coupling: {scene.stress_pressure_coupling}",
        )
    change = scene.outer_change_limit
    if change and scene.stress_pressure_coupling != "implicit":
        raise SceneError(
            "numerics.outer_change_limit",
            f"got {change:g}: allowed: 0 (never) or > 0 and <= 1, with "
            "numerics.stress_pressure_coupling = 'implicit' (the share it halves); this scene's "
            f"coupling: {scene.stress_pressure_coupling}",
        )
    if m.grain_diameter >= s.orifice_width:
        raise SceneError(
            "material.grain_diameter",
            f"got {m.grain_diameter:g} m; allowed: > 0 and < silo.orifice_width "
            f"({s.orifice_width:g} m)",
        )
    if (me.cells_across is None) == (me.cells_across_orifice is None):
        raise SceneError(
            "mesh.cells_across",
            "give exactly one of mesh.cells_across (cells across L) and "
            "mesh.cells_across_orifice (cells across D)",
        )
    cells_in_orifice = s.orifice_width / scene.cell_size
    if cells_in_orifice < 2 - 1e-9:
        need = math.ceil(2 * s.width / s.orifice_width)
        raise SceneError(
            "mesh.cells_across",
            f"got {scene.cells_across}: the orifice spans {cells_in_orifice:.2f} cells; "
            f"allowed: >= {need} (at least 2 cells across the orifice)",
        )
    centred_bottom = s.orifice_position == "bottom" and s.eccentricity == 0.0
    if me.graded and not (
        (
            centred_bottom
            and (
                (scene.representation in ("planar", "axisymmetric") and s.shape != "hopper")
                or (scene.representation == "3d" and s.shape == "cylindrical")
            )
        )
        or (
            s.orifice_position == "lateral"
            and (
                scene.representation == "planar"
                or (scene.representation == "3d" and s.shape == "cylindrical")
            )
        )
    ):
        raise SceneError(
            "mesh.growth_rate",
            f"got {me.growth_rate:g}: graded meshes are built for flat-bottomed silos with a "
            "centred bottom orifice, planar, axisymmetric or 3D cylinders, and for planar "
            "silos and 3D cylinders with a lateral orifice (this scene: "
            f"{scene.representation}, {s.shape}, {s.orifice_position} orifice"
            f"{', off centre' if s.eccentricity else ''}); allowed here: 1 (uniform)",
        )
    if me.orifice_edge_refinement > 1.0 + 1e-12 and not me.graded:
        raise SceneError(
            "mesh.orifice_edge_refinement",
            f"got {me.orifice_edge_refinement:g}: the orifice's edges are refined on graded "
            "meshes (mesh.growth_rate > 1, which names where they are built; this scene: "
            f"{scene.representation}, growth rate {me.growth_rate:g}); allowed here: 1",
        )
    if me.orifice_exit_refinement > 1.0 + 1e-12 and (
        not me.graded or s.orifice_position != "bottom"
    ):
        raise SceneError(
            "mesh.orifice_exit_refinement",
            f"got {me.orifice_exit_refinement:g}: the exit rows are refined on graded meshes "
            "of a bottom orifice (mesh.growth_rate > 1; this scene: "
            f"{s.orifice_position} orifice, growth rate {me.growth_rate:g}); allowed here: 1",
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
    if s.feeder_flow_rate is not None:
        if scene.gas_coupled:
            raise SceneError(
                "silo.feeder_flow_rate",
                "a feeder with gas coupling is not modelled; allowed with gas.mode 'open-top'",
            )
        if scene.representation == "planar" and not s.thickness:
            raise SceneError(
                "silo.thickness",
                "missing: a planar scene needs the silo thickness W to turn the feeder's "
                "m^3/s into a flow per unit depth",
            )
    if scene.run.write_interval > scene.run.end_time:
        raise SceneError(
            "run.write_interval",
            f"got {scene.run.write_interval:g} s; allowed: > 0 and <= run.end_time "
            f"({scene.run.end_time:g} s)",
        )
    if not _NAME.fullmatch(scene.name):
        raise SceneError(
            "name",
            f"got {scene.name!r}; allowed: ASCII letters, digits, '.', '_' and '-', starting "
            "with a letter or digit (the name becomes a directory OpenFOAM and MPI read)",
        )


def _validate_rheology(scene: Scene) -> None:
    m = scene.material
    if m.rheology == "mu-i":
        for key in ("mu_inf", "regularisation_alpha"):
            if getattr(m, key) is not None:
                raise SceneError(
                    f"material.{key}", "only for material.rheology = 'barker-gray' (got 'mu-i')"
                )
        return
    try:
        m.friction_law.i1  # noqa: B018 - raises where there is no well-posed range
    except FoamsiloError as exc:
        raise SceneError("material.rheology", str(exc)) from None


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
