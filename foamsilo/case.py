"""Write an OpenFOAM case for a scene: dictionaries, mesh and initial fill.

The case is assembled in a temporary directory beside the target and
renamed into place only when complete, so a failure (a bad value caught
late, gmsh, checkMesh) leaves nothing half-written behind.  A case is a
normal OpenFOAM case: ``siloFoam`` runs in it by hand, ParaView opens
``case.foam``, and ``scene.toml`` holds the scene it came from.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jinja2

from foamsilo import __version__
from foamsilo.errors import FoamsiloError, MeshError
from foamsilo.foam import run_utility, set_alpha_field
from foamsilo.mesh import MeshResult, mesh_case
from foamsilo.scene import Scene, to_toml
from foamsilo.solver import SOLVER_NAME
from foamsilo.toolchain import OpenFOAM, repo_root

GRANULAR_PHASE = "granular"
METADATA_FILE = "foamsilo.json"
SCENE_FILE = "scene.toml"

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


def templates_dir() -> Path:
    """Return the ``templates/`` directory of the checkout."""
    return repo_root() / "templates"


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
        "nu_air": scene.air.viscosity / scene.air.density,
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
        "friction_relaxation": scene.numerics.friction_relaxation,
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


@dataclass
class Case:
    """A written case.

    Attributes
    ----------
    path
        The case directory.
    scene
        The scene it was made from.
    representation
        ``planar``, ``axisymmetric`` or ``3d``.
    files
        Every file written, relative to ``path``.
    mesh
        Meshing result (cells, checkMesh figures).
    """

    path: Path
    scene: Scene
    representation: str
    files: list[str] = field(default_factory=list)
    mesh: MeshResult | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        return {
            "case_dir": str(self.path),
            "representation": self.representation,
            "files": self.files,
            "mesh": self.mesh.as_dict() if self.mesh else None,
        }


def write_whole(path: Path, text: str) -> None:
    """Write a file whole or not at all (a temporary file, then a rename)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def scene_digest(scene: Scene) -> str:
    """Stable hash of a scene's values (to tell whether a case matches it)."""
    return hashlib.sha256(json.dumps(scene.to_dict(), sort_keys=True).encode()).hexdigest()[:16]


def _list_files(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())


def create_case(
    scene: Scene,
    case_dir: Path,
    of: OpenFOAM,
    *,
    overwrite: bool = False,
    scene_text: str | None = None,
    dump_geometry: Path | None = None,
) -> Case:
    """Write a complete, runnable case for ``scene`` at ``case_dir``.

    Parameters
    ----------
    scene
        The validated scene.
    case_dir
        Target directory; must not exist (or be empty) unless ``overwrite``.
    of
        OpenFOAM to run the mesh utilities with.
    overwrite
        Replace an existing case.
    scene_text
        Text of the scene file it came from (copied into the case); by
        default the validated scene is written.
    dump_geometry
        Also write the gmsh geometry there.

    Raises
    ------
    FoamsiloError
        The target exists; or meshing or an OpenFOAM utility failed (the
        geometry is then kept beside the target for inspection).
    """
    case_dir = Path(case_dir).resolve()
    if case_dir.exists() and any(case_dir.iterdir()) and not overwrite:
        raise FoamsiloError(f"{case_dir} exists and is not empty (use --overwrite to replace it)")
    case_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{case_dir.name}.tmp-", dir=case_dir.parent))
    tmp.chmod(0o755)  # mkdtemp makes it private
    try:
        render_templates(scene, tmp)
        (tmp / SCENE_FILE).write_text(
            scene_text if scene_text is not None else to_toml(scene.to_dict())
        )
        (tmp / "case.foam").touch()
        try:
            mesh = mesh_case(scene, tmp, of, dump_geometry)
        except MeshError as exc:
            if exc.geometry_file and exc.geometry_file.exists():
                kept = case_dir.parent / f"{case_dir.name}.failed{exc.geometry_file.suffix}"
                shutil.copy(exc.geometry_file, kept)
                exc.geometry_file = kept
                exc.args = (
                    f"{exc.args[0].split(' (geometry written')[0]} (geometry written to {kept})",
                )
            raise
        shutil.copytree(tmp / "0", tmp / "0.orig")  # pristine fields, before the fill
        set_alpha_field(of, tmp)
        if scene.gas_coupled:
            run_utility(of, tmp, "topoSet")  # the zone the pore-pressure gradient is averaged on
        meta = {
            "foamsilo_version": __version__,
            "scene": scene.name,
            "scene_digest": scene_digest(scene),
            "representation": scene.representation,
            "cells": mesh.cells,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
        }
        (tmp / METADATA_FILE).write_text(json.dumps(meta, indent=2))
        if case_dir.exists():
            shutil.rmtree(case_dir)
        tmp.rename(case_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    mesh.msh_file = case_dir / mesh.msh_file.relative_to(tmp)
    return Case(case_dir, scene, scene.representation, _list_files(case_dir), mesh)


def read_metadata(case_dir: Path) -> dict[str, Any]:
    """Return the ``foamsilo.json`` metadata of a case."""
    path = Path(case_dir) / METADATA_FILE
    if not path.exists():
        raise FoamsiloError(f"{case_dir} is not a foamsilo case (no {METADATA_FILE})")
    return json.loads(path.read_text())
