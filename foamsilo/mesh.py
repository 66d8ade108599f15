"""gmsh silo meshes, converted to OpenFOAM polyMeshes and checked.

The builders make OCC geometry with named physical groups that become the
OpenFOAM patches (``walls``, ``orifice``, ``atmosphere`` and, for a planar
mesh, ``frontAndBack``), mesh it with hexahedra, and write gmsh format 2.2
for ``gmshToFoam``.  When meshing fails, the geometry is written next to the
mesh (``.geo_unrolled`` and ``.brep``) for inspection.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

from foamsilo.errors import MeshError
from foamsilo.foam import CheckMeshResult, check_mesh, gmsh_to_foam, set_patch_types
from foamsilo.scene import WEDGE_ANGLE_DEG, Scene
from foamsilo.toolchain import OpenFOAM

#: OpenFOAM patch type of each physical group, per representation.
PATCH_TYPES = {
    "planar": {"walls": "wall", "orifice": "patch", "atmosphere": "patch", "frontAndBack": "empty"},
    "axisymmetric": {
        "walls": "wall",
        "orifice": "patch",
        "atmosphere": "patch",
        "front": "wedge",
        "back": "wedge",
    },
    "3d": {"walls": "wall", "orifice": "patch", "atmosphere": "patch"},
}

#: Fewest cells on a quarter circle: the 48-gon holds 99.7% of the disk's area
MIN_QUADRANT_CELLS = 12
#: Largest cell width away from the orifice, in cells at the orifice (3D cross-sections)
COARSE_RATIO_3D = 4.0


@dataclass(frozen=True)
class PlanarSilo:
    """A rectangular silo cross-section with a bottom slot, one cell thick.

    Attributes
    ----------
    width
        L [m].
    height
        H [m].
    orifice_width
        D [m], centred at x = L/2.
    cells_across
        Cells across L (the one resolution parameter).
    """

    width: float
    height: float
    orifice_width: float
    cells_across: int
    top_cell_ratio: float = 1.0
    fine_height: float | None = None
    fill_height: float | None = None

    #: cells that must fit between the initial fill and the open top
    HEADSPACE_CELLS = 2

    @classmethod
    def from_scene(cls, scene: Scene) -> PlanarSilo:
        """Make the planar geometry of a scene."""
        s, m = scene.silo, scene.mesh
        return cls(
            s.width,
            s.height,
            s.orifice_width,
            m.cells_across,
            m.top_cell_ratio,
            m.fine_height,
            s.fill_height,
        )

    @property
    def effective_top_cell_ratio(self) -> float:
        """Top cell ratio, capped so that the headspace keeps its cells.

        Cells taller than half the gap between the fill and the top put grains
        in the top row of cells, and they leave through the open top (0.7% of
        them at 16 cells across, measured).
        """
        if self.fill_height is None:
            return self.top_cell_ratio
        dx = self.width / self.cells_across
        cap = (self.height - self.fill_height) / (self.HEADSPACE_CELLS * dx)
        ratio = min(self.top_cell_ratio, cap)
        return ratio if ratio > 1.2 else 1.0  # too little to pay: uniform

    @property
    def graded(self) -> bool:
        """Whether cells grow above ``fine_height``."""
        return self.effective_top_cell_ratio > 1.0 + 1e-12

    @property
    def fine_top(self) -> float:
        """Top of the zone of square cells [m] (the height when uniform)."""
        if not self.graded:
            return self.height
        dx = self.width / self.cells_across
        h = self.fine_height if self.fine_height is not None else self.width
        return min(self.height, max(dx, round(h / dx) * dx))

    @property
    def grading(self) -> tuple[int, float]:
        """Cells above ``fine_top`` and their geometric growth ratio per cell.

        The first cell above the fine zone is about one cell width high, the
        last about ``top_cell_ratio`` cell widths.
        """
        if not self.graded or self.fine_top >= self.height:
            return 0, 1.0
        dx = self.width / self.cells_across
        span = self.height - self.fine_top
        R = self.effective_top_cell_ratio
        # sum of a geometric series from dx to R dx over n cells equals span
        n = max(2, round((span / dx) * math.log(R) / (R - 1)))
        r = R ** (1.0 / (n - 1))
        return n, r

    @property
    def divisions(self) -> tuple[int, int, int]:
        """Cells across the left wall segment, the orifice and the right segment."""
        n = self.cells_across
        dx = self.width / n
        n_orf = max(2, round(self.orifice_width / dx))
        if (n - n_orf) % 2:  # keep the mesh symmetric about the axis
            n_orf += 1 if self.orifice_width / dx > n_orf else -1
        n_side = (n - n_orf) // 2
        return n_side, n_orf, n_side

    @property
    def cells_high(self) -> int:
        """Cells over the height."""
        dx = self.width / self.cells_across
        return max(1, round(self.fine_top / dx)) + self.grading[0]

    @property
    def thickness(self) -> float:
        """Thickness of the one-cell-thick slab (= the cell size) [m]."""
        return self.width / self.cells_across

    @property
    def n_cells(self) -> int:
        """Number of cells the mesh will have."""
        return sum(self.divisions) * self.cells_high


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


def _dump_geometry(gmsh: object, path: Path) -> Path:
    for suffix in (".geo_unrolled", ".brep"):
        try:
            gmsh.write(str(path.with_suffix(suffix)))  # type: ignore[attr-defined]
        except Exception:  # noqa: BLE001 - best effort on an already failing path
            pass
    return path.with_suffix(".geo_unrolled")


def build_planar(geom: PlanarSilo, msh_file: Path, dump_geometry: Path | None = None) -> None:
    """Mesh a planar silo with gmsh and write ``msh_file`` (format 2.2).

    Parameters
    ----------
    geom
        The silo.
    msh_file
        Output mesh file.
    dump_geometry
        If given, also write the geometry there (``.geo_unrolled``, ``.brep``).

    Raises
    ------
    MeshError
        With the geometry written next to ``msh_file`` for inspection.
    """
    import gmsh

    L, H, D = geom.width, geom.height, geom.orifice_width
    x1, x2 = (L - D) / 2, (L + D) / 2
    n_left, n_orf, n_right = geom.divisions
    dz = geom.thickness
    y_fine = geom.fine_top
    n_fine = round(y_fine / dz) if geom.graded else geom.cells_high
    n_up, ratio = geom.grading
    tol = 0.01 * L / geom.cells_across  # OCC pads bounding boxes by ~1e-7 m

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("planar_silo")
        occ = gmsh.model.occ
        rows = [(0.0, y_fine)] + ([(y_fine, H)] if n_up else [])
        rects = [
            occ.addRectangle(xa, ya, 0, xb - xa, yb - ya)
            for ya, yb in rows
            for xa, xb in ((0.0, x1), (x1, x2), (x2, L))
        ]
        occ.fragment([(2, rects[0])], [(2, r) for r in rects[1:]])
        occ.synchronize()
        surfaces = [t for _, t in gmsh.model.getEntities(2)]
        if len(surfaces) != len(rects):
            raise MeshError(
                f"planar silo geometry has {len(surfaces)} faces, expected {len(rects)}",
                _dump_geometry(gmsh, msh_file),
            )
        # Structured quads: cells along x per block; along y uniform in the
        # fine zone, growing geometrically (upward) above it
        for _, c in gmsh.model.getEntities(1):
            xmin, ymin, _, xmax, ymax, _ = gmsh.model.getBoundingBox(1, c)
            if abs(ymax - ymin) > tol:  # vertical
                if ymin > y_fine - tol and n_up:
                    lo, hi = gmsh.model.getParametrizationBounds(1, c)
                    y0 = gmsh.model.getValue(1, c, [lo[0]])[1]
                    y1 = gmsh.model.getValue(1, c, [hi[0]])[1]
                    coef = ratio if y1 > y0 else 1.0 / ratio  # grow upward
                    gmsh.model.mesh.setTransfiniteCurve(c, n_up + 1, "Progression", coef)
                else:
                    gmsh.model.mesh.setTransfiniteCurve(c, n_fine + 1)
            else:
                xm = 0.5 * (xmin + xmax)
                n = n_left if xm < x1 else (n_orf if xm < x2 else n_right)
                gmsh.model.mesh.setTransfiniteCurve(c, n + 1)
        for s in surfaces:
            gmsh.model.mesh.setTransfiniteSurface(s)
            gmsh.model.mesh.setRecombine(2, s)
        ext = occ.extrude([(2, s) for s in surfaces], 0, 0, dz, numElements=[1], recombine=True)
        occ.synchronize()
        volumes = [t for d, t in ext if d == 3]

        groups: dict[str, list[int]] = {
            "walls": [],
            "orifice": [],
            "atmosphere": [],
            "frontAndBack": [],
        }
        for _, s in gmsh.model.getEntities(2):
            xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(2, s)
            if abs(zmax - zmin) < tol:
                groups["frontAndBack"].append(s)
            elif abs(ymax - ymin) < tol and abs(ymin) < tol:
                xm = 0.5 * (xmin + xmax)
                groups["orifice" if x1 - tol < xm < x2 + tol else "walls"].append(s)
            elif abs(ymax - ymin) < tol and abs(ymin - H) < tol:
                groups["atmosphere"].append(s)
            elif abs(xmax - xmin) < tol and (abs(xmin) < tol or abs(xmin - L) < tol):
                groups["walls"].append(s)
            # else: internal faces between the blocks
        for name, tags in groups.items():
            if not tags:
                raise MeshError(f"no surface for patch {name!r}", _dump_geometry(gmsh, msh_file))
            gmsh.model.addPhysicalGroup(2, tags, name=name)
        gmsh.model.addPhysicalGroup(3, volumes, name="silo")

        if dump_geometry is not None:
            _dump_geometry(gmsh, dump_geometry)
        try:
            gmsh.model.mesh.generate(3)
        except Exception as exc:
            raise MeshError(f"gmsh failed: {exc}", _dump_geometry(gmsh, msh_file)) from exc
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)  # gmshToFoam reads ascii only
        gmsh.write(str(msh_file))
    finally:
        gmsh.finalize()


# ---------------------------------------------------------------------------- layout


@dataclass(frozen=True)
class Row:
    """A horizontal band of cells from y0 to y1.

    Its n cells are each ``ratio`` times taller than the one below.
    """

    y0: float
    y1: float
    n: int
    ratio: float = 1.0

    def heights(self) -> list[float]:
        """Cumulative layer heights as fractions of the band (gmsh ``heights``)."""
        if abs(self.ratio - 1.0) < 1e-12:
            return [(k + 1) / self.n for k in range(self.n)]
        w = [self.ratio**k for k in range(self.n)]
        tot = sum(w)
        acc, out = 0.0, []
        for x in w:
            acc += x
            out.append(acc / tot)
        out[-1] = 1.0
        return out


def vertical_rows(scene: Scene) -> list[Row]:
    """Bands of cells from the bottom to the top of the domain.

    Square cells (of the size at the orifice) up to ``mesh.fine_height`` (or the
    silo width), band edges at every corner of the wall and at the edges of a
    lateral orifice, then cells growing to ``mesh.top_cell_ratio`` times taller.
    """
    s = scene.silo
    h = scene.cell_size
    H = s.height
    cuts = {y for y, _ in s.profile if 0.0 < y < H}
    if s.orifice_position == "lateral":
        assert s.orifice_height is not None
        cuts |= {y for y in (s.orifice_height, s.orifice_height + s.orifice_width) if 0 < y < H}
    g = PlanarSilo(
        s.width,
        H,
        s.orifice_width,
        scene.mesh.cells_across,
        scene.mesh.top_cell_ratio,
        scene.mesh.fine_height,
        s.fill_height,
    )
    fine_top = H
    if g.graded:
        need = max(cuts, default=0.0)
        fine_top = max(g.fine_top, math.ceil(need / h - 1e-9) * h + (h if need > 0 else 0.0))
        if fine_top > H - 2 * h:
            fine_top = H
    edges = sorted({0.0, fine_top, *cuts} | ({H} if fine_top < H else set()))
    edges = [y for y in edges if y <= H]
    rows = []
    for y0, y1 in zip(edges[:-1], edges[1:], strict=True):
        if y0 >= fine_top - 1e-12:
            span = y1 - y0
            R = g.effective_top_cell_ratio
            n = max(2, round((span / h) * math.log(R) / (R - 1)))
            rows.append(Row(y0, y1, n, R ** (1.0 / (n - 1))))
        else:
            rows.append(Row(y0, y1, max(1, round((y1 - y0) / h))))
    return rows


def _growth(span: float, first: float, last: float) -> tuple[int, float]:
    """Cells and per-cell ratio for a band from cells of size ``first`` to ``last``."""
    R = last / first
    if R < 1.2:
        return max(1, round(span / first)), 1.0
    n = max(2, round((span / first) * math.log(R) / (R - 1)))
    return n, R ** (1.0 / (n - 1))


# ---------------------------------------------------------------------------- gmsh helpers


def _transfinite(gmsh: object, curve: int, n: int, ratio: float = 1.0) -> None:
    """N cells on a curve, growing by ``ratio`` from its first to its last point."""
    m = gmsh.model.mesh  # type: ignore[attr-defined]
    if abs(ratio - 1.0) < 1e-12:
        m.setTransfiniteCurve(curve, n + 1)
    else:
        m.setTransfiniteCurve(curve, n + 1, "Progression", ratio)


def _extrude_rows(gmsh: object, surfaces: list[int], rows: list[Row]) -> list[int]:
    """Extrude cross-section surfaces (in the plane y = 0) up through the rows."""
    occ = gmsh.model.occ  # type: ignore[attr-defined]
    volumes: list[int] = []
    base = [(2, t) for t in surfaces]
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
        tops = [ext[k - 1] for k in range(1, len(ext)) if ext[k][0] == 3]
        volumes += [t for d, t in ext if d == 3]
        base = tops
    occ.synchronize()
    return volumes


def _boundary_surfaces(gmsh: object) -> list[tuple[int, tuple[float, ...], tuple[float, ...]]]:
    """Faces with one volume on one side: (tag, centre of mass, bounding box)."""
    out = []
    model = gmsh.model  # type: ignore[attr-defined]
    for _, s in model.getEntities(2):
        up, _ = model.getAdjacencies(2, s)
        if len(up) == 1:
            out.append((s, tuple(model.occ.getCenterOfMass(2, s)), model.getBoundingBox(2, s)))
    return out


def _add_groups(gmsh: object, groups: dict[str, list[int]], msh_file: Path) -> None:
    for name, tags in groups.items():
        if not tags:
            raise MeshError(f"no surface for patch {name!r}", _dump_geometry(gmsh, msh_file))
        gmsh.model.addPhysicalGroup(2, tags, name=name)  # type: ignore[attr-defined]
    vols = [t for _, t in gmsh.model.getEntities(3)]  # type: ignore[attr-defined]
    gmsh.model.addPhysicalGroup(3, vols, name="silo")  # type: ignore[attr-defined]


def _classify(scene: Scene, centre: tuple[float, ...], box: tuple[float, ...], tol: float) -> str:
    """Patch of a boundary face of a planar, wedge or 3D silo from where it lies."""
    s = scene.silo
    rep = scene.representation
    x, y, z = centre
    xmin, ymin, zmin, xmax, ymax, zmax = box
    if rep == "planar" and zmax - zmin < tol:
        return "frontAndBack"
    if rep == "axisymmetric":
        half = math.radians(WEDGE_ANGLE_DEG) / 2
        phi = math.atan2(z, x)
        if abs(phi) > half / 2:
            return "front" if phi > 0 else "back"
    if ymax - ymin < tol and ymax < tol:
        return "orifice" if _in_bottom_orifice(scene, x, z) else "walls"
    if ymax - ymin < tol and abs(ymin - s.height) < tol:
        return "atmosphere"
    if s.orifice_position == "lateral":
        assert s.orifice_height is not None
        if s.orifice_height - tol < y < s.orifice_height + s.orifice_width + tol:
            if _on_lateral_orifice(scene, x, z, tol):
                return "orifice"
    return "walls"


def _in_bottom_orifice(scene: Scene, x: float, z: float) -> bool:
    s = scene.silo
    if s.orifice_position != "bottom":
        return False
    if s.shape == "hopper":
        return True
    r = s.orifice_width / 2
    rep = scene.representation
    if rep == "planar":
        return abs(x - s.width / 2) < r
    if rep == "axisymmetric":
        return math.hypot(x, z) < r
    if s.shape == "cylindrical":
        return math.hypot(x - s.eccentricity, z) < r
    W = s.thickness or 0.0
    ol = s.orifice_length if s.orifice_length is not None else W
    return abs(x - s.width / 2) < r and abs(z - W / 2) < ol / 2


def _on_lateral_orifice(scene: Scene, x: float, z: float, tol: float) -> bool:
    s = scene.silo
    rep = scene.representation
    if rep == "planar":
        return x > s.width - tol
    if s.shape == "rectangular":
        W = s.thickness or 0.0
        ol = s.orifice_length if s.orifice_length is not None else W
        return x > s.width - tol and abs(z - W / 2) < ol / 2
    R = s.width / 2
    if s.resolved_orifice_shape == "circular":
        return x > 0.5 * R and abs(z) < s.orifice_width / 2
    assert s.orifice_length is not None
    return x > 0 and abs(math.atan2(z, x)) < s.orifice_length / (2 * R)


def _finish(gmsh: object, msh_file: Path, dump_geometry: Path | None) -> None:
    if dump_geometry is not None:
        _dump_geometry(gmsh, dump_geometry)
    try:
        gmsh.model.mesh.generate(3)  # type: ignore[attr-defined]
    except Exception as exc:
        raise MeshError(f"gmsh failed: {exc}", _dump_geometry(gmsh, msh_file)) from exc
    gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)  # type: ignore[attr-defined]
    gmsh.option.setNumber("Mesh.Binary", 0)  # type: ignore[attr-defined] # gmshToFoam: ascii
    gmsh.write(str(msh_file))  # type: ignore[attr-defined]


def _element_kinds(gmsh: object) -> dict[str, int]:
    """Count the 3D elements of each kind in the generated mesh."""
    names = {4: "tetrahedra", 5: "hexahedra", 6: "prisms", 7: "pyramids"}
    out: dict[str, int] = {}
    types, tags, _ = gmsh.model.mesh.getElements(3)  # type: ignore[attr-defined]
    for t, tg in zip(types, tags, strict=True):
        name = names.get(int(t), f"type{int(t)}")
        out[name] = out.get(name, 0) + len(tg)
    return out


def _block_grid(
    gmsh: object,
    P: list[list[int]],
    cols: list[tuple[int, float]],
    rows: list[tuple[int, float]],
) -> list[int]:
    """Transfinite quad blocks between the points P[i][j] (straight edges).

    ``cols[i]`` and ``rows[j]`` give the cells and growth ratio of block
    column i (along the first index) and block row j (along the second).
    """
    occ = gmsh.model.occ  # type: ignore[attr-defined]
    ni, nj = len(P), len(P[0])
    A = [[occ.addLine(P[i][j], P[i + 1][j]) for j in range(nj)] for i in range(ni - 1)]
    B = [[occ.addLine(P[i][j], P[i][j + 1]) for j in range(nj - 1)] for i in range(ni)]
    surfaces = []
    for i in range(ni - 1):
        for j in range(nj - 1):
            loop = occ.addCurveLoop([A[i][j], B[i + 1][j], A[i][j + 1], B[i][j]])
            surfaces.append(occ.addPlaneSurface([loop]))
    occ.synchronize()
    for i in range(ni - 1):
        for j in range(nj):
            _transfinite(gmsh, A[i][j], *cols[i])
    for i in range(ni):
        for j in range(nj - 1):
            _transfinite(gmsh, B[i][j], *rows[j])
    for t in surfaces:
        gmsh.model.mesh.setTransfiniteSurface(t)  # type: ignore[attr-defined]
        gmsh.model.mesh.setRecombine(2, t)  # type: ignore[attr-defined]
    return surfaces


# ---------------------------------------------------------------------------- 2D: planar and wedge


def _profile_columns(scene: Scene) -> tuple[float, list[float], list[int]]:
    """Wall-relative column edges of a planar or axisymmetric profile.

    Returns the centre c and fractions f with x = c + f r(y), and the cells
    of each column.
    """
    s = scene.silo
    h = scene.cell_size
    R = s.width / 2
    r_o = s.orifice_width / 2
    planar = scene.representation == "planar"
    if s.shape == "hopper":
        # as many cells across the outlet as there are across the orifice, but
        # never wider than COARSE_RATIO_3D cells at the top
        n = max(2, round(r_o / h), math.ceil(R / (COARSE_RATIO_3D * h)))
        return (R, [-1.0, 0.0, 1.0], [n, n]) if planar else (0.0, [0.0, 1.0], [n])
    if planar:  # rectangular silo with a lateral orifice (a bottom slot is PlanarSilo)
        return 0.0, [0.0, 2.0], [scene.mesh.cells_across]  # wall to wall: 0 to 2R
    # axisymmetric flat-bottomed cylinder: the axis, the orifice edge, the wall
    n1 = max(1, round(r_o / h))
    n2 = max(1, round((R - r_o) / h))
    return 0.0, [0.0, r_o / R, 1.0], [n1, n2]


def build_profile(scene: Scene, msh_file: Path, dump_geometry: Path | None = None) -> int:
    """Mesh a planar or axisymmetric (wedge) silo profile with structured quads.

    The profile x = c + f r(y) is cut into columns (axis, orifice edge, wall)
    and the rows of :func:`vertical_rows`; each block is a transfinite quad.
    Planar: extruded one cell thick; axisymmetric: revolved by
    ``WEDGE_ANGLE_DEG`` about the y axis, symmetric about z = 0.

    Returns
    -------
    int
        The number of cells.
    """
    import gmsh

    s = scene.silo
    rows = vertical_rows(scene)
    c, fr, ncols = _profile_columns(scene)
    ys = [rows[0].y0] + [r.y1 for r in rows]
    planar = scene.representation == "planar"
    tol = 1e-3 * scene.cell_size
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("profile")
        occ = gmsh.model.occ
        # an axisymmetric profile lies in the plane at -WEDGE_ANGLE_DEG/2 and is
        # revolved through the wedge (a rotation about +y by -a turns +x to +z)
        half = 0.0 if planar else math.radians(WEDGE_ANGLE_DEG) / 2
        ca, sa = math.cos(half), math.sin(half)
        P = [
            [
                occ.addPoint(ca * (c + f * s.wall_radius(y)), y, -sa * (c + f * s.wall_radius(y)))
                for y in ys
            ]
            for f in fr
        ]
        surfaces = _block_grid(gmsh, P, [(n, 1.0) for n in ncols], [(r.n, r.ratio) for r in rows])
        dims = [(2, t) for t in surfaces]
        if planar:
            occ.extrude(dims, 0, 0, scene.cell_size, numElements=[1], recombine=True)
        else:
            occ.revolve(dims, 0, 0, 0, 0, 1, 0, -2 * half, numElements=[1], recombine=True)
        occ.synchronize()
        groups: dict[str, list[int]] = {k: [] for k in PATCH_TYPES[scene.representation]}
        for tag, centre, box in _boundary_surfaces(gmsh):
            groups[_classify(scene, centre, box, tol)].append(tag)
        _add_groups(gmsh, groups, msh_file)
        _finish(gmsh, msh_file, dump_geometry)
    finally:
        gmsh.finalize()
    return sum(ncols) * sum(r.n for r in rows)


# ---------------------------------------------------------------------------- 3D


@dataclass(frozen=True)
class OGrid:
    """Structured O-grid of a disk of radius ``radius`` (cross-section in x-z).

    A central square (corners at ``square`` x the first ring radius), then
    rings out to each radius in ``rings``; quadrants centred on +x, +z, -x,
    -z.  ``arcs`` gives, per quadrant, the angular segments (start, end, cells)
    between the quadrant's corners.
    """

    rings: tuple[float, ...]
    ring_cells: tuple[tuple[int, float], ...]
    arcs: tuple[tuple[tuple[float, float, int], ...], ...]
    square: float = 0.6

    @property
    def n_cells(self) -> int:
        """Cells in the cross-section."""
        na = sum(n for _, _, n in self.arcs[0])
        nb = sum(n for _, _, n in self.arcs[1])
        around = 2 * (na + nb)
        return na * nb + around * sum(n for n, _ in self.ring_cells)


def ogrid_for(scene: Scene) -> OGrid:
    """Lay out the O-grid of a cylinder's (or a 3D hopper's top) cross-section."""
    s = scene.silo
    h = scene.cell_size
    R = s.width / 2
    coarse = COARSE_RATIO_3D * h
    q = math.pi / 4
    if s.orifice_position == "lateral":
        assert s.orifice_length is not None
        tw = s.orifice_length / (2 * R)
        n_orf = max(2, round(s.orifice_length / h))
        n_side = max(MIN_QUADRANT_CELLS // 2, round((q - tw) * R / (2 * h)))
        n_b = max(MIN_QUADRANT_CELLS, round(2 * q * R / (2 * h)))
        quad0 = ((-q, -tw, n_side), (-tw, tw, n_orf), (tw, q, n_side))
        n_a = 2 * n_side + n_orf
        n_r = max(2, round((1 - 0.6) * R / h))
        return OGrid(
            (R,),
            ((n_r, 1.0),),
            (quad0, ((q, 3 * q, n_b),), ((3 * q, 5 * q, n_a),), ((5 * q, 7 * q, n_b),)),
        )
    r_o = s.orifice_width / 2
    n_q = max(MIN_QUADRANT_CELLS, round(q * 2 * r_o / h), math.ceil(2 * q * R / coarse))
    arcs = tuple(((q * (2 * k - 1), q * (2 * k + 1), n_q),) for k in range(4))
    if s.shape == "hopper":  # the whole bottom is the outlet; radii scale down to it
        r_in = R
        size = 2 * q * r_o / n_q  # arc cell at the outlet
        n_r = max(2, round((1 - 0.6) * r_o / size))
        return OGrid((R,), ((n_r, 1.0),), arcs)
    # flat bottom, centred orifice: a ring ends on the orifice edge, then the
    # cells grow towards the wall up to the arc spacing there
    r_in = r_o
    size = 2 * q * r_in / n_q
    n_r1 = max(1, round((1 - 0.6) * r_in / max(size, 0.8 * h)))
    first = (1 - 0.6) * r_in / n_r1
    last = min(coarse, max(first, 2 * q * R / n_q))
    n_r2, g2 = _growth(R - r_o, first, last)
    return OGrid((r_o, R), ((n_r1, 1.0), (n_r2, g2)), arcs)


def _build_ogrid_section(gmsh: object, og: OGrid) -> list[int]:
    """Make the O-grid cross-section surfaces (plane y = 0) with transfinite settings."""
    occ = gmsh.model.occ  # type: ignore[attr-defined]
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
    surfaces = []
    loop = occ.addCurveLoop(sq_lines)
    square = occ.addPlaneSurface([loop])
    surfaces.append(square)
    ring_surfs = []
    for k in range(len(og.rings)):
        inner_lines = sq_lines if k == 0 else arcs[k - 1]
        for i in range(m):
            lp = occ.addCurveLoop(
                [inner_lines[i], radial[k][(i + 1) % m], arcs[k][i], radial[k][i]]
            )
            ring_surfs.append(occ.addPlaneSurface([lp]))
    surfaces += ring_surfs
    occ.remove([(0, centre)])
    occ.synchronize()
    for i in range(m):
        _transfinite(gmsh, sq_lines[i], counts[i])
        for k in range(len(og.rings)):
            _transfinite(gmsh, arcs[k][i], counts[i])
            n, g = og.ring_cells[k]
            _transfinite(gmsh, radial[k][i], n, g)
    corners = [sq_pts[i] for i, a in enumerate(angles) if a in corner_angles]
    gmsh.model.mesh.setTransfiniteSurface(square, "Left", corners)  # type: ignore[attr-defined]
    for t in ring_surfs:
        gmsh.model.mesh.setTransfiniteSurface(t)  # type: ignore[attr-defined]
    for t in surfaces:
        gmsh.model.mesh.setRecombine(2, t)  # type: ignore[attr-defined]
    return surfaces


def _xz(p: tuple[float, float]) -> tuple[float, float, float]:
    """Cross-section point (x, z) in 3D, in the plane y = 0."""
    return p[0], 0.0, p[1]


def _box_section(gmsh: object, scene: Scene) -> tuple[list[int], int]:
    """Transfinite blocks of a rectangular silo's cross-section (x-z plane)."""
    s = scene.silo
    occ = gmsh.model.occ  # type: ignore[attr-defined]
    h = scene.cell_size
    L = s.width
    assert s.thickness is not None
    W = s.thickness
    ol = s.orifice_length if s.orifice_length is not None else W
    if s.orifice_position == "bottom":
        n_l, n_o, n_r = PlanarSilo(L, s.height, s.orifice_width, scene.mesh.cells_across).divisions
        xs, nx = [0.0, (L - s.orifice_width) / 2, (L + s.orifice_width) / 2, L], [n_l, n_o, n_r]
    else:
        xs, nx = [0.0, L], [scene.mesh.cells_across]
    if ol < W - 1e-12:
        zs = [0.0, (W - ol) / 2, (W + ol) / 2, W]
    else:
        zs = [0.0, W]
    nz = [
        max(2 if len(zs) == 2 else 1, round((b - a) / h))
        for a, b in zip(zs[:-1], zs[1:], strict=True)
    ]
    P = [[occ.addPoint(x, 0, z) for z in zs] for x in xs]
    surfaces = _block_grid(gmsh, P, [(n, 1.0) for n in nx], [(n, 1.0) for n in nz])
    return surfaces, sum(nx) * sum(nz)


def _free_section(gmsh: object, scene: Scene) -> list[int]:
    """Quad-dominant cross-section of a cylinder with an eccentric orifice."""
    s = scene.silo
    occ = gmsh.model.occ  # type: ignore[attr-defined]
    h = scene.cell_size
    R, r = s.width / 2, s.orifice_width / 2
    disk = occ.addDisk(0, 0, 0, R, R)
    hole = occ.addDisk(s.eccentricity, 0, 0, r, r)
    occ.fragment([(2, disk)], [(2, hole)])
    occ.rotate(occ.getEntities(2), 0, 0, 0, 1, 0, 0, math.pi / 2)  # x-y plane to x-z
    occ.synchronize()
    surfaces = [t for _, t in gmsh.model.getEntities(2)]  # type: ignore[attr-defined]
    edge = [c for _, c in gmsh.model.getEntities(1) if _is_orifice_edge(gmsh, c, s)]  # type: ignore[attr-defined]
    f = gmsh.model.mesh.field  # type: ignore[attr-defined]
    dist = f.add("Distance")
    f.setNumbers(dist, "CurvesList", edge)
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
        gmsh.option.setNumber(opt, val)  # type: ignore[attr-defined]
    for c in edge:  # a 24-gon at least: 98.9% of the disk's area
        n = max(24, math.ceil(2 * math.pi * r / h))
        gmsh.model.mesh.setTransfiniteCurve(c, n + 1)  # type: ignore[attr-defined]
    for t in surfaces:
        gmsh.model.mesh.setRecombine(2, t)  # type: ignore[attr-defined]
    return surfaces


def _is_orifice_edge(gmsh: object, c: int, s: object) -> bool:
    b = gmsh.model.getBoundingBox(1, c)  # type: ignore[attr-defined]
    return (b[3] - b[0]) < 1.01 * s.orifice_width  # type: ignore[attr-defined]


def _map_hopper(msh_file: Path, scene: Scene) -> None:
    """Scale the nodes of a cylinder mesh radially onto the hopper's wall profile."""
    import numpy as np

    s = scene.silo
    R = s.width / 2
    text = msh_file.read_text()
    a = text.index("$Nodes\n")
    b = text.index("$EndNodes")
    head, body = text[: a + 7], text[a + 7 : b]
    n_line, rest = body.split("\n", 1)
    data = np.loadtxt(rest.splitlines(), ndmin=2)
    ys, rs = zip(*s.profile, strict=True)
    scale = np.interp(data[:, 2], ys, rs) / R
    data[:, 1] *= scale
    data[:, 3] *= scale
    lines = "\n".join(f"{int(t)} {x:.12g} {y:.12g} {z:.12g}" for t, x, y, z in data)
    msh_file.write_text(f"{head}{n_line}\n{lines}\n{text[b:]}")


def build_3d(
    scene: Scene, msh_file: Path, dump_geometry: Path | None = None
) -> tuple[int | None, str]:
    """Mesh a 3D silo: an O-grid or box cross-section extruded in rows of hexahedra.

    A cylinder with a centred or lateral rectangular orifice, and a hopper
    (whose cylinder mesh is then scaled radially onto the cone), get a
    structured O-grid; a box gets transfinite blocks; an eccentric outlet a
    quad-dominant unstructured cross-section (hexahedra, prisms where a
    triangle is left); a circular lateral orifice in a curved wall is meshed
    with tetrahedra (the fall-back).

    Returns
    -------
    tuple
        The number of cells (None when unstructured) and the kind of cells.
    """
    import gmsh

    s = scene.silo
    rows = vertical_rows(scene)
    tol = 1e-3 * scene.cell_size
    kind = "hexahedral"
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("silo3d")
        n_section: int | None
        if (
            s.shape == "cylindrical"
            and s.orifice_position == "lateral"
            and (s.resolved_orifice_shape == "circular")
        ):
            return _build_tet(gmsh, scene, msh_file, dump_geometry), "tetrahedral"
        if s.shape == "rectangular":
            surfaces, n_section = _box_section(gmsh, scene)
        elif s.eccentricity > 0:
            surfaces, n_section = _free_section(gmsh, scene), None
        else:
            og = ogrid_for(scene)
            surfaces, n_section = _build_ogrid_section(gmsh, og), og.n_cells
        _extrude_rows(gmsh, surfaces, rows)
        groups: dict[str, list[int]] = {k: [] for k in PATCH_TYPES["3d"]}
        for tag, centre, box in _boundary_surfaces(gmsh):
            groups[_classify(scene, centre, box, tol)].append(tag)
        _add_groups(gmsh, groups, msh_file)
        _finish(gmsh, msh_file, dump_geometry)
        kinds = _element_kinds(gmsh)
        if set(kinds) - {"hexahedra"}:
            kind = "hex-dominant (" + ", ".join(f"{v} {k}" for k, v in sorted(kinds.items())) + ")"
    finally:
        gmsh.finalize()
    if s.shape == "hopper":
        _map_hopper(msh_file, scene)
    n = None if n_section is None else n_section * sum(r.n for r in rows)
    return n, kind


def _build_tet(gmsh: object, scene: Scene, msh_file: Path, dump_geometry: Path | None) -> None:
    """Tetrahedra for a circular hole in a curved wall (no hexahedral layout fits it)."""
    s = scene.silo
    occ = gmsh.model.occ  # type: ignore[attr-defined]
    h = scene.cell_size
    R, r = s.width / 2, s.orifice_width / 2
    assert s.orifice_height is not None
    yc = s.orifice_height + r
    silo = occ.addCylinder(0, 0, 0, 0, s.height, 0, R)
    tool = occ.addCylinder(0, yc, 0, 2 * R, 0, 0, r)
    occ.fragment([(3, silo)], [(3, tool)])
    occ.synchronize()
    outside = [
        (3, t)
        for _, t in gmsh.model.getEntities(3)  # type: ignore[attr-defined]
        if occ.getCenterOfMass(3, t)[0] > R
    ]
    occ.remove(outside, recursive=True)
    occ.synchronize()
    tol = 1e-3 * h
    groups: dict[str, list[int]] = {k: [] for k in PATCH_TYPES["3d"]}
    for tag, centre, box in _boundary_surfaces(gmsh):
        groups[_classify(scene, centre, box, tol)].append(tag)
    f = gmsh.model.mesh.field  # type: ignore[attr-defined]
    dist = f.add("Distance")
    f.setNumbers(dist, "SurfacesList", groups["orifice"])
    thr = f.add("Threshold")
    f.setNumber(thr, "InField", dist)
    f.setNumber(thr, "SizeMin", h)
    f.setNumber(thr, "SizeMax", COARSE_RATIO_3D * h)
    f.setNumber(thr, "DistMin", r)
    f.setNumber(thr, "DistMax", 4 * r + R)
    f.setAsBackgroundMesh(thr)
    for opt, val in (
        ("Mesh.MeshSizeExtendFromBoundary", 0),
        ("Mesh.MeshSizeFromPoints", 0),
        ("Mesh.MeshSizeFromCurvature", 0),
        ("Mesh.Optimize", 1),
    ):
        gmsh.option.setNumber(opt, val)  # type: ignore[attr-defined]
    _add_groups(gmsh, groups, msh_file)
    _finish(gmsh, msh_file, dump_geometry)


# ---------------------------------------------------------------------------- entry points


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
    """
    t0 = time.perf_counter()
    rep = scene.representation
    s = scene.silo
    msh = case / "constant" / "silo.msh"
    kind = "hexahedral"
    expected: int | None
    if rep == "planar" and s.shape == "rectangular" and s.orifice_position == "bottom":
        geom = PlanarSilo.from_scene(scene)
        build_planar(geom, msh, dump_geometry)
        expected = geom.n_cells
    elif rep in ("planar", "axisymmetric"):
        expected = build_profile(scene, msh, dump_geometry)
        if rep == "axisymmetric" or s.shape == "hopper":
            kind = "hexahedral (prisms on the axis)" if rep == "axisymmetric" else kind
    else:
        expected, kind = build_3d(scene, msh, dump_geometry)
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


def cells_estimate(scene: Scene) -> int:
    """Return the number of cells the scene's mesh will have (structured meshes exactly)."""
    s = scene.silo
    rep = scene.representation
    rows = vertical_rows(scene)
    if rep == "planar" and s.shape == "rectangular" and s.orifice_position == "bottom":
        return PlanarSilo.from_scene(scene).n_cells
    if rep in ("planar", "axisymmetric"):
        return sum(_profile_columns(scene)[2]) * sum(r.n for r in rows)
    if s.shape == "rectangular":
        h = scene.cell_size
        W = s.thickness or h
        return scene.mesh.cells_across * max(2, round(W / h)) * sum(r.n for r in rows)
    if (
        s.eccentricity > 0
        or s.orifice_position == "lateral"
        and s.resolved_orifice_shape == "circular"
    ):
        # unstructured: cross-section area over the mean cell area, roughly
        h = scene.cell_size
        return round(math.pi * (s.width / 2) ** 2 / (2 * h) ** 2) * sum(r.n for r in rows)
    return ogrid_for(scene).n_cells * sum(r.n for r in rows)
