"""gmsh silo meshes, converted to OpenFOAM polyMeshes and checked.

The layout (:mod:`~foamsilo.mesh.layout`: rows, labelled profile blocks,
O-grids; no gmsh) decides where the cells go and which patch each side of
the shape is on; the builders make the gmsh geometry from it and name the
patches as they build it: :mod:`~foamsilo.mesh.profile` (planar and
axisymmetric, one pipeline), :mod:`~foamsilo.mesh.solid` (3D);
:mod:`~foamsilo.mesh.gmsh_model` runs them in a child process and writes
the ``.msh``; :mod:`~foamsilo.mesh.convert` turns it into a checked polyMesh.
"""

from foamsilo.mesh.convert import MSH_NAME, MeshResult, mesh_case
from foamsilo.mesh.layout import (
    OGrid,
    ProfileLayout,
    Row,
    cells_estimate,
    o_grid_floored,
    ogrid_for,
    profile_layout,
    slot_divisions,
    top_cell_ratio,
    vertical_rows,
)
from foamsilo.mesh.patches import PATCH_TYPES, patch_order

__all__ = [
    "MSH_NAME",
    "PATCH_TYPES",
    "MeshResult",
    "OGrid",
    "ProfileLayout",
    "Row",
    "cells_estimate",
    "mesh_case",
    "o_grid_floored",
    "ogrid_for",
    "patch_order",
    "profile_layout",
    "slot_divisions",
    "top_cell_ratio",
    "vertical_rows",
]
