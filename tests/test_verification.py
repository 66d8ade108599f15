"""Code verification of siloFoam through the real solver: exact steady layers.

A layer on an inclined plane, periodic along the slope, runs from rest to
its steady state (``foamsilo bench verification --quick``: 10 cells across
the layer) and is set against the exact profile:

* the mu(I) (Bagnold) layer: issue 18 asks for the surface velocity within
  2% on a coarse grid (measured -1.5% at 10 cells);
* the Newtonian film at the viscosity cap: a second-order scheme on a
  parabola is within 2% at 10 cells (measured +1.0%, the no-slip wall and
  the free surface each half a cell from the nearest centre);
* the same layer with Barker & Gray's regularised law, on a slope below
  the law's well-posed range (its low-I curve), at 40 cells;
* Hagen-Poiseuille flow on the axisymmetric wedge at the cap: the hoop
  terms of the stress divergence, the peak on the axis within 2% at 10
  cells across the radius (measured -0.3%).
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest

from foamsilo.analytic.exact import bagnold_velocity, newtonian_film_velocity
from foamsilo.case.channel import Channel
from foamsilo.cli import main
from foamsilo.errors import FoamsiloError, SceneError


@pytest.fixture(scope="module")
def verification(tmp_path_factory, solver):
    root = tmp_path_factory.mktemp("verify")
    buf = io.StringIO()
    args = ["bench", "verification", "--quick", "-o", str(root / "out"),
            "--work-dir", str(root / "work"), "--json"]  # fmt: skip
    with contextlib.redirect_stdout(buf):
        code = main(args)
    return code, json.loads(buf.getvalue()), root


@pytest.mark.openfoam
def test_bagnold_surface_velocity_within_two_percent(verification):
    code, res, _ = verification
    assert code == 0, [c for c in res["checks"] if not c["passed"]]
    row = res["bagnold"]["rows"][0]
    assert row["cells"] == 10
    assert abs(row["peak_error"]) < 0.02
    # the whole profile, not only its top: within 3% of u_s everywhere
    assert row["max_error"] < 0.03
    # the run ended steady, so the error is the grid's
    assert row["unsteadiness"] < 1e-3


@pytest.mark.openfoam
def test_regularised_law_below_its_well_posed_range(verification):
    """Barker & Gray's low-I curve in the solver: tan(theta) = 0.41 < mu(I1)."""
    from foamsilo.analytic.rheology import FrictionLaw

    _, res, _ = verification
    row = res["bagnold-regularised"]["rows"][0]
    assert row["cells"] == 40
    assert abs(row["peak_error"]) < 0.02
    assert row["unsteadiness"] < 1e-3
    # the plain law's layer would be 18% slower: the run is on the other curve
    plain = FrictionLaw(0.4, 0.28, 0.4).inertial_number(0.41)
    reg = FrictionLaw(0.4, 0.28, 0.4, alpha=1.9).inertial_number(0.41)
    assert row["peak_velocity"] / row["peak_velocity_exact"] > 1 - (1 - plain / reg) / 3


@pytest.mark.openfoam
@pytest.mark.parametrize("name", ["film", "pipe"])
def test_newtonian_flows_at_the_cap(verification, name):
    # film: the depth-averaged velocity is 2/3 of u_s; pipe: the mean is half
    # the axis velocity (the flow rate), where a wrong hoop term or wedge
    # volume shows far above the grid's second-order error
    _, res, _ = verification
    row = res[name]["rows"][0]
    assert row["cells"] == 10
    assert abs(row["peak_error"]) < 0.02
    assert abs(row["mean_error"]) < 0.01
    assert row["unsteadiness"] < 1e-3


@pytest.mark.openfoam
def test_report_written(verification):
    _, _, root = verification
    md = (root / "out" / "verification-quick.md").read_text()
    assert "| 10 |" in md and "pass" in md and "FAIL" not in md
    assert (root / "out" / "verification-quick.png").stat().st_size > 0


def test_exact_profiles():
    theta, h, d, g = math.atan(0.54), 0.02, 1e-3, 9.81
    z = np.linspace(0, h, 2001)
    u = bagnold_velocity(z, h, theta, 0.4, 0.28, 0.4, d, g)
    # I = I0 (tan - mu_s) / (mu_s + dmu - tan) = 0.4; du/dz = I sqrt(g cos (h - z)) / d
    dudz = np.gradient(u, z)
    expected = 0.4 * np.sqrt(g * math.cos(theta) * (h - z)) / d
    inner = slice(5, 1800)  # clear of the surface, where d2u/dz2 is singular
    assert np.allclose(dudz[inner], expected[inner], rtol=1e-4)
    # the depth-averaged velocity is 3/5 of the surface velocity
    assert np.trapezoid(u, z) / h == pytest.approx(0.6 * u[-1], rel=1e-6)
    nu = 5.6e-3
    f = newtonian_film_velocity(z, h, math.atan(0.3), nu, g)
    assert f[-1] == pytest.approx(g * math.sin(math.atan(0.3)) * h**2 / (2 * nu))
    assert np.trapezoid(f, z) / h == pytest.approx(2 / 3 * f[-1], rel=1e-6)


def test_channel_refuses_bad_values():
    with pytest.raises(SceneError, match="channel.cells"):
        Channel(tan_theta=0.5, depth=0.02, cells=1, air_depth=0.01, length=0.05)
    with pytest.raises(SceneError, match="channel.depth"):
        Channel(tan_theta=0.5, depth=-1.0, cells=10, air_depth=0.01, length=0.05)
    c = Channel(tan_theta=0.54, depth=0.02, cells=10, air_depth=0.0101, length=0.05)
    # the surface on a row boundary, the air rounded to whole rows
    assert c.rows == 15 and c.height == pytest.approx(0.03)


def test_film_above_the_yield_slope_is_refused():
    from foamsilo.studies.verify import channel_for, channel_scene, entries, exact_velocity

    entry = dict(entries()["film"], tan_theta=0.45)
    channel = channel_for(entry, 10)
    with pytest.raises(FoamsiloError, match="below mu_s"):
        exact_velocity("film", channel_scene(entry, channel), channel, np.array([0.01]))


def test_the_peak_is_judged_on_check_cells():
    """The regularised layer's check is at 40 cells in the full run too, not the coarsest."""
    from dataclasses import replace

    from foamsilo.studies.verify import ChannelResult, check_row, entries

    base = ChannelResult(cells=10, time=45.0, y=[], u=[], u_exact=[], peak_velocity=1.0,
                         peak_velocity_exact=1.0, peak_error=0.0, mean_error=0.0,
                         l2_error=0.0, max_error=0.0, unsteadiness=0.0, alpha_min=0.0,
                         alpha_max=1.0, steps=None, cpu_s=None)  # fmt: skip
    table = entries()
    rows = [replace(base, cells=n) for n in table["bagnold-regularised"]["cells"]]
    assert check_row("bagnold-regularised", table["bagnold-regularised"], rows).cells == 40
    assert check_row("bagnold", table["bagnold"], rows).cells == 10
    with pytest.raises(FoamsiloError, match="check_cells = 40: not among"):
        check_row("bagnold-regularised", table["bagnold-regularised"], rows[:2])


def test_a_lever_reaches_every_case_and_its_own_report():
    """`bench verification --set`: the override on top of the entry's own, a report of its own."""
    from foamsilo.studies.verify import channel_for, channel_scene, entries, report_stem

    entry = entries()["bagnold"]
    channel = channel_for(entry, 10)
    lever = ["numerics.viscosity_interpolation=harmonic", "numerics.p_tolerance=1e-9"]
    scene = channel_scene(entry, channel, lever)
    assert scene.numerics.viscosity_interpolation == "harmonic"
    assert scene.numerics.p_tolerance == 1e-9  # after the entry's own 1e-10
    assert channel_scene(entry, channel).numerics.viscosity_interpolation == "linear"
    # the checked-in report stays the defaults'
    assert report_stem(False, []) == "verification"
    assert report_stem(True, lever) == "verification-quick-set"
