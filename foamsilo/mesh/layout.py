"""Where the cells go: rows, profile blocks and O-grid cross-sections (no gmsh here).

A mesh is laid out before gmsh sees it, so that cell counts are known (and
tested) without meshing:

* :func:`vertical_rows`: horizontal bands from the floor to the top of the
  domain, square cells up to ``mesh.fine_height``, growing above it, with a
  band edge at every corner of the wall and at the edges of a lateral orifice;
* :func:`profile_layout`: the quad blocks of a planar or axisymmetric
  profile, each side labelled with the patch it lies on (``walls``,
  ``orifice``, ``atmosphere``, ``axis``) or ``None`` inside the silo;
* :func:`ogrid_for`: the structured O-grid of a cylinder's cross-section.

Patches are named here, where the shape is laid out, and carried through
the gmsh build (:mod:`foamsilo.mesh.profile`, :mod:`foamsilo.mesh.solid`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from foamsilo.scene import Scene

#: Patch names (gmsh physical groups, OpenFOAM patches)
WALLS, ORIFICE, ATMOSPHERE, AXIS = "walls", "orifice", "atmosphere", "axis"

#: Cells that must fit between the initial fill and the open top
HEADSPACE_CELLS = 2
#: Fewest cells on a quarter circle: the 48-gon holds 99.7% of the disk's area
MIN_QUADRANT_CELLS = 12
#: Largest cell width away from the orifice, in cells at the orifice (3D cross-sections)
COARSE_RATIO_3D = 4.0


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


def top_cell_ratio(scene: Scene) -> float:
    """Height of the topmost cell over the cell width, capped by the headspace.

    Cells taller than half the gap between the fill and the top put grains in
    the top row of cells, and they leave through the open top. Below a ratio of
    1.2 the mesh stays uniform.
    """
    h = scene.cell_size
    s = scene.silo
    cap = (s.height - s.fill_height) / (HEADSPACE_CELLS * h)
    ratio = min(scene.mesh.top_cell_ratio, cap)
    return ratio if ratio > 1.2 else 1.0


def _fine_top(scene: Scene) -> float:
    """Top of the square cells [m] (the domain height when the mesh is uniform)."""
    s, h = scene.silo, scene.cell_size
    if top_cell_ratio(scene) <= 1.0 + 1e-12:
        return s.height
    fine = scene.mesh.fine_height if scene.mesh.fine_height is not None else s.width
    return min(s.height, max(h, round(fine / h) * h))


def _growth(span: float, first: float, last: float) -> tuple[int, float]:
    """Cells and per-cell ratio for a band from cells of size ``first`` to ``last``."""
    R = last / first
    if R < 1.2:
        return max(1, round(span / first)), 1.0
    n = max(2, round((span / first) * math.log(R) / (R - 1)))
    return n, R ** (1.0 / (n - 1))


def graded_segments(
    span: float, h: float, growth: float, coarse: float
) -> list[tuple[float, int, float]]:
    """Bands of cells over ``span`` that grow away from a neighbour of size ``h``.

    Each band is (length, cells, ratio), listed from the fine end; a band's
    cells grow by ``ratio`` per cell (gmsh's ``Progression``). The first
    band's cells grow from ``h`` by at most ``growth`` per cell up to
    ``coarse`` x ``h``; the rest of the span, if any, is cells of that size.

    Examples
    --------
    >>> [(round(a, 3), n, round(r, 3)) for a, n, r in graded_segments(10.0, 1.0, 1.0, 4.0)]
    [(10.0, 10, 1.0)]
    """
    if growth <= 1.0 + 1e-12 or span <= 1.5 * h:
        return [(span, max(1, round(span / h)), 1.0)]

    def length(n: int, r: float) -> float:  # n cells from h r to h r^n
        return n * h if abs(r - 1.0) < 1e-12 else h * r * (r**n - 1) / (r - 1)

    n_g = max(1, math.ceil(math.log(coarse) / math.log(growth) - 1e-9)) if coarse > 1 else 0
    r_g = coarse ** (1.0 / n_g) if n_g else 1.0
    band = length(n_g, r_g) if n_g else 0.0
    if n_g and band + coarse * h <= span:
        rest = span - band
        return [(band, n_g, r_g), (rest, max(1, round(rest / (coarse * h))), 1.0)]
    if not n_g:
        return [(span, max(1, round(span / h)), 1.0)]
    # the span ends within the growth: fewest cells that reach it, ratio fitted
    n, r = _fill_within_growth(span, length, growth)
    if n * h >= span:
        return [(span, max(1, round(span / h)), 1.0)]
    return [(span, n, r)]


def _fill_within_growth(
    span: float, length: Callable[[int, float], float], growth: float
) -> tuple[int, float]:
    """Fewest cells whose growth by at most ``growth`` reaches ``span``, and their ratio.

    ``length(n, r)`` is the length of n cells growing by r per cell.
    """
    n = 1
    while length(n, growth) < span:
        n += 1
    lo, hi = 1.0 + 1e-12, growth
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if length(n, mid) < span else (lo, mid)
    return n, 0.5 * (lo + hi)


def edge_bands(span: float, h: float, k: float, growth: float) -> list[tuple[float, int, float]]:
    """Bands of cells over ``span`` that widen from about ``h / k`` at one end to ``h``.

    Each band is (length, cells, ratio), listed from the fine end; cells grow
    by ``ratio`` per cell. The growing band's ratio is at most ``growth`` and
    its last cell is ``h / ratio``, so that the whole cells of ``h`` after it
    continue the growth; its first cell is ``h / k`` to within the fraction of
    a cell that fits the band into the span. A span too short for the whole
    growth is filled by cells growing from ``h / k`` by at most ``growth``
    (ending narrower than ``h``).

    Examples
    --------
    >>> [(round(a, 3), n, round(r, 3)) for a, n, r in edge_bands(10.0, 1.0, 4.0, 2.0)]
    [(1.0, 2, 2.0), (9.0, 9, 1.0)]
    """
    e = h / k
    if k <= 1.0 + 1e-12 or span <= e * 1.5:
        return [(span, max(1, round(span / h)), 1.0)]

    def band(n: int) -> float:  # n cells from e, each k^(1/n) times the last
        r = k ** (1.0 / n)
        return e * (r**n - 1) / (r - 1)

    n_g = max(1, math.ceil(math.log(k) / math.log(growth) - 1e-9))
    if span >= band(n_g) + h:
        m = math.floor((span - band(n_g)) / h + 1e-9)  # whole cells of h after the band
        target = span - m * h
        n = n_g
        while abs(band(n + 1) - target) < abs(band(n) - target):
            n += 1
        return [(target, n, k ** (1.0 / n)), (m * h, m, 1.0)]

    def length(n: int, r: float) -> float:  # cells e, e r, ..., e r^(n-1)
        return n * e if abs(r - 1.0) < 1e-12 else e * (r**n - 1) / (r - 1)

    n, r = _fill_within_growth(span, length, growth)
    return [(span, n, r)]


def toward_edge(bands: list[tuple[float, int, float]]) -> list[tuple[float, int, float]]:
    """Bands listed from their fine end (:func:`edge_bands`), turned to run towards it."""
    return [(span, n, 1.0 / r) for span, n, r in reversed(bands)]


def edge_region(scene: Scene, room: float | None = None, k: float | None = None) -> float:
    """Width [m] of the orifice region beside an orifice edge (graded meshes).

    ``mesh.orifice_region`` D in whole cells, widened to hold the whole growth
    from the edge's refined cells (h / ``k``, default
    ``mesh.orifice_edge_refinement``) to the orifice's cells, never past the
    wall: ``room`` [m] is the distance from the edge to the wall it faces
    (default: a centred bottom orifice's edge to the side wall).
    """
    s, h, me = scene.silo, scene.cell_size, scene.mesh
    if room is None:
        room = (s.width - s.orifice_width) / 2
    if k is None:
        k = me.orifice_edge_refinement
    region = max(h, round(me.orifice_region * s.orifice_width / h) * h)
    # the growing band as edge_bands lays it out in a span long enough for it
    bands = edge_bands(10 * (s.width / 2), h, k, me.growth_rate)
    if len(bands) > 1 and region < bands[0][0] + h:  # too short for the growth
        region = bands[0][0]
    # a sliver left by the wall would be a cell much narrower than its neighbour
    return room if room - region < 1.5 * h else region


def away_from_edge(
    scene: Scene, room: float, coarse: float, k: float | None = None
) -> list[tuple[float, int, float]]:
    """Bands from an orifice edge across ``room`` [m] to the wall it faces, fine end first.

    The orifice region (:func:`edge_region`, cells widening from the edge's
    refined ones, h / ``k``, to h), then cells growing by the growth rate up
    to ``coarse`` x h (:func:`graded_segments`). ``k`` defaults to
    ``mesh.orifice_edge_refinement``; 1 leaves the region cells of h.
    """
    h, me = scene.cell_size, scene.mesh
    if k is None:
        k = me.orifice_edge_refinement
    region = edge_region(scene, room, k)
    bands = edge_bands(region, h, k, me.growth_rate)
    if room - region > 1e-9 * room:
        bands += graded_segments(room - region, h, me.growth_rate, coarse)
    return bands


def coarse_ratio(scene: Scene) -> float:
    """Largest cell size of a graded mesh over the orifice's cell size (>= 1)."""
    return max(1.0, scene.silo.width / scene.mesh.coarse_cells_across / scene.cell_size)


def similar_grading(
    cells_across: int, reference: int, growth_rate: float, coarse_cells_across: int
) -> tuple[float, int]:
    """Growth rate and largest cells of a graded mesh refined as a whole.

    A grid convergence study needs grids refined alike everywhere (Roache
    1998), not only at the orifice: with a fixed growth rate g the cells at a
    distance x beyond the orifice region are about (g - 1) x wide at every
    resolution, and the largest ones stay L / ``coarse_cells_across``, so
    their part of the error does not shrink. Refined by s = ``cells_across``
    / ``reference`` as a whole, each cell of the reference grid becomes about
    s cells: the growth rate is g^(1/s) (exactly s cells for one in the limit
    g -> 1) and the largest cells L / (s ``coarse_cells_across``).

    Parameters
    ----------
    cells_across : int
        Cells across L of the grid wanted.
    reference : int
        Cells across L of the grid whose grading is given.
    growth_rate, coarse_cells_across
        That grid's ``mesh.growth_rate`` and ``mesh.coarse_cells_across``.

    Returns
    -------
    tuple of (float, int)
        ``mesh.growth_rate`` and ``mesh.coarse_cells_across`` at ``cells_across``.

    Examples
    --------
    >>> g, c = similar_grading(144, 72, 1.1, 16)
    >>> round(g, 4), c
    (1.0488, 32)
    """
    s = cells_across / reference
    return growth_rate ** (1.0 / s), max(2, round(coarse_cells_across * s))


def _graded_rows(scene: Scene) -> list[Row]:
    """Rows of a graded mesh: square cells up to ``mesh.orifice_region`` D, then growing.

    With ``mesh.orifice_exit_refinement`` k > 1 the rows of the orifice region
    grow from h / k at the floor to h (:func:`edge_bands`), as the columns do
    from an orifice edge.
    """
    s, h, me = scene.silo, scene.cell_size, scene.mesh
    if s.orifice_position == "lateral":
        return _lateral_graded_rows(scene)
    # the region's height as an edge's region's width, the silo's height its room
    k = me.orifice_exit_refinement
    y_f = edge_region(scene, room=s.height, k=k)
    bands = edge_bands(y_f, h, k, me.growth_rate)
    rows, y = [], 0.0
    for i, (span, n, r) in enumerate(bands):
        y1 = y_f if i == len(bands) - 1 else y + span  # the region's top exactly
        rows.append(Row(y, y1, n, r))
        y = y1
    headspace = (s.height - s.fill_height) / (HEADSPACE_CELLS * h)
    y = y_f
    for span, n, r in graded_segments(
        s.height - y_f, h, me.growth_rate, max(1.0, min(coarse_ratio(scene), headspace))
    ):
        if span > 1e-12 * s.height:
            rows.append(Row(y, y + span, n, r))
        y += span
    return rows


def _lateral_graded_rows(scene: Scene) -> list[Row]:
    """Rows of a graded mesh beside a lateral orifice, from the floor to the top.

    Rows narrow towards each of the orifice's edges from both sides (to h /
    ``mesh.orifice_edge_refinement``, as a bottom orifice's columns do), the
    orifice's rows are cells of h between them, and away from the orifice
    (down to the floor, up to the top) each side has its orifice region and
    then cells growing by the growth rate, the top's capped by the headspace.
    """
    s, h, me = scene.silo, scene.cell_size, scene.mesh
    assert s.orifice_height is not None
    lo, hi = s.orifice_height, s.orifice_height + s.orifice_width
    headspace = (s.height - s.fill_height) / (HEADSPACE_CELLS * h)
    below = toward_edge(away_from_edge(scene, lo, coarse_ratio(scene))) if lo > 1e-12 else []
    if me.orifice_edge_refinement > 1.0 + 1e-12:  # narrowing to both edges
        half = edge_bands(s.orifice_width / 2, h, me.orifice_edge_refinement, me.growth_rate)
        orifice = half + toward_edge(half)
    else:
        orifice = [(s.orifice_width, max(1, round(s.orifice_width / h)), 1.0)]
    top = max(1.0, min(coarse_ratio(scene), headspace))
    above = away_from_edge(scene, s.height - hi, top) if s.height - hi > 1e-12 else []
    rows, y = [], 0.0
    for bands, end in ((below, lo), (orifice, hi), (above, s.height)):
        for i, (span, n, r) in enumerate(bands):
            y1 = end if i == len(bands) - 1 else y + span  # the edges exactly
            rows.append(Row(y, y1, n, r))
            y = y1
    return rows


def vertical_rows(scene: Scene) -> list[Row]:
    """Bands of cells from the bottom to the top of the domain.

    Square cells (of the size at the orifice) up to ``mesh.fine_height`` (or the
    silo width), band edges at every corner of the wall and at the edges of a
    lateral orifice, then cells growing to ``mesh.top_cell_ratio`` times taller
    (capped so that the headspace above the fill keeps two cells). A graded
    mesh (``mesh.growth_rate`` > 1) has square cells up to
    ``mesh.orifice_region`` orifice widths, then cells growing by the growth
    rate up to the largest cells (``mesh.coarse_cells_across``); beside a
    lateral orifice the same on both sides of it (:func:`_lateral_graded_rows`).
    """
    if scene.mesh.graded:
        return _graded_rows(scene)
    s = scene.silo
    h = scene.cell_size
    H = s.height
    cuts = {y for y, _ in s.profile if 0.0 < y < H}
    if s.orifice_position == "lateral":
        assert s.orifice_height is not None
        cuts |= {y for y in (s.orifice_height, s.orifice_height + s.orifice_width) if 0 < y < H}
    R = top_cell_ratio(scene)
    fine_top = H
    if R > 1.0:
        need = max(cuts, default=0.0)
        fine_top = max(_fine_top(scene), math.ceil(need / h - 1e-9) * h + (h if need > 0 else 0.0))
        if fine_top > H - 2 * h:
            fine_top = H
    edges = sorted({0.0, fine_top, *cuts} | ({H} if fine_top < H else set()))
    edges = [y for y in edges if y <= H]
    rows = []
    for y0, y1 in zip(edges[:-1], edges[1:], strict=True):
        if y0 >= fine_top - 1e-12:
            # a geometric series from h to R h over n cells fills the span
            n = max(2, round(((y1 - y0) / h) * math.log(R) / (R - 1)))
            rows.append(Row(y0, y1, n, R ** (1.0 / (n - 1))))
        else:
            rows.append(Row(y0, y1, max(1, round((y1 - y0) / h))))
    return rows


def slot_divisions(width: float, orifice_width: float, cells_across: int) -> tuple[int, int, int]:
    """Cells across the left wall segment, a centred orifice, and the right segment.

    The orifice gets at least two cells, and the count is nudged by one so
    that the mesh stays symmetric about the axis.
    """
    n = cells_across
    dx = width / n
    n_orf = max(2, round(orifice_width / dx))
    if (n - n_orf) % 2:
        n_orf += 1 if orifice_width / dx > n_orf else -1
    n_side = (n - n_orf) // 2
    return n_side, n_orf, n_side


# ---------------------------------------------------------------------------- profiles

Side = str | None


@dataclass(frozen=True)
class Block:
    """One structured quad block of a profile (the x-y plane, y up).

    Attributes
    ----------
    corners
        (x, y) of the bottom-left, bottom-right, top-right and top-left corners.
    cells
        Cells along x and along y.
    ratio
        Growth of the cell height per cell, upward.
    sides
        Patch of the bottom, right, top and left sides (None: inside the silo).
    x_ratio
        Growth of the cell width per cell, towards +x.
    """

    corners: tuple[tuple[float, float], ...]
    cells: tuple[int, int]
    ratio: float
    sides: tuple[Side, Side, Side, Side]
    x_ratio: float = 1.0


@dataclass(frozen=True)
class ProfileLayout:
    """The blocks of a planar or axisymmetric profile, row by row from the floor."""

    blocks: tuple[Block, ...]
    columns: tuple[int, ...]
    rows: tuple[Row, ...]
    column_ratios: tuple[float, ...] = ()

    @property
    def n_cells(self) -> int:
        """Cells of the mesh (the profile is one cell thick)."""
        return sum(self.columns) * sum(r.n for r in self.rows)


def profile_columns(scene: Scene) -> tuple[list[tuple[float, float]], list[int], list[Side]]:
    """Column edges of a planar or axisymmetric profile.

    Returns the edges as pairs (a, b) with x = a + b r(y) (r the wall's
    half-width at height y: a fixed x where b = 0, a point that follows a
    sloping wall otherwise), the cells of each column, and the patch of each
    column's bottom.
    """
    s = scene.silo
    h = scene.cell_size
    R = s.width / 2
    r_o = s.orifice_width / 2
    planar = scene.representation == "planar"
    if scene.mesh.graded:
        return _graded_columns(scene)[:3]
    if s.shape == "hopper":
        # as many cells across the outlet as there are across the orifice, but
        # never wider than COARSE_RATIO_3D cells at the top
        n = max(2, round(r_o / h), math.ceil(R / (COARSE_RATIO_3D * h)))
        if planar:
            return [(R, -1.0), (R, 0.0), (R, 1.0)], [n, n], [ORIFICE, ORIFICE]
        return [(0.0, 0.0), (0.0, 1.0)], [n], [ORIFICE]
    if planar and s.orifice_position == "bottom":  # rectangular silo, centred slot
        left, orf, right = slot_divisions(s.width, s.orifice_width, scene.cells_across)
        x1, x2 = (s.width - s.orifice_width) / 2, (s.width + s.orifice_width) / 2
        edges = [(0.0, 0.0), (x1, 0.0), (x2, 0.0), (s.width, 0.0)]
        return edges, [left, orf, right], [WALLS, ORIFICE, WALLS]
    if planar:  # rectangular silo with a lateral orifice: wall to wall
        return [(0.0, 0.0), (0.0, 2.0)], [scene.cells_across], [WALLS]
    # axisymmetric flat-bottomed cylinder: the axis, the orifice edge, the wall
    n1 = max(1, round(r_o / h))
    n2 = max(1, round((R - r_o) / h))
    return [(0.0, 0.0), (0.0, r_o / R), (0.0, 1.0)], [n1, n2], [ORIFICE, WALLS]


def _graded_columns(
    scene: Scene,
) -> tuple[list[tuple[float, float]], list[int], list[Side], list[float]]:
    """Columns of a graded profile: the orifice, its region, then cells growing to the wall.

    Beside a lateral orifice (in the right wall) the columns are cells of h
    across the orifice region, then grow towards the left wall. Returns the
    edges, cells and bottom patches as :func:`profile_columns`, and each
    column's growth of the cell width towards +x.
    """
    s, h, me = scene.silo, scene.cell_size, scene.mesh
    if s.orifice_position == "lateral":
        # the orifice in the right wall: the columns are not refined towards
        # it (its edges are, by the rows), as a bottom orifice's rows are not
        bands = toward_edge(away_from_edge(scene, s.width, coarse_ratio(scene), k=1.0))
        xs = [0.0]
        for span, _, _ in bands:
            xs.append(xs[-1] + span)
        xs[-1] = s.width
        return (
            [(x, 0.0) for x in xs],
            [n for _, n, _ in bands],
            [WALLS] * len(bands),
            [r for _, _, r in bands],
        )
    R, r_o = s.width / 2, s.orifice_width / 2
    k = me.orifice_edge_refinement
    # from the orifice's edge to the wall: the orifice region (widening from the
    # edge's refined cells), then growth
    outward = away_from_edge(scene, R - r_o, coarse_ratio(scene))
    # from the orifice's edge inward: the orifice's cells widen towards its centre
    if k <= 1.0 + 1e-12:  # unrefined: the orifice is one column of cells of h
        n_o = max(1, round(r_o / h)) if scene.representation == "axisymmetric" else None
        inward = [(r_o, n_o, 1.0)] if n_o else []
    else:
        inward = edge_bands(r_o, h, k, me.growth_rate)
    # from the centre (axis) to the wall: cells narrow towards the edge, then widen
    half = toward_edge(inward) + outward
    sides: list[Side] = [*([ORIFICE] * len(inward)), *([WALLS] * len(outward))]
    if scene.representation == "axisymmetric":
        xs = [0.0]
        for i, (span, _, _) in enumerate(half):
            xs.append(r_o if i == len(inward) - 1 else xs[-1] + span)
        xs[-1] = R
        return [(x, 0.0) for x in xs], [n for _, n, _ in half], sides, [r for _, _, r in half]
    # planar, centred slot: the right half mirrored on the left; unrefined,
    # one column of cells across the whole slot
    n_mid = 0 if inward else max(2, round(s.orifice_width / h))
    centre = r_o if n_mid else 0.0
    left_x = [R - centre]
    for span, _, _ in half:
        left_x.append(left_x[-1] - span)
    left_x[-1] = 0.0
    right_x = [R + centre]
    for span, _, _ in half:
        right_x.append(right_x[-1] + span)
    right_x[-1] = s.width
    xs = [*reversed(left_x), *(right_x if n_mid else right_x[1:])]
    mid = [(0.0, n_mid, 1.0)] if n_mid else []
    ns = [n for _, n, _ in [*reversed(half), *mid, *half]]
    rs = [1.0 / r for _, _, r in reversed(half)] + [r for _, _, r in [*mid, *half]]
    bottoms = [*reversed(sides), *([ORIFICE] if n_mid else []), *sides]
    return [(x, 0.0) for x in xs], ns, bottoms, rs


def profile_layout(scene: Scene) -> ProfileLayout:
    """Quad blocks of a planar or axisymmetric profile, sides labelled with their patch.

    Blocks are listed row by row from the floor, left to right. The left side
    of an axisymmetric profile is the axis; the right side of the last column
    is the wall, or the orifice in the rows of a lateral orifice.
    """
    s = scene.silo
    rows = vertical_rows(scene)
    if scene.mesh.graded:
        edges, ncols, bottoms, x_ratios = _graded_columns(scene)
    else:
        edges, ncols, bottoms = profile_columns(scene)
        x_ratios = [1.0] * len(ncols)
    axisymmetric = scene.representation == "axisymmetric"

    def x(edge: tuple[float, float], y: float) -> float:
        a, b = edge
        return a if b == 0.0 else a + b * s.wall_radius(y)

    def right_side(row: Row) -> Side:
        if s.orifice_position == "lateral":
            assert s.orifice_height is not None
            lo, hi = s.orifice_height, s.orifice_height + s.orifice_width
            if row.y0 >= lo - 1e-12 and row.y1 <= hi + 1e-12:
                return ORIFICE
        return WALLS

    blocks = []
    last_row, last_col = len(rows) - 1, len(ncols) - 1
    for j, row in enumerate(rows):
        for i, n in enumerate(ncols):
            ea, eb = edges[i], edges[i + 1]
            corners = (
                (x(ea, row.y0), row.y0),
                (x(eb, row.y0), row.y0),
                (x(eb, row.y1), row.y1),
                (x(ea, row.y1), row.y1),
            )
            bottom = bottoms[i] if j == 0 else None
            top = ATMOSPHERE if j == last_row else None
            left = (AXIS if axisymmetric else WALLS) if i == 0 else None
            right = right_side(row) if i == last_col else None
            sides = (bottom, right, top, left)
            blocks.append(Block(corners, (n, row.n), row.ratio, sides, x_ratios[i]))
    return ProfileLayout(tuple(blocks), tuple(ncols), tuple(rows), tuple(x_ratios))


# ---------------------------------------------------------------------------- 3D cross-sections


@dataclass(frozen=True)
class OGrid:
    """Structured O-grid of a disk (cross-section in the x-z plane).

    A central square (corners at ``square`` x the first ring radius), then
    rings out to each radius in ``rings``; quadrants centred on +x, +z, -x,
    -z. ``arcs`` gives, per quadrant, the angular segments (start, end, cells)
    between the quadrant's corners. ``orifice_rings`` rings from the centre
    (and the square) make the bottom orifice; ``lateral_arc`` is the angular
    segment of the wall that is a lateral orifice (or None). ``floored``: a
    count was raised to its floor (``MIN_QUADRANT_CELLS`` on a quarter
    circle, an arc beside a lateral orifice no wider in angle than those,
    two radial cells) above what the cell size asks for, so the
    cross-section is finer than the scene's cells across say; such a grid is
    not one refinement family with finer ones.
    """

    rings: tuple[float, ...]
    ring_cells: tuple[tuple[int, float], ...]
    arcs: tuple[tuple[tuple[float, float, int], ...], ...]
    orifice_rings: int = 0
    lateral_arc: tuple[float, float] | None = None
    square: float = 0.6
    floored: bool = False

    @property
    def n_cells(self) -> int:
        """Cells in the cross-section."""
        na = sum(n for _, _, n in self.arcs[0])
        nb = sum(n for _, _, n in self.arcs[1])
        around = 2 * (na + nb)
        return na * nb + around * sum(n for n, _ in self.ring_cells)


def widest_arc_cells(angle: float) -> int:
    """Fewest cells on a wall arc of ``angle`` radians: none wider than a floored quarter's.

    The floor is an angle, the polygon's fidelity to the circle, so that an
    arc beside a lateral orifice is held no finer than the quarters are (a
    count as floor would hold a narrow arc fixed, finer than its cells say,
    on every grid a study affords).
    """
    return math.ceil(angle / (math.pi / 2 / MIN_QUADRANT_CELLS) - 1e-9)


def ogrid_for(scene: Scene) -> OGrid:
    """Lay out the O-grid of a cylinder's (or a 3D hopper's top) cross-section."""
    s = scene.silo
    h = scene.cell_size
    R = s.width / 2
    coarse = COARSE_RATIO_3D * h
    q = math.pi / 4
    if s.orifice_position == "lateral":
        arc = s.lateral_arc_length
        assert arc is not None
        tw = arc / (2 * R)
        raw = (
            round(arc / h),
            round((q - tw) * R / (2 * h)),
            round(2 * q * R / (2 * h)),
            round((1 - 0.6) * R / h),
        )
        floors = (
            max(2, widest_arc_cells(2 * tw)),
            max(1, widest_arc_cells(q - tw)),
            MIN_QUADRANT_CELLS,
            2,
        )
        n_orf, n_side, n_b, n_r = (max(f, n) for f, n in zip(floors, raw, strict=True))
        quad0 = ((-q, -tw, n_side), (-tw, tw, n_orf), (tw, q, n_side))
        n_a = 2 * n_side + n_orf
        return OGrid(
            (R,),
            ((n_r, 1.0),),
            (quad0, ((q, 3 * q, n_b),), ((3 * q, 5 * q, n_a),), ((5 * q, 7 * q, n_b),)),
            lateral_arc=(-tw, tw),
            floored=any(n < f for f, n in zip(floors, raw, strict=True)),
        )
    r_o = s.orifice_width / 2
    n_size = max(round(q * 2 * r_o / h), math.ceil(2 * q * R / coarse))
    n_q = max(MIN_QUADRANT_CELLS, n_size)
    floored = n_size < MIN_QUADRANT_CELLS
    arcs = tuple(((q * (2 * k - 1), q * (2 * k + 1), n_q),) for k in range(4))
    if s.shape == "hopper":  # the whole bottom is the outlet; radii scale down to it
        size = 2 * q * r_o / n_q  # arc cell at the outlet
        n_r = max(2, round((1 - 0.6) * r_o / size))
        return OGrid((R,), ((n_r, 1.0),), arcs, orifice_rings=1, floored=floored)
    # flat bottom, centred orifice: a ring ends on the orifice edge, then the
    # cells grow towards the wall up to the arc spacing there
    size = 2 * q * r_o / n_q
    n_r1 = max(1, round((1 - 0.6) * r_o / max(size, 0.8 * h)))
    first = (1 - 0.6) * r_o / n_r1
    last = min(coarse, max(first, 2 * q * R / n_q))
    k = scene.mesh.orifice_edge_refinement
    if k <= 1.0 + 1e-12:
        n_r2, g2 = _growth(R - r_o, first, last)
        return OGrid((r_o, R), ((n_r1, 1.0), (n_r2, g2)), arcs, orifice_rings=1, floored=floored)
    # the orifice's edge refined: radial cells narrow to first / k on both
    # sides of it (as a profile's columns, edge_bands), then grow to the wall
    growth = scene.mesh.growth_rate
    inward = edge_bands((1 - 0.6) * r_o, first, k, growth)  # listed from the edge
    radii, cells = [], []
    r = r_o - sum(span for span, _, _ in inward)
    for span, n, ratio in toward_edge(inward):
        r += span
        radii.append(r)
        cells.append((n, ratio))
    radii[-1] = r_o
    outward = edge_bands(R - r_o, first, k, growth)
    if len(outward) > 1:  # after the growth to `first`, cells grow on to the wall
        span = outward.pop()[0]
        outward += graded_segments(span, first, growth, max(1.0, last / first))
    for span, n, ratio in outward:
        radii.append(radii[-1] + span)
        cells.append((n, ratio))
    radii[-1] = R
    return OGrid(tuple(radii), tuple(cells), arcs, orifice_rings=len(inward), floored=floored)


def o_grid_floored(scene: Scene) -> bool:
    """Whether the scene's 3D O-grid holds a count at its floor (finer than its cells say).

    Such a grid is no refinement family with finer ones: a grid study or a
    convergence series leaves it out. False for any other mesh.
    """
    s = scene.silo
    if scene.representation != "3d" or s.shape == "rectangular" or s.eccentricity > 0:
        return False
    return ogrid_for(scene).floored


def cells_estimate(scene: Scene) -> int:
    """Return the number of cells the scene's mesh will have (structured meshes exactly)."""
    s = scene.silo
    rep = scene.representation
    rows = vertical_rows(scene)
    layers = sum(r.n for r in rows)
    if rep in ("planar", "axisymmetric"):
        return profile_layout(scene).n_cells
    h = scene.cell_size
    if s.shape == "rectangular":
        W = s.thickness or h
        return scene.cells_across * max(2, round(W / h)) * layers
    if s.eccentricity > 0:
        # unstructured: cross-section area over the mean cell area, roughly
        return round(math.pi * (s.width / 2) ** 2 / (2 * h) ** 2) * layers
    return ogrid_for(scene).n_cells * layers
