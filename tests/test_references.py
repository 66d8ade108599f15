"""The rates a scene is compared with (`foamsilo compare`, the report, the plots).

A law applies only to the geometry it was derived for: the 2D Beverloo law to
a planar silo's centred bottom orifice, Zhou et al.'s eq. 1 to a cylinder's;
a lateral orifice gets none, a feeder its own rate.
"""

from __future__ import annotations

import pytest

from foamsilo.compare import open_top_law, references
from foamsilo.errors import FoamsiloError
from foamsilo.scene import load_preset


def test_the_planar_bottom_orifice_has_beverloo_and_zhou():
    keys = [r.key for r in references(load_preset("zhou-planar"))]
    assert keys == ["zhou-planar", "beverloo-2d"]


def test_a_planar_lateral_orifice_has_no_law():
    scene = load_preset("zhou-rect-lateral")
    assert references(scene) == []
    with pytest.raises(FoamsiloError, match="lateral orifice"):
        open_top_law(scene)


def test_the_cylinder_and_the_feeder():
    assert [r.key for r in references(load_preset("zhou-cyl-bottom"))] == ["zhou-eq1"]
    (feeder,) = references(load_preset("venier-test2"))
    assert feeder.key == "feeder"
    # 8.35 m^3/h of the bulk at 2300 kg/m^3
    assert feeder.q == pytest.approx(2300 * 8.35 / 3600, rel=1e-3)
