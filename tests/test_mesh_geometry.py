"""Planar silo mesh layout (pure geometry, no gmsh run)."""

from __future__ import annotations

import pytest

from foamsilo.mesh import PlanarSilo


def test_uniform_mesh_counts():
    g = PlanarSilo(0.1, 0.4, 0.025, 64)
    assert g.divisions == (24, 16, 24)
    assert g.cells_high == 256 and g.n_cells == 64 * 256
    assert not g.graded and g.thickness == pytest.approx(0.1 / 64)


def test_orifice_divisions_stay_symmetric():
    # D/dx = 5.2 cells: rounded to keep the mesh symmetric about the axis
    g = PlanarSilo(0.1, 0.4, 0.026, 20)
    left, orifice, right = g.divisions
    assert left == right and left + orifice + right == 20


@pytest.mark.parametrize("ratio", [2.0, 3.0, 5.0])
def test_graded_mesh_fills_the_height_with_the_requested_ratio(ratio):
    g = PlanarSilo(0.1, 0.4, 0.025, 64, top_cell_ratio=ratio)
    dx = 0.1 / 64
    n, r = g.grading
    assert g.fine_top == pytest.approx(0.1)  # default: square cells up to one width
    # cell heights dx r^k, k = 0..n-1, fill the rest of the height ...
    heights = [dx * r**k for k in range(n)]
    assert sum(heights) == pytest.approx(0.4 - g.fine_top, rel=0.03)
    # ... and the last one is ratio cell widths high
    assert heights[-1] / dx == pytest.approx(ratio)
    assert g.n_cells < 64 * 256


def test_grading_keeps_grains_out_of_the_top_row():
    """The top cells may not be taller than half the gap above the fill."""
    for n in (16, 32, 64, 128):
        g = PlanarSilo(0.1, 0.4, 0.025, n, top_cell_ratio=3.0, fill_height=0.39)
        if g.graded:
            top_cell = 0.1 / n * g.effective_top_cell_ratio
            assert top_cell <= (0.4 - 0.39) / PlanarSilo.HEADSPACE_CELLS + 1e-12
    # 16 across: no room in a 10 mm headspace, the mesh stays uniform
    assert not PlanarSilo(0.1, 0.4, 0.025, 16, 3.0, None, 0.39).graded
    # 128 across: the full ratio fits
    assert PlanarSilo(0.1, 0.4, 0.025, 128, 3.0, None, 0.39).effective_top_cell_ratio == 3.0
