"""Mesh layout (pure geometry, no gmsh run): rows, blocks and their patches."""

from __future__ import annotations

import math

import numpy as np
import pytest

from foamsilo.mesh import profile_layout, slot_divisions, top_cell_ratio, vertical_rows
from foamsilo.scene import load_preset

#: The mesh keys' defaults, a uniform mesh (the planar and lab silo presets are
#: graded since issue 18)
MESH_DEFAULTS = {
    "mesh.growth_rate": 1.0,
    "mesh.orifice_edge_refinement": 1.0,
    "mesh.orifice_exit_refinement": 1,
    "mesh.orifice_region": 1.0,
    "mesh.coarse_cells_across": 16,
}


def _uniform(preset: str, n: int, sets: dict[str, object]):
    """``preset`` at ``n`` across, on the uniform mesh unless ``sets`` grade it."""
    sets = {**MESH_DEFAULTS, **sets}
    return load_preset(preset, [f"mesh.cells_across={n}", *[f"{k}={v}" for k, v in sets.items()]])


def planar(n: int, **sets: object):
    """The planar silo at ``n`` across, on the uniform mesh unless ``sets`` grade it."""
    return _uniform("zhou-planar", n, sets)


def lab_silo(n: int, **sets: object):
    """The lab silo at ``n`` across, on the uniform mesh unless ``sets`` grade it."""
    return _uniform("zhou-cyl-bottom", n, sets)


def test_uniform_mesh_counts():
    scene = planar(64, **{"mesh.top_cell_ratio": 1.0})
    assert slot_divisions(0.1, 0.025, 64) == (24, 16, 24)
    rows = vertical_rows(scene)
    assert len(rows) == 1 and rows[0].n == 256 and rows[0].ratio == 1.0
    assert profile_layout(scene).n_cells == 64 * 256


def test_orifice_divisions_stay_symmetric():
    # D/dx = 5.2 cells: rounded to keep the mesh symmetric about the axis
    left, orifice, right = slot_divisions(0.1, 0.026, 20)
    assert left == right and left + orifice + right == 20


@pytest.mark.parametrize("ratio", [2.0, 3.0, 5.0])
def test_graded_mesh_fills_the_height_with_the_requested_ratio(ratio):
    # a low fill leaves room for the full ratio in the headspace
    scene = planar(64, **{"mesh.top_cell_ratio": ratio, "silo.fill_height": 0.2})
    dx = 0.1 / 64
    fine, graded = vertical_rows(scene)
    assert fine.y1 == pytest.approx(0.1)  # default: square cells up to one width
    heights = [dx * graded.ratio**k for k in range(graded.n)]
    # cell heights dx r^k, k = 0..n-1, fill the rest of the height ...
    assert sum(heights) == pytest.approx(0.4 - fine.y1, rel=0.03)
    # ... and the last one is ratio cell widths high
    assert heights[-1] / dx == pytest.approx(ratio)
    assert profile_layout(scene).n_cells < 64 * 256


def test_grading_keeps_grains_out_of_the_top_row():
    """The top cells may not be taller than half the gap above the fill."""
    for n in (16, 32, 64, 128):
        scene = planar(n)
        ratio = top_cell_ratio(scene)
        if ratio > 1.0:
            assert 0.1 / n * ratio <= (0.4 - 0.39) / 2 + 1e-12
    # 16 across: no room in a 10 mm headspace, the mesh stays uniform
    assert top_cell_ratio(planar(16)) == 1.0
    # 128 across: the full ratio fits
    assert top_cell_ratio(planar(128)) == 3.0


def test_blocks_carry_their_patches():
    """The planar slot: orifice under the middle column, walls beside, atmosphere on top."""
    layout = profile_layout(planar(16))
    bottoms = [b.sides[0] for b in layout.blocks if b.corners[0][1] == 0.0]
    assert bottoms == ["walls", "orifice", "walls"]
    tops = {b.sides[2] for b in layout.blocks if b.corners[2][1] == pytest.approx(0.4)}
    assert tops == {"atmosphere"}
    inner = [b.sides[1] for b in layout.blocks[:-1] if b.corners[1][0] < 0.1]
    assert set(inner) == {None}  # sides between blocks are inside the silo


def test_wedge_axis_and_lateral_orifice_sides():
    wedge = profile_layout(lab_silo(24))
    assert {b.sides[3] for b in wedge.blocks if b.corners[0][0] == 0.0} == {"axis"}
    lateral = profile_layout(load_preset("zhou-rect-lateral"))
    s = load_preset("zhou-rect-lateral").silo
    right = [
        (b.corners[1][1], b.corners[2][1], b.sides[1])
        for b in lateral.blocks
        if b.corners[1][0] == pytest.approx(s.width)  # the right wall's column
    ]
    assert len(right) == len(lateral.rows)
    for y0, y1, side in right:
        inside = y0 >= s.orifice_height - 1e-12 and y1 <= s.orifice_height + s.orifice_width + 1e-12
        assert side == ("orifice" if inside else "walls")


@pytest.mark.parametrize("growth", [1.05, 1.1, 1.2])
@pytest.mark.parametrize("span", [0.3, 2.0, 40.0])
def test_graded_bands_fill_the_span_and_grow_smoothly(growth, span):
    from foamsilo.mesh.layout import graded_segments

    h, coarse = 0.1, 6.0
    bands = graded_segments(span, h, growth, coarse)
    sizes = []
    for length, n, r in bands:
        first = length * (r - 1) / (r**n - 1) if abs(r - 1) > 1e-12 else length / n
        cells = [first * r**k for k in range(n)]
        assert sum(cells) == pytest.approx(length, rel=1e-9)
        sizes += cells
    assert sum(length for length, _, _ in bands) == pytest.approx(span, rel=1e-12)
    # from the fine cell next to the span on, no jump above the growth rate
    # within the growing band; the uniform rest (whole cells of about the
    # coarse size) joins it within 1.5 x either way
    steps = [b / a for a, b in zip([h, *sizes[:-1]], sizes, strict=True)]
    n_grow = bands[0][1]
    assert max(steps[:n_grow]) <= growth * (1 + 1e-9)
    assert all(1 / 1.5 <= x <= 1.5 for x in steps[n_grow:])
    assert max(sizes) <= coarse * h * 1.5


def _rows_between(scene, a: float, b: float) -> int:
    """Rows of cells whose centres lie between heights a and b."""
    edges = [0.0]
    for r in vertical_rows(scene):
        edges += [r.y0 + (r.y1 - r.y0) * f for f in r.heights()]
    return sum(a <= (y0 + y1) / 2 < b for y0, y1 in zip(edges, edges[1:], strict=False))


def test_a_graded_mesh_refined_as_a_whole_refines_beyond_the_orifice_region():
    from foamsilo.mesh.layout import similar_grading

    fixed = {"mesh.growth_rate": 1.1, "mesh.coarse_cells_across": 16}
    base = lab_silo(72, **fixed)
    for n in (144, 216):
        g, c = similar_grading(n, 72, 1.1, 16)
        alike = lab_silo(n, **{"mesh.growth_rate": g, "mesh.coarse_cells_across": c})
        kept = lab_silo(n, **fixed)
        s = n / 72
        # in the orifice region (up to 1 D = 0.01 m), the growth (1-3 D) and
        # the column above: s times the rows of the 72-across grid, to a cell
        # or two at each band's ends
        for a, b in [(0.0, 0.01), (0.01, 0.03), (0.03, 0.1), (0.1, 0.54)]:
            assert _rows_between(alike, a, b) / _rows_between(base, a, b) == pytest.approx(
                s, rel=0.1
            )
        # the growth rate and the largest cells kept: 3-10 D above the floor
        # the grid is not refined at all
        assert _rows_between(kept, 0.03, 0.1) <= _rows_between(base, 0.03, 0.1) + 1
        assert _rows_between(kept, 0.1, 0.54) <= _rows_between(base, 0.1, 0.54)


def test_a_graded_profile_keeps_the_orifice_cells_and_spends_fewer_elsewhere():
    lab = [lab_silo(72, **{"mesh.growth_rate": g}) for g in (1.0, 1.1)]
    for uniform_scene, graded_scene in ((planar(72), planar(72, **{"mesh.growth_rate": 1.1})), lab):
        uniform = profile_layout(uniform_scene)
        graded = profile_layout(graded_scene)
        orifice = [b.cells[0] for b in graded.blocks if b.sides[0] == "orifice"]
        assert orifice == [b.cells[0] for b in uniform.blocks if b.sides[0] == "orifice"]
        assert graded.n_cells < 0.6 * uniform.n_cells
        # the rows near the floor are the uniform mesh's square cells
        assert graded.rows[0].ratio == 1.0 and graded.rows[0].y1 >= 0.01 - 1e-12
        # the widths grow away from the orifice on both sides of a slot
        assert all(r >= 1.0 for r in graded.column_ratios[len(graded.columns) // 2 :])


def test_graded_meshes_only_where_they_are_built():
    from foamsilo.errors import SceneError

    with pytest.raises(SceneError, match=r"mesh\.growth_rate.*allowed here: 1"):
        load_preset("venier-test2", ["mesh.growth_rate=1.1"])  # eccentric outlet
    with pytest.raises(SceneError, match=r"mesh\.growth_rate"):
        load_preset("zhou-planar", ["mesh.growth_rate=2"])
    with pytest.raises(SceneError, match=r"mesh\.growth_rate.*allowed here: 1"):
        load_preset("zhou-rect-lateral", ["mesh.representation='3d'", "silo.thickness=0.01",
                                          "material.wall_friction=", "gas.mode='open-top'",
                                          "gas.q_air_lpm=", "gas.q_air_scaled=",
                                          "mesh.orifice_edge_refinement=1"])  # fmt: skip
    with pytest.raises(SceneError, match=r"mesh\.growth_rate.*allowed here: 1"):
        load_preset("hopper-conical", ["mesh.growth_rate=1.1"])


@pytest.mark.parametrize("preset", ["zhou-cyl-lateral", "zhou-cyl-lateral-rect"])
@pytest.mark.parametrize("n", [24, 40, 56])
@pytest.mark.parametrize("k", [1.0, 4.0])
def test_a_3d_lateral_orifice_s_rows_are_graded_from_its_edges(preset, n, k):
    """A cylinder's lateral orifice: the rows narrow to h / k at its two edges and grow away.

    The rows of the orifice's band end at its edges exactly (the band that
    the sweep makes the orifice), no row of the orifice region is higher
    than h, neighbours differ by at most the growth rate (squared where a
    growing band meets the region), and the O-grid's cross-section is the
    uniform mesh's, so the graded mesh has fewer cells only by its rows.
    """
    from foamsilo.mesh import ogrid_for
    from foamsilo.mesh.layout import cells_estimate, edge_region

    g = 1.15
    base = [f"mesh.cells_across={n}"]
    scene = load_preset(preset, [*base, f"mesh.growth_rate={g}", "mesh.coarse_cells_across=6",
                                 "mesh.orifice_region=0.5", f"mesh.orifice_edge_refinement={k}"])  # fmt: skip
    uniform = load_preset(preset, [*base, "mesh.growth_rate=1", "mesh.coarse_cells_across=16",
                                   "mesh.orifice_region=1"])  # fmt: skip
    s, h = scene.silo, scene.cell_size
    assert s.orifice_height is not None
    lo, hi = s.orifice_height, s.orifice_height + s.orifice_width
    rows = vertical_rows(scene)
    edges = [r.y0 for r in rows] + [rows[-1].y1]
    assert min(abs(e - lo) for e in edges) < 1e-12 and min(abs(e - hi) for e in edges) < 1e-12
    # the node heights from each row's own layer fractions (what the sweep extrudes)
    ys_a = np.array([0.0] + [r.y0 + (r.y1 - r.y0) * f for r in rows for f in r.heights()])
    hs_a = np.diff(ys_a)
    assert ys_a[-1] == pytest.approx(s.height, rel=1e-12)
    for e in (lo, hi):
        i = int(np.argmin(np.abs(ys_a - e)))
        assert ys_a[i] == pytest.approx(e, abs=1e-12)
        assert hs_a[i - 1] == pytest.approx(h / k, rel=0.15)
        assert hs_a[i] == pytest.approx(h / k, rel=0.15)
    mid = (ys_a[:-1] + ys_a[1:]) / 2
    below, above = edge_region(scene, room=lo), edge_region(scene, room=s.height - hi)
    region = (mid > lo - below) & (mid < hi + above)
    # (whole rows fill the orifice's height: h to within half a row over its rows)
    assert hs_a[region].max() <= h * (1 + 0.5 * h / s.orifice_width + 1e-9)
    steps = hs_a[1:] / hs_a[:-1]
    assert np.all(np.maximum(steps, 1 / steps) <= g**2 * 1.01)
    assert ogrid_for(scene) == ogrid_for(uniform)
    # the rows' savings (the edges' own rows cost some back)
    assert cells_estimate(scene) < (0.7 if k == 1 else 0.8) * cells_estimate(uniform)


@pytest.mark.parametrize("preset", ["zhou-planar", "zhou-cyl-bottom"])
@pytest.mark.parametrize("n", [24, 36, 48, 72, 144])
@pytest.mark.parametrize("k", [2.0, 4.0, 8.0])
def test_the_orifice_edge_columns_narrow_smoothly_to_h_over_k(preset, n, k):
    scene = load_preset(
        preset,
        [f"mesh.cells_across={n}", "mesh.growth_rate=1.1", f"mesh.orifice_edge_refinement={k}"],
    )
    lay = profile_layout(scene)
    h, s = scene.cell_size, scene.silo
    planar = scene.representation == "planar"
    floor = [b for b in lay.blocks if b.corners[0][1] == 0.0]
    widths, bottoms = [], []
    for b in floor:
        (x0, _), (x1, _) = b.corners[0], b.corners[1]
        n_x, r = b.cells[0], b.x_ratio
        w = [r**j for j in range(n_x)]
        widths += [(x1 - x0) * c / sum(w) for c in w]
        bottoms += [b.sides[0]] * n_x
    widths_a = np.array(widths)
    x = np.concatenate([[0.0], np.cumsum(widths_a)])
    assert x[-1] == pytest.approx(s.width if planar else s.width / 2, rel=1e-12)
    # the orifice patch is the orifice, exactly
    lo, hi = ((s.width - s.orifice_width) / 2, (s.width + s.orifice_width) / 2) if planar else (
        0.0, s.orifice_width / 2)  # fmt: skip
    on = [i for i, side in enumerate(bottoms) if side == "orifice"]
    assert x[on[0]] == pytest.approx(lo, abs=1e-12) and x[on[-1] + 1] == pytest.approx(hi)
    # the narrowest cells (h / k to the few % that fit the band) touch the edges
    edges = [hi] if not planar else [lo, hi]
    for e in edges:
        i = int(np.argmin(np.abs(x - e)))
        for c in (widths_a[i - 1], widths_a[i]):
            assert c == pytest.approx(h / k, rel=0.05)
    assert widths_a.min() >= h / k * 0.95
    # the cells widen smoothly: by at most the growth rate per cell within a
    # band, within 1.3x where a band meets the next; no orifice cell wider than h
    steps = widths_a[1:] / widths_a[:-1]
    assert np.all(np.maximum(steps, 1 / steps) <= 1.3)
    assert max(widths_a[on]) <= h * (1 + 1e-9)
    assert lay.n_cells == sum(lay.columns) * sum(r.n for r in lay.rows)


@pytest.mark.parametrize("n", [24, 32, 48, 96, 128, 192])
@pytest.mark.parametrize("k", [1.0, 4.0])
def test_a_lateral_orifice_s_rows_narrow_to_its_edges_and_the_columns_grow_from_it(n, k):
    scene = load_preset(
        "zhou-rect-lateral",
        [f"mesh.cells_across={n}", "mesh.growth_rate=1.1", f"mesh.orifice_edge_refinement={k}"],
    )
    lay = profile_layout(scene)
    h, s = scene.cell_size, scene.silo
    lo, hi = s.orifice_height, s.orifice_height + s.orifice_width
    # the rows' heights from the floor to the top, and the right wall's patches
    heights, right = [], []
    for row, b in zip(lay.rows, [b for b in lay.blocks if b.sides[1] is not None], strict=True):
        w = [row.ratio**j for j in range(row.n)]
        heights += [(row.y1 - row.y0) * c / sum(w) for c in w]
        right += [b.sides[1]] * row.n
    y = np.concatenate([[0.0], np.cumsum(heights)])
    assert y[-1] == pytest.approx(s.height, rel=1e-12)
    # the orifice patch is the orifice, exactly
    on = [i for i, side in enumerate(right) if side == "orifice"]
    assert on == list(range(on[0], on[-1] + 1))
    assert y[on[0]] == pytest.approx(lo, abs=1e-12) and y[on[-1] + 1] == pytest.approx(hi)
    # the rows touching each edge, above and below it, are h / k high (to the
    # few % that fit the band); none is lower, none in the orifice higher than h
    # (unrefined, the orifice is whole cells of about h: half a cell in D / h)
    hs = np.array(heights)
    tol = 0.05 if k > 1 else 0.5 * h / s.orifice_width
    for e in (lo, hi):
        i = int(np.argmin(np.abs(y - e)))
        for c in (hs[i - 1], hs[i]):
            assert c == pytest.approx(h / k, rel=tol)
    assert hs.min() >= h / k * (1 - tol)
    assert max(hs[on]) <= h * (1 + tol)
    # smooth: within 1.3x from row to row, by at most the growth rate within a band
    steps = hs[1:] / hs[:-1]
    assert np.all(np.maximum(steps, 1 / steps) <= 1.3)
    # the columns are h wide at the orifice's wall and grow by at most the
    # growth rate towards the far wall, up to about L / coarse_cells_across
    # (the rest after the growth is whole cells of about that size)
    widths = []
    for b in lay.blocks[: len(lay.columns)]:
        (x0, _), (x1, _) = b.corners[0], b.corners[1]
        w = [b.x_ratio**j for j in range(b.cells[0])]
        widths += [(x1 - x0) * c / sum(w) for c in w]
    ws = np.array(widths[::-1])  # from the orifice's wall
    assert sum(ws) == pytest.approx(s.width, rel=1e-12)
    d = round(s.orifice_width / h)  # the orifice region: one D of cells of h
    assert ws[:d] == pytest.approx(np.full(d, h), rel=1e-9)
    grow = ws[1:] / ws[:-1]
    assert np.all(np.maximum(grow, 1 / grow) <= 1.3)
    assert ws.max() <= 1.5 * s.width / scene.mesh.coarse_cells_across
    # and on fine grids it spends far fewer cells than the uniform mesh
    assert lay.n_cells == sum(lay.columns) * sum(r.n for r in lay.rows)
    if n >= 96:
        flat = [f"mesh.cells_across={n}", "mesh.growth_rate=1", "mesh.orifice_edge_refinement=1"]
        uniform = profile_layout(load_preset("zhou-rect-lateral", flat))
        assert lay.n_cells < 0.3 * uniform.n_cells


def test_the_orifice_edge_is_refined_only_on_graded_meshes():
    from foamsilo.errors import SceneError

    with pytest.raises(SceneError, match=r"mesh\.orifice_edge_refinement.*allowed here: 1"):
        lab_silo(72, **{"mesh.orifice_edge_refinement": 4})  # uniform
    with pytest.raises(SceneError, match=r"mesh\.orifice_edge_refinement.*allowed here: 1"):
        load_preset("venier-test2", ["mesh.orifice_edge_refinement=4"])  # eccentric, uniform
    with pytest.raises(SceneError, match=r"mesh\.orifice_edge_refinement"):
        load_preset("zhou-cyl-bottom", ["mesh.growth_rate=1.1", "mesh.orifice_edge_refinement=0.5"])


@pytest.mark.parametrize("preset", ["zhou-planar", "zhou-cyl-bottom", "venier-test1"])
@pytest.mark.parametrize(
    ("growth", "region", "n"),
    [(1.1, 1.0, 24), (1.1, 1.0, 48), (1.1, 1.0, 96), (1.1, 1.0, 192),
     (1.2, 0.5, 96), (1.2, 0.5, 192)],
)  # fmt: skip
@pytest.mark.parametrize("k", [2.0, 4.0])
def test_the_exit_rows_grow_smoothly_from_h_over_k_at_the_floor(preset, growth, region, n, k):
    # (the lab silo's preset refines its exit's rows: the plain rows without)
    base = [f"mesh.cells_across={n}", f"mesh.growth_rate={growth}",
            f"mesh.orifice_region={region}", "mesh.orifice_exit_refinement=1"]  # fmt: skip
    scene = load_preset(preset, [*base, f"mesh.orifice_exit_refinement={k}"])
    plain = vertical_rows(load_preset(preset, base))
    rows = vertical_rows(scene)
    h, s = scene.cell_size, scene.silo
    heights = []
    for row in rows:
        w = [row.ratio**j for j in range(row.n)]
        heights += [(row.y1 - row.y0) * c / sum(w) for c in w]
    hs = np.array(heights)
    assert sum(hs) == pytest.approx(s.height, rel=1e-12)
    # the floor's row is h / k high (to the 15% that fit the band of growing
    # rows into whole cells of h), none lower
    assert hs[0] == pytest.approx(h / k, rel=0.15) and hs.min() >= h / k * 0.95
    # they grow by at most the growth rate a row within a band; where the
    # growing band meets the graded rows above, its last row (about h / g)
    # meets their first (about h g)
    steps = hs[1:] / hs[:-1]
    assert np.all(np.maximum(steps, 1 / steps) <= max(1.3, growth**2 * 1.01))
    # no row of the orifice region higher than h; above it the unrefined rows,
    # unless the region was too low for the whole growth and took its height
    top = plain[0].y1
    region_rows = hs[np.cumsum(hs) <= top * (1 + 1e-9)]
    assert region_rows.max() <= h * (1 + 1e-9)

    def above(rs, y):
        return [(r.n, round(r.ratio, 9), round(r.y1, 12)) for r in rs if r.y0 >= y - 1e-9]

    widened = next(r.y0 for r in rows if r.y0 >= top - 1e-9) > top + 1e-9
    assert widened or above(rows, top) == above(plain, top)
    assert not widened or n <= 48  # only coarse grids lack the room
    # at most a few rows more than without the refinement
    assert (
        0 < sum(r.n for r in rows) - sum(r.n for r in plain) <= 2 * math.log(k) / math.log(growth)
    )


def test_the_exit_rows_are_refined_only_on_graded_meshes_of_a_bottom_orifice():
    from foamsilo.errors import SceneError

    match = r"mesh\.orifice_exit_refinement.*allowed here: 1"
    with pytest.raises(SceneError, match=match):
        lab_silo(72, **{"mesh.orifice_exit_refinement": 2})  # uniform
    with pytest.raises(SceneError, match=match):
        load_preset("zhou-rect-lateral", ["mesh.growth_rate=1.1",
                                          "mesh.orifice_exit_refinement=2"])  # fmt: skip
    with pytest.raises(SceneError, match=r"mesh\.orifice_exit_refinement.*>= 1"):
        load_preset("zhou-cyl-bottom", ["mesh.orifice_exit_refinement=0.5"])


@pytest.mark.parametrize("preset", ["zhou-cyl-lateral", "zhou-cyl-lateral-rect"])
def test_the_arcs_beside_a_lateral_orifice_refine_with_the_cells(preset):
    """Each arc of the orifice's quadrant follows the cell size above an angular floor.

    The floor is the widest cell angle a quarter circle may hold (its 12
    cells), so that an arc beside the orifice is never held finer than the
    rest of the wall, and a refinement study's regular grids start where the
    quarters' own floor ends.
    """
    from foamsilo.mesh import ogrid_for
    from foamsilo.mesh.layout import MIN_QUADRANT_CELLS

    widest = (np.pi / 2) / MIN_QUADRANT_CELLS

    def quadrant(n):
        og = ogrid_for(load_preset(preset, [f"mesh.cells_across={n}"]))
        return og, [(b - a, c) for a, b, c in og.arcs[0]]

    for n in range(12, 97, 4):
        og, arcs = quadrant(n)
        for angle, cells in arcs:
            assert angle / cells <= widest * (1 + 1e-9)  # the polygon's fidelity
        # a regular grid: every arc and the quarters above their floors
        if n >= 36:
            assert not og.floored, n
    # the arcs beside the orifice double with the cells across (to a cell's rounding)
    side = {n: quadrant(n)[1][0][1] for n in (48, 96)}
    assert abs(side[96] - 2 * side[48]) <= 1, side
