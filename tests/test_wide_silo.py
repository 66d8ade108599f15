"""A real run of a wide planar silo: its steady discharge gets a Q.

The silo is 10 orifice widths wide (L = 5, D = 0.5, g = 1, d = 1/30, rho = 1),
60 cells across L (6 across the orifice), run for 3 s = 4.2 sqrt(D/g) =
1.3 sqrt(L/g). The rate settles within ~2 sqrt(D/g) of the opening; a steady
window judged on the silo width's time scale (it must outlast sqrt(L/g) =
2.2 s) would refuse it, the orifice's scale (2 sqrt(D/g) = 1.4 s) accepts it.

Band for the rate: the 2D Beverloo law with the continuum constant of
Zhou et al. 2019, Q = 1.28 rho sqrt(g) D^(3/2). With 6 cells across the
orifice the coarse-grid error is of order 10% (the planar test at 4 cells
across measures -7%; Zhou's own code is 9% low at 8 across), so the test
accepts 15%. Measured here: -5.2%.
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import pytest

from foamsilo.cli import main

pytestmark = pytest.mark.openfoam

SCENE = """
name = "wide-planar"
description = "wide planar silo, g = 1: L = 5, D = 0.5, d = 1/30"
gravity = 1.0

[silo]
shape = "rectangular"
width = 5.0
height = 10.0
fill_height = 9.0
orifice_width = 0.5
orifice_position = "bottom"

[material]
grain_diameter = 0.03333333333333333
density = 1.0
mu_s = 0.4
delta_mu = 0.28
i0 = 0.4
viscosity_cap_scaled = 100.0

[air]
density = 1e-3
viscosity = 1e-5

[mesh]
cells_across = 60
representation = "planar"

[run]
end_time = 3.0
write_interval = 1.5
"""

L, D, G = 5.0, 0.5, 1.0


@pytest.fixture(scope="module")
def wide_run(tmp_path_factory, solver):
    root = tmp_path_factory.mktemp("wide")
    scene = root / "wide.toml"
    scene.write_text(SCENE)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["run", str(scene), "-o", str(root / "case"), "--quiet", "--json"])
    assert code == 0, buf.getvalue()
    return json.loads(buf.getvalue())


def test_wide_silo_gets_a_steady_rate(wide_run):
    s = wide_run
    assert s["ok"] and s["steady"], s["steady_reason"]
    t0, t1 = s["steady_window_s"]
    # the case is the one the test is about: the window is shorter than the
    # silo's time scale, yet at least two of the orifice's
    assert 2 * math.sqrt(D / G) <= t1 - t0 < math.sqrt(L / G)


def test_wide_silo_rate_follows_beverloo(wide_run):
    s = wide_run
    beverloo = 1.28 * math.sqrt(G) * D**1.5
    assert s["Q"] == pytest.approx(beverloo, rel=0.15)
    assert s["beverloo_2d"]["rel_diff"] == pytest.approx(s["Q"] / beverloo - 1, abs=1e-9)


def test_wide_silo_rate_has_an_error(wide_run):
    s = wide_run
    # batch means over 10 batches of the window: a finite, small standard
    # error (the fluctuation of the rate is ~0.2% here)
    assert 0 < s["Q_time_error"] < 0.01 * s["Q"]
    assert s["Q_time_error_batch_span"] == pytest.approx(
        (s["steady_window_s"][1] - s["steady_window_s"][0]) / 10 / math.sqrt(D / G)
    )
