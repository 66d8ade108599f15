"""From a scene to a checked OpenFOAM mesh: gmsh, gmshToFoam, patch types, checkMesh."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from foamsilo.errors import MeshError
from foamsilo.foam import CheckMeshResult, check_mesh, gmsh_to_foam, set_patch_types
from foamsilo.mesh.gmsh_model import build_isolated
from foamsilo.mesh.patches import PATCH_TYPES
from foamsilo.scene import Scene
from foamsilo.toolchain import OpenFOAM

#: The gmsh mesh, kept in the case beside polyMesh
MSH_NAME = "silo.msh"


@dataclass
class MeshResult:
    """A meshed case.

    Attributes
    ----------
    representation
        ``planar``, ``axisymmetric`` or ``3d``.
    cells
        Number of cells.
    check
        checkMesh verdict and figures.
    msh_file
        The gmsh mesh.
    seconds
        Wall time of meshing and conversion.
    cell_kind
        ``hexahedral`` or the fall-back used.
    timings
        Seconds spent in gmsh, gmshToFoam and checkMesh.
    """

    representation: str
    cells: int
    check: CheckMeshResult
    msh_file: Path
    seconds: float
    cell_kind: str = "hexahedral"
    timings: dict[str, float] | None = None

    def as_dict(self) -> dict[str, object]:
        """JSON-friendly form."""
        return {
            "representation": self.representation,
            "cells": self.cells,
            "cell_kind": self.cell_kind,
            "checkMesh": self.check.as_dict(),
            "msh_file": str(self.msh_file),
            "seconds": round(self.seconds, 3),
            "timings_s": {k: round(v, 3) for k, v in (self.timings or {}).items()},
        }


def _build(scene: Scene, msh: Path, dump_geometry: Path | None) -> tuple[int | None, str]:
    """Write the gmsh mesh of ``scene`` (run in the meshing child process)."""
    if scene.representation in ("planar", "axisymmetric"):
        from foamsilo.mesh.profile import build_profile

        kind = (
            "hexahedral (prisms on the axis)"
            if scene.representation == "axisymmetric"
            else ("hexahedral")
        )
        return build_profile(scene, msh, dump_geometry), kind
    from foamsilo.mesh.solid import build_3d

    return build_3d(scene, msh, dump_geometry)


def mesh_case(
    scene: Scene, case: Path, of: OpenFOAM, dump_geometry: Path | None = None
) -> MeshResult:
    """Mesh ``scene`` into ``case/constant/polyMesh`` and check it.

    The representation is the scene's (``auto`` resolved: the cheapest that
    is faithful to it).

    Raises
    ------
    MeshError
        If gmsh fails or checkMesh finds the mesh unusable.
    KeyboardInterrupt
        Ctrl-C during meshing (the meshing process is already gone).
    """
    t0 = time.perf_counter()
    rep = scene.representation
    msh = Path(case) / "constant" / MSH_NAME
    msh.parent.mkdir(parents=True, exist_ok=True)
    expected, kind = build_isolated(_build, scene, msh, dump_geometry)
    t1 = time.perf_counter()
    gmsh_to_foam(of, case, msh)
    set_patch_types(case, PATCH_TYPES[rep])
    t2 = time.perf_counter()
    check = check_mesh(of, case)
    t3 = time.perf_counter()
    if not check.ok:
        raise MeshError("checkMesh failed: " + "; ".join(check.failed_checks), msh)
    if expected is not None and check.cells != expected:
        raise MeshError(f"expected {expected} cells, checkMesh found {check.cells}", msh)
    timings = {"gmsh": t1 - t0, "gmshToFoam": t2 - t1, "checkMesh": t3 - t2}
    return MeshResult(rep, check.cells, check, msh, t3 - t0, kind, timings)
