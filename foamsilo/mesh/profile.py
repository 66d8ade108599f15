"""Planar and axisymmetric meshes: a profile of quad blocks, one cell thick.

The one 2D pipeline: the blocks of :func:`foamsilo.mesh.layout.profile_layout`
(row by row, each side labelled with its patch) become gmsh quads, glued by
a fragment, meshed as transfinite quads, then extruded one cell thick
(planar) or revolved through ``WEDGE_ANGLE_DEG`` about the y axis
(axisymmetric, symmetric about z = 0). Each boundary face gets the patch of
the block side it was swept from, the swept-from faces are ``frontAndBack``
(planar) or ``back`` (wedge), the swept-to ones ``frontAndBack`` or ``front``.
"""

from __future__ import annotations

import math
from pathlib import Path

import gmsh

from foamsilo.mesh.gmsh_model import Session
from foamsilo.mesh.layout import AXIS, Block, profile_layout
from foamsilo.mesh.patches import patch_order
from foamsilo.scene import WEDGE_ANGLE_DEG, Scene


def _side_of(block: Block, a: tuple[float, float], b: tuple[float, float], tol: float) -> int:
    """Which side (0 bottom, 1 right, 2 top, 3 left) of ``block`` joins points a and b."""

    def near(p: tuple[float, float], q: tuple[float, float]) -> bool:
        return abs(p[0] - q[0]) < tol and abs(p[1] - q[1]) < tol

    c = block.corners
    for k in range(4):
        p, q = c[k], c[(k + 1) % 4]
        if (near(a, p) and near(b, q)) or (near(a, q) and near(b, p)):
            return k
    raise ValueError(f"curve {a} - {b} is no side of the block with corners {c}")


def build_profile(scene: Scene, msh_file: Path, dump_geometry: Path | None = None) -> int:
    """Mesh a planar or axisymmetric profile into ``msh_file``; return the cell count.

    Raises
    ------
    MeshError
        gmsh failed, or the glued blocks do not have the sides laid out (the
        geometry is written beside the mesh).
    """
    layout = profile_layout(scene)
    planar = scene.representation == "planar"
    tol = 1e-3 * scene.cell_size
    # an axisymmetric profile lies in the plane at -WEDGE_ANGLE_DEG/2 and is
    # revolved through the wedge (a rotation about +y by -a turns +x to +z)
    half = 0.0 if planar else math.radians(WEDGE_ANGLE_DEG) / 2
    ca, sa = math.cos(half), math.sin(half)

    def to_profile_plane(p: tuple[float, ...]) -> tuple[float, float]:
        """(x, y) in the profile plane of a point of the (rotated) model."""
        return (p[0] / ca if ca else p[0]), p[1]

    with Session("profile", msh_file) as s:
        occ = s.occ
        inputs = []
        for block in layout.blocks:
            pts = [occ.addPoint(ca * x, y, -sa * x) for x, y in block.corners]
            lines = [occ.addLine(pts[k], pts[(k + 1) % 4]) for k in range(4)]
            inputs.append(occ.addPlaneSurface([occ.addCurveLoop(lines)]))
        _, mapping = occ.fragment([(2, inputs[0])], [(2, t) for t in inputs[1:]])
        occ.synchronize()
        surfaces = []
        for out in mapping:
            if len(out) != 1:
                raise s.fail(f"a profile block was cut into {len(out)} faces by its neighbours")
            surfaces.append(out[0][1])
        # each curve: cells, growth and patch from the side of the block it bounds
        label: dict[int, str | None] = {}
        for block, surf in zip(layout.blocks, surfaces, strict=True):
            for c in s.boundary(2, surf):
                a, b = (to_profile_plane(p) for p in s.curve_ends(c))
                try:
                    k = _side_of(block, a, b, tol)
                except ValueError as exc:
                    raise s.fail(str(exc)) from None
                if k in (0, 2):  # the cells grow towards +x: invert on a curve going -x
                    r = block.x_ratio if b[0] > a[0] else 1.0 / block.x_ratio
                    s.transfinite(c, block.cells[0], r)
                else:  # the cells grow upward: invert the ratio on a downward curve
                    r = block.ratio if b[1] > a[1] else 1.0 / block.ratio
                    s.transfinite(c, block.cells[1], r)
                if label.get(c) is None:
                    label[c] = block.sides[k]
        for t in sorted(surfaces):
            gmsh.model.mesh.setTransfiniteSurface(t)
            gmsh.model.mesh.setRecombine(2, t)
        base = sorted(surfaces)
        if planar:
            ext = occ.extrude(
                [(2, t) for t in base], 0, 0, scene.cell_size, numElements=[1], recombine=True
            )
        else:
            ext = occ.revolve(
                [(2, t) for t in base],
                0,
                0,
                0,
                0,
                1,
                0,
                -2 * half,
                numElements=[1],
                recombine=True,
            )
        occ.synchronize()
        # extrude returns, per base surface: the swept-to face, the volume, the sides
        tops = [ext[k - 1][1] for k in range(1, len(ext)) if ext[k][0] == 3]
        swept = {t for d, t in ext if d == 2} - set(tops)
        s.add_patch("frontAndBack" if planar else "back", base)
        s.add_patch("frontAndBack" if planar else "front", tops)
        for c, name in label.items():
            if name is None or name == AXIS:
                continue
            faces = [f for f in swept if c in s.boundary(2, f)]
            if len(faces) != 1:
                raise s.fail(f"the {name} curve {c} was swept into {len(faces)} faces")
            s.add_patch(name, faces)
        s.write(patch_order(scene.representation), dump_geometry)
    return layout.n_cells
