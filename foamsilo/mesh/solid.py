"""3D meshes: a labelled cross-section swept up through the rows of cells.

A cross-section in the plane y = 0 (an O-grid for a cylinder or a hopper,
transfinite blocks for a box, a quad-dominant disk for an eccentric outlet)
is built with each floor face labelled ``orifice`` or ``walls`` and each
curve of its rim labelled as wall or as part of a lateral orifice. It is
extruded row by row (:func:`foamsilo.mesh.layout.vertical_rows`); the face
swept from a rim curve in a row is ``walls``, or ``orifice`` where the curve
belongs to a lateral orifice and the row lies inside it. A hopper is meshed
as its cylinder and its nodes are then moved radially onto the cone. A
circular hole in a cylinder's wall is the band it spans, swept as orifice,
with the faces outside its circle given back to the wall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import gmsh
import numpy as np

from foamsilo.mesh.gmsh_model import Carve, Session
from foamsilo.mesh.layout import (
    ATMOSPHERE,
    COARSE_RATIO_3D,
    ORIFICE,
    WALLS,
    OGrid,
    Row,
    ogrid_for,
    slot_divisions,
    vertical_rows,
)
from foamsilo.mesh.patches import patch_order
from foamsilo.scene import Scene

#: Label of a rim curve that is part of a lateral orifice
LATERAL = "lateral-orifice"


@dataclass
class Section:
    """A cross-section (plane y = 0): its faces, their floor patch, its labelled rim."""

    floor: dict[int, str] = field(default_factory=dict)
    rim: dict[int, str] = field(default_factory=dict)

    @property
    def surfaces(self) -> list[int]:
        """The faces, in the order they were made."""
        return list(self.floor)


def _xz(p: tuple[float, float]) -> tuple[float, float, float]:
    """Cross-section point (x, z) in 3D, in the plane y = 0."""
    return p[0], 0.0, p[1]


def _ogrid_section(s: Session, og: OGrid) -> Section:
    """Make the O-grid cross-section with its transfinite settings."""
    occ = s.occ
    centre = occ.addPoint(0, 0, 0)

    def pt(r: float, a: float) -> tuple[float, float]:
        return r * math.cos(a), r * math.sin(a)

    # angular break points around the circle, in order
    angles: list[float] = []
    counts: list[int] = []
    for quad in og.arcs:
        for a0, _, n in quad:
            angles.append(a0)
            counts.append(n)
    corner_angles = {og.arcs[k][0][0] for k in range(4)}
    s_half = og.square * og.rings[0] / math.sqrt(2)

    def square_pt(a: float) -> tuple[float, float]:
        # point of the square's edge on the ray at angle a
        c, s_ = math.cos(a), math.sin(a)
        t = s_half / max(abs(c), abs(s_))
        return t * c, t * s_

    sq_pts = [occ.addPoint(*_xz(square_pt(a))) for a in angles]
    ring_pts = [[occ.addPoint(*_xz(pt(r, a))) for a in angles] for r in og.rings]
    m = len(angles)
    sq_lines = [occ.addLine(sq_pts[i], sq_pts[(i + 1) % m]) for i in range(m)]
    arcs = [
        [occ.addCircleArc(ring_pts[k][i], centre, ring_pts[k][(i + 1) % m]) for i in range(m)]
        for k in range(len(og.rings))
    ]
    inner = [sq_pts] + ring_pts[:-1]
    radial = [
        [occ.addLine(inner[k][i], ring_pts[k][i]) for i in range(m)] for k in range(len(og.rings))
    ]
    section = Section()
    square = occ.addPlaneSurface([occ.addCurveLoop(sq_lines)])
    section.floor[square] = ORIFICE if og.orifice_rings > 0 else WALLS
    ring_surfs = []
    for k in range(len(og.rings)):
        inner_lines = sq_lines if k == 0 else arcs[k - 1]
        for i in range(m):
            lp = occ.addCurveLoop(
                [inner_lines[i], radial[k][(i + 1) % m], arcs[k][i], radial[k][i]]
            )
            t = occ.addPlaneSurface([lp])
            ring_surfs.append(t)
            section.floor[t] = ORIFICE if k < og.orifice_rings else WALLS
    occ.remove([(0, centre)])
    occ.synchronize()
    for i in range(m):
        s.transfinite(sq_lines[i], counts[i])
        for k in range(len(og.rings)):
            s.transfinite(arcs[k][i], counts[i])
            n, g = og.ring_cells[k]
            s.transfinite(radial[k][i], n, g)
    corners = [sq_pts[i] for i, a in enumerate(angles) if a in corner_angles]
    gmsh.model.mesh.setTransfiniteSurface(square, "Left", corners)
    for t in ring_surfs:
        gmsh.model.mesh.setTransfiniteSurface(t)
    for t in section.surfaces:
        gmsh.model.mesh.setRecombine(2, t)
    # the rim: the outer ring's arcs; a lateral orifice spans one angular segment
    segments = [(a0, a1) for quad in og.arcs for a0, a1, _ in quad]
    for i, arc in enumerate(arcs[-1]):
        section.rim[arc] = LATERAL if og.lateral_arc == segments[i] else WALLS
    return section


def _block_grid(
    s: Session,
    P: list[list[int]],
    cols: list[tuple[int, float]],
    rows: list[tuple[int, float]],
) -> tuple[list[list[int]], list[list[int]], list[list[int]]]:
    """Transfinite quad blocks between the points P[i][j] (straight edges).

    ``cols[i]`` and ``rows[j]`` give the cells and growth ratio of block
    column i (along the first index) and block row j (along the second).
    Returns the surfaces S[i][j] and the lines A[i][j] (P[i][j] to P[i+1][j])
    and B[i][j] (P[i][j] to P[i][j+1]).
    """
    occ = s.occ
    ni, nj = len(P), len(P[0])
    A = [[occ.addLine(P[i][j], P[i + 1][j]) for j in range(nj)] for i in range(ni - 1)]
    B = [[occ.addLine(P[i][j], P[i][j + 1]) for j in range(nj - 1)] for i in range(ni)]
    S = [
        [
            occ.addPlaneSurface([occ.addCurveLoop([A[i][j], B[i + 1][j], A[i][j + 1], B[i][j]])])
            for j in range(nj - 1)
        ]
        for i in range(ni - 1)
    ]
    occ.synchronize()
    for i in range(ni - 1):
        for j in range(nj):
            s.transfinite(A[i][j], *cols[i])
    for i in range(ni):
        for j in range(nj - 1):
            s.transfinite(B[i][j], *rows[j])
    for row in S:
        for t in row:
            gmsh.model.mesh.setTransfiniteSurface(t)
            gmsh.model.mesh.setRecombine(2, t)
    return S, A, B


def _box_section(s: Session, scene: Scene) -> tuple[Section, int]:
    """Transfinite blocks of a rectangular silo's cross-section (x-z plane)."""
    sil = scene.silo
    h = scene.cell_size
    L = sil.width
    assert sil.thickness is not None
    W = sil.thickness
    ol = sil.orifice_length if sil.orifice_length is not None else W
    bottom = sil.orifice_position == "bottom"
    if bottom:
        n_l, n_o, n_r = slot_divisions(L, sil.orifice_width, scene.cells_across)
        xs, nx = [0.0, (L - sil.orifice_width) / 2, (L + sil.orifice_width) / 2, L], [n_l, n_o, n_r]
    else:
        xs, nx = [0.0, L], [scene.cells_across]
    split = ol < W - 1e-12
    zs = [0.0, (W - ol) / 2, (W + ol) / 2, W] if split else [0.0, W]
    nz = [
        max(2 if len(zs) == 2 else 1, round((b - a) / h))
        for a, b in zip(zs[:-1], zs[1:], strict=True)
    ]
    P = [[s.occ.addPoint(x, 0, z) for z in zs] for x in xs]
    S, A, B = _block_grid(s, P, [(n, 1.0) for n in nx], [(n, 1.0) for n in nz])
    section = Section()
    mid_z = {1} if split else set(range(len(zs) - 1))
    for i, col in enumerate(S):
        for j, t in enumerate(col):
            section.floor[t] = ORIFICE if bottom and i == 1 and j in mid_z else WALLS
    last = len(xs) - 1
    for i in range(len(xs) - 1):  # the walls at z = 0 and z = W
        section.rim[A[i][0]] = WALLS
        section.rim[A[i][-1]] = WALLS
    for j in range(len(zs) - 1):  # the walls at x = 0 and x = L
        section.rim[B[0][j]] = WALLS
        section.rim[B[last][j]] = LATERAL if not bottom and j in mid_z else WALLS
    return section, sum(nx) * sum(nz)


def _free_section(s: Session, scene: Scene) -> Section:
    """Quad-dominant cross-section of a cylinder with an eccentric orifice."""
    sil = scene.silo
    occ = s.occ
    h = scene.cell_size
    R, r = sil.width / 2, sil.orifice_width / 2
    disk = occ.addDisk(0, 0, 0, R, R)
    hole = occ.addDisk(sil.eccentricity, 0, 0, r, r)
    _, mapping = occ.fragment([(2, disk)], [(2, hole)])
    occ.rotate(occ.getEntities(2), 0, 0, 0, 1, 0, 0, math.pi / 2)  # x-y plane to x-z
    occ.synchronize()
    holes = {t for _, t in mapping[1]}
    section = Section()
    for _, t in gmsh.model.getEntities(2):
        section.floor[t] = ORIFICE if t in holes else WALLS
    hole_edge = sorted({c for t in holes for c in s.boundary(2, t)})
    rim = [t for _, t in gmsh.model.getBoundary([(2, t) for t in section.surfaces], combined=True)]
    for c in rim:
        section.rim[abs(c)] = WALLS
    f = gmsh.model.mesh.field
    dist = f.add("Distance")
    f.setNumbers(dist, "CurvesList", hole_edge)
    f.setNumber(dist, "Sampling", 200)
    thr = f.add("Threshold")
    f.setNumber(thr, "InField", dist)
    f.setNumber(thr, "SizeMin", h)
    f.setNumber(thr, "SizeMax", COARSE_RATIO_3D * h)
    f.setNumber(thr, "DistMin", 0.5 * r)
    f.setNumber(thr, "DistMax", max(2 * r, 0.5 * R))
    f.setAsBackgroundMesh(thr)
    for opt, val in (
        ("Mesh.MeshSizeExtendFromBoundary", 0),
        ("Mesh.MeshSizeFromPoints", 0),
        ("Mesh.MeshSizeFromCurvature", 0),
        ("Mesh.Algorithm", 8),  # frontal-Delaunay for quads
        ("Mesh.RecombinationAlgorithm", 1),  # blossom: all quads where it can
    ):
        gmsh.option.setNumber(opt, val)
    for c in hole_edge:  # a 24-gon at least: 98.9% of the disk's area
        gmsh.model.mesh.setTransfiniteCurve(c, max(24, math.ceil(2 * math.pi * r / h)) + 1)
    for t in section.surfaces:
        gmsh.model.mesh.setRecombine(2, t)
    return section


def _sweep(s: Session, section: Section, rows: list[Row], band: tuple[float, float] | None) -> None:
    """Extrude the section up through the rows and record every boundary face's patch.

    ``band`` is the height range of a lateral orifice: there the faces swept
    from ``LATERAL`` rim curves are the orifice.
    """
    occ = s.occ
    for t, patch in section.floor.items():
        s.add_patch(patch, [t])
    base = [(2, t) for t in section.surfaces]
    sweeps: list[tuple[Row, list[tuple[int, int]]]] = []
    for row in rows:
        ext = occ.extrude(
            base,
            0,
            row.y1 - row.y0,
            0,
            numElements=[1] * row.n,
            heights=row.heights(),
            recombine=True,
        )
        sweeps.append((row, ext))
        base = [ext[k - 1] for k in range(1, len(ext)) if ext[k][0] == 3]
    occ.synchronize()
    rim = dict(section.rim)
    for row, ext in sweeps:
        tops = {ext[k - 1][1] for k in range(1, len(ext)) if ext[k][0] == 3}
        sides = {t for d, t in ext if d == 2} - tops
        faces_of: dict[int, list[int]] = {}
        for f in sides:
            for c in s.boundary(2, f):
                faces_of.setdefault(c, []).append(f)
        top_curves = {c for t in tops for c in s.boundary(2, t)}
        inside = band is not None and row.y0 >= band[0] - 1e-12 and row.y1 <= band[1] + 1e-12
        swept_rim: dict[int, str] = {}
        for c, label in rim.items():
            faces = faces_of.get(c, [])
            if len(faces) != 1:
                raise s.fail(f"the rim curve {c} was swept into {len(faces)} faces")
            face = faces[0]
            s.add_patch(ORIFICE if label == LATERAL and inside else WALLS, [face])
            up = [k for k in s.boundary(2, face) if k in top_curves]
            if len(up) != 1:
                raise s.fail(f"the face swept from rim curve {c} meets {len(up)} top curves")
            swept_rim[up[0]] = label
        rim = swept_rim
    s.add_patch(ATMOSPHERE, [t for _, t in base])


def build_3d(
    scene: Scene, msh_file: Path, dump_geometry: Path | None = None
) -> tuple[int | None, str]:
    """Mesh a 3D silo into ``msh_file``.

    Returns
    -------
    tuple
        The number of cells (None when unstructured) and the kind of cells.
    """
    sil = scene.silo
    order = patch_order("3d")
    with Session("silo3d", msh_file) as s:
        rows = vertical_rows(scene)
        n_section: int | None
        if sil.shape == "rectangular":
            section, n_section = _box_section(s, scene)
        elif sil.eccentricity > 0:
            section, n_section = _free_section(s, scene), None
        else:
            og = ogrid_for(scene)
            section, n_section = _ogrid_section(s, og), og.n_cells
        band = None
        if sil.orifice_position == "lateral":
            assert sil.orifice_height is not None
            band = (sil.orifice_height, sil.orifice_height + sil.orifice_width)
        _sweep(s, section, rows, band)
        node_map = None
        if sil.shape == "hopper":  # the cylinder's nodes moved radially onto the cone
            ys, rs = zip(*sil.profile, strict=True)
            R = sil.width / 2

            def node_map(x: float, y: float, z: float) -> tuple[float, float, float]:
                k = _interp(y, ys, rs) / R
                return x * k, y, z * k

        s.write(order, dump_geometry, node_map, _hole(scene))
        kinds = s.element_kinds()
    kind = "hexahedral"
    if set(kinds) - {"hexahedra"}:
        kind = "hex-dominant (" + ", ".join(f"{v} {k}" for k, v in sorted(kinds.items())) + ")"
    n = None if n_section is None else n_section * sum(r.n for r in rows)
    return n, kind


def _hole(scene: Scene) -> Carve | None:
    """Return the cut of a circular hole drilled along +x through a cylinder's wall.

    The band of the wall the hole spans (its height, and its arc at the
    centre height) is swept as orifice; the faces nearest the hole's axis,
    in sqrt(z^2 + (y - y_c)^2), whose areas add up to the hole's (the disc's
    area on the curved wall, :func:`hole_area`) stay orifice, the others go
    back to the wall: a staircase of whole faces with the hole's area.
    """
    sil = scene.silo
    if not (
        sil.shape == "cylindrical"
        and sil.orifice_position == "lateral"
        and sil.resolved_orifice_shape == "circular"
    ):
        return None
    assert sil.orifice_height is not None
    r = sil.orifice_width / 2
    yc = sil.orifice_height + r

    def distance(c: np.ndarray) -> np.ndarray:
        return np.asarray(np.hypot(c[:, 2], c[:, 1] - yc))

    area = hole_area(sil.width / 2, r)
    return Carve(ORIFICE, WALLS, distance, area, "circular lateral orifice")


def hole_area(R: float, r: float) -> float:
    """Area of the wall of a cylinder (radius R) inside a hole of radius r drilled along its radius.

    The wall at z = R sin(theta) has the area element dz dy / sqrt(1 - z^2/R^2):
    ``A = int_{-r}^{r} 2 sqrt(r^2 - z^2) / sqrt(1 - z^2/R^2) dz`` (pi r^2 for R -> inf).
    """
    from scipy.integrate import quad

    value, _ = quad(lambda z: 2 * math.sqrt(max(r * r - z * z, 0.0)) / math.sqrt(1 - (z / R) ** 2),
                    -r, r)  # fmt: skip
    return float(value)


def _interp(x: float, xs: tuple[float, ...], ys: tuple[float, ...]) -> float:
    """Piecewise-linear interpolation (numpy's ``interp`` for one point, clamped)."""
    if x <= xs[0]:
        return ys[0]
    for i in range(len(xs) - 1):
        if x <= xs[i + 1]:
            t = (x - xs[i]) / (xs[i + 1] - xs[i]) if xs[i + 1] > xs[i] else 0.0
            return ys[i] + t * (ys[i + 1] - ys[i])
    return ys[-1]
