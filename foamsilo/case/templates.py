"""The case's dictionaries: jinja2 templates rendered from the scene.

A scene gets only the templates it needs (:func:`template_list`): no
pore-pressure field, dictionary or zone for a dry silo, no wall-friction
dictionary outside quasi-2D scenes, no ``decomposeParDict`` for a serial run.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import jinja2

from foamsilo import __version__
from foamsilo.resources import templates_dir
from foamsilo.scene import Scene
from foamsilo.solver import SOLVER_NAME

#: siloFoam takes a step again (half the step) when its volume fraction leaves
#: [-this, 1 + this] within the outer iterations: MULES keeps it within ~1e-6
#: of [0, 1], so this far out is a blow-up, not an overshoot
RETAKE_ALPHA_EXCURSION = 0.5
#: ... or when the step ends with a Courant number this many times its limit
#: (the controller never grows the step by more than 1.2 per step)
RETAKE_COURANT_FACTOR = 20.0
#: The start-up, in discharge times sqrt(D/g): the steady window's
#: (``foamsilo.post.steady.START``). No retake in it for a scene that iterates
#: each step: a failed step there is the mu(I) Picard iteration not converging
#: along the start-up's path, which a retake does not cure (the start-up then
#: crawls at small steps); the runner's recovery iterates the start-up again
#: from the last written time. And its steps may take their own face mean of
#: the viscosity (``numerics.start_up_viscosity_interpolation``; docs/solver.md)
START_UP = 1.0
#: The solver's retakes (``run.max_step_retakes``) are counted over this many
#: discharge times, not per step: a retake that fixes the failed step but
#: leaves a field it cannot heal fails the steps after it, each retaken at a
#: smaller step (the 3D thin lateral silo crawled on at 1/100 of its step);
#: past the budget the run stops and the runner restarts it from the last
#: written time with its step capped (docs/solver.md)
RETAKE_WINDOW = 1.0

#: Templates every case gets, by representation (a scene gets what it needs)
_COMMON = [
    "system/controlDict",
    "system/fvSchemes",
    "system/fvSolution",
    "system/setAlphaFieldDict",
    "constant/transportProperties",
    "constant/g",
    "constant/hRef",
    "constant/turbulenceProperties",
    "0/U",
    "0/p_rgh",
    "0/alpha.granular",
]


def _foam_number(value: Any) -> str:
    """Format a number for an OpenFOAM dictionary (round-trip precision)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    return f"{float(value):.10g}"


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )
    env.filters["foam"] = _foam_number
    return env


def template_context(scene: Scene) -> dict[str, Any]:
    """Values the templates see: the scene sections plus derived numbers."""
    rep = scene.representation
    depth = scene.cell_size if rep == "planar" else 1.0
    constraint = {
        "planar": [("frontAndBack", "empty")],
        "axisymmetric": [("front", "wedge"), ("back", "wedge")],
        "3d": [],
    }[rep]
    s = scene.silo
    # the orifice's centre on the floor (the probes' axis and the zone's centre)
    if rep == "planar" or s.shape == "rectangular":
        x_axis = s.width / 2
    elif rep == "axisymmetric":
        x_axis = 0.25 * scene.cell_size  # just off the (degenerate) axis
    else:
        x_axis = s.eccentricity
    H, D = scene.silo.height, scene.silo.orifice_width
    n_probes = 50
    return {
        "version": __version__,
        "scene": scene,
        "silo": scene.silo,
        "material": scene.material,
        "air": scene.air,
        "mesh": scene.mesh,
        "run": scene.run,
        "numerics": scene.numerics,
        "gravity": scene.gravity,
        "representation": rep,
        "solver": SOLVER_NAME,
        "eta_max": scene.eta_max,
        "p_min": scene.p_min,
        "nu_air": scene.air.viscosity / scene.void_density,
        "constraint_patches": constraint,
        "axis_x": x_axis,
        "mid_depth": 0.5 * depth
        if rep == "planar"
        else (s.thickness or 0.0) / 2
        if s.shape == "rectangular"
        else 0.0,
        # A start step far below the Courant limit; the controller grows it
        "initial_delta_t": 1e-3 * scene.cell_size / (scene.gravity * scene.silo.width) ** 0.5,
        "n_non_orthogonal_correctors": 0,
        # gas coupling
        "permeability": scene.permeability,
        "inertial_permeability": scene.inertial_permeability,
        # the flow into the mesh: per unit depth times the cell thickness
        # (planar), the wedge's share (axisymmetric), all of it (3D)
        "injection_flux": scene.q_air_per_depth * depth
        if rep == "planar"
        else scene.q_air * scene.mesh_fraction,
        # taps on the axis: dense over the first D, then up to the top
        # (and the scene's own taps)
        "axis_probes": sorted(
            {D * (k + 0.5) / 20 for k in range(20)}
            | {D + (H - D) * (k + 0.5) / n_probes for k in range(n_probes)}
            | set(scene.gas.taps)
        ),
        "friction_velocity": 1e-3 * (scene.gravity * scene.silo.width) ** 0.5,
        # the grains' volume on this mesh (a wedge, a unit-depth slab) at the
        # emptied height: the solver ends the run below it
        "stop_granular_volume": (
            scene.emptied_height * scene.cross_section_area * scene.mesh_fraction
            if scene.run.stop_when_empty
            else 0.0
        ),
        "friction_relaxation": scene.numerics.friction_relaxation,
        "retake_alpha_excursion": RETAKE_ALPHA_EXCURSION,
        "retake_courant_factor": RETAKE_COURANT_FACTOR,
        "retake_window": RETAKE_WINDOW * scene.discharge_time_scale,
        "retake_from": START_UP * scene.discharge_time_scale if scene.outer_correctors > 1 else 0.0,
        "start_up_end": START_UP * scene.discharge_time_scale,
    }


def template_list(scene: Scene) -> list[str]:
    """Templates (relative to ``templates/``, without ``.j2``) the scene needs."""
    names = list(_COMMON)
    if scene.run.n_procs > 1:
        names.append("system/decomposeParDict")
    if scene.gas_coupled:
        names += ["0/pf", "constant/porePressureProperties", "system/topoSetDict"]
    if scene.wall_friction:
        names.append("constant/wallFrictionProperties")
    return names


def decompose_dict(scene: Scene, n_procs: int) -> str:
    """``system/decomposeParDict`` for ``n_procs`` ranks (whatever the scene's run.n_procs)."""
    ctx = template_context(scene)
    ctx["run"] = dataclasses.replace(scene.run, n_procs=n_procs)
    name = "system/decomposeParDict.j2"
    return _environment().get_template(name).render(template_name=name, **ctx)


def render_template(name: str, scene: Scene, case: Path, **extra: Any) -> Path:
    """Render one template (``system/blockMeshDict``) into ``case`` with more values."""
    ctx = {**template_context(scene), **extra}
    text = _environment().get_template(f"{name}.j2").render(template_name=f"{name}.j2", **ctx)
    out = case / name
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    return out


def render_templates(scene: Scene, case: Path) -> list[str]:
    """Render the scene's templates into ``case``; return the files written."""
    env = _environment()
    ctx = template_context(scene)
    written = []
    for name in template_list(scene):
        text = env.get_template(f"{name}.j2").render(template_name=f"{name}.j2", **ctx)
        out = case / name
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)
        written.append(name)
    return written
