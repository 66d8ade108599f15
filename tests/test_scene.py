"""Scene model: presets, derived values, validation errors naming the field."""

from __future__ import annotations

import math

import pytest

from foamsilo.errors import SceneError
from foamsilo.scene import (
    apply_overrides,
    load_preset,
    load_scene_file,
    preset_data,
    preset_names,
    reference_markdown,
    scene_from_dict,
    to_toml,
)


def test_zhou_planar_preset_has_the_paper_values():
    s = load_preset("zhou-planar")
    L = s.silo.width
    assert s.silo.height == pytest.approx(4 * L)
    assert s.silo.fill_height == pytest.approx(3.9 * L)
    assert s.silo.orifice_width == pytest.approx(0.25 * L)
    assert s.material.grain_diameter == pytest.approx(L / 90)
    assert (s.material.mu_s, s.material.delta_mu, s.material.i0) == (0.4, 0.28, 0.4)
    # eta_max = 100 rho sqrt(g L^3)
    assert s.eta_max == pytest.approx(100 * 2500 * math.sqrt(9.81 * 0.1**3), rel=1e-12)
    assert s.eta_max == pytest.approx(24761.361, rel=1e-7)
    assert s.representation == "planar"
    # its 1% grid (issue 18): 26 cells across the orifice, graded away from it,
    # the edges refined; the paper used 64 across, uniform
    assert (s.mesh.cells_across, s.mesh.cells_across_orifice) == (104, None)
    assert s.mesh.graded and s.mesh.orifice_edge_refinement == 2
    assert s.time_scale == pytest.approx(math.sqrt(0.1 / 9.81))


def test_overrides_are_typed_toml_literals():
    s = load_preset(
        "zhou-planar", ["mesh.cells_across=16", "run.end_time=0.25", "mesh.representation=planar"]
    )
    assert s.mesh.cells_across == 16 and isinstance(s.mesh.cells_across, int)
    assert s.run.end_time == 0.25
    assert s.cell_size == pytest.approx(0.1 / 16)


def test_the_resolution_can_be_given_across_the_orifice():
    from foamsilo.mesh import profile_layout

    # the lab silo, L/D = 6: 12 cells across D are the 72 across L
    s = load_preset("zhou-cyl-bottom", ["mesh.cells_across_orifice=12"])
    assert s.mesh.cells_across is None  # the preset's cells_across made way
    assert s.cells_across == 72 and s.cell_size == pytest.approx(0.01 / 12)
    same = load_preset("zhou-cyl-bottom", ["mesh.cells_across=72"])
    assert profile_layout(s) == profile_layout(same)
    # and back: setting cells_across removes cells_across_orifice
    back = load_preset("zhou-cyl-bottom", ["mesh.cells_across_orifice=12", "mesh.cells_across=36"])
    assert back.cells_across == 36 and back.mesh.cells_across_orifice is None
    with pytest.raises(SceneError, match=r"mesh\.cells_across.*exactly one"):
        load_preset("zhou-cyl-bottom", ["mesh.cells_across="])


def test_pressure_floor_default_and_explicit():
    s = load_preset("zhou-planar")
    assert s.p_min == pytest.approx(1e-4 * 2500 * 9.81 * 0.1)
    s2 = load_preset("zhou-planar", ["material.pressure_floor=0.5"])
    assert s2.p_min == 0.5


@pytest.mark.parametrize(
    ("override", "field", "allowed"),
    [
        ("silo.orifice_width=0.1", "silo.orifice_width", "< silo.width"),
        ("silo.orifice_width=0.2", "silo.orifice_width", "< silo.width"),
        ("silo.fill_height=0.41", "silo.fill_height", "<= silo.height"),
        ("silo.width=-0.1", "silo.width", "> 0"),
        ("silo.height=0", "silo.height", "> 0"),
        ("material.grain_diameter=-1e-3", "material.grain_diameter", "> 0"),
        ("material.density=0", "material.density", "> 0"),
        ("material.mu_s=-0.1", "material.mu_s", ">= 0"),
        ("mesh.cells_across=0", "mesh.cells_across", ">= 4"),
        ("mesh.cells_across=6", "mesh.cells_across", "at least 2 cells across the orifice"),
        ("mesh.cells_across=16.5", "mesh.cells_across", "integer"),
        ("run.end_time=-1", "run.end_time", "> 0"),
        ("silo.colour=1", "silo.colour", "allowed keys in silo"),
        ("flavour=1", "flavour", "allowed keys"),
        ("mesh.representation=axisymmetric", "mesh.representation", "allowed"),
        ("silo.shape=hexagonal", "silo.shape", "'rectangular'"),
        ("material.mu_s='a lot'", "material.mu_s", "a number"),
        ("material.grain_diameter=0.03", "material.grain_diameter", "< silo.orifice_width"),
        ("numerics.rhie_chow_scale=2", "numerics.rhie_chow_scale", "< 2"),
        ("numerics.rhie_chow_scale=0", "numerics.rhie_chow_scale", "> 0"),
        ("numerics.stress_pressure_divergence=1.5", "numerics.stress_pressure_divergence", "<= 1"),
        ("numerics.face_smoothing=grid", "numerics.face_smoothing", "'courant'"),
        ("numerics.face_smoothing_courant=0", "numerics.face_smoothing_courant", "> 0"),
        ("numerics.face_smoothing_max_ratio=0.5", "numerics.face_smoothing_max_ratio", ">= 1"),
        (
            "numerics.viscosity_interpolation=geometric",
            "numerics.viscosity_interpolation",
            "'harmonic'",
        ),
        ("numerics.outer_growth_limit=0.5", "numerics.outer_growth_limit", "> 1"),
        # the planar silo's stress is lagged: no share to halve
        ("numerics.outer_growth_limit=2", "numerics.outer_growth_limit", "'implicit'"),
        ("numerics.outer_change_limit=1.5", "numerics.outer_change_limit", "<= 1"),
        ("numerics.outer_change_limit=0.05", "numerics.outer_change_limit", "'implicit'"),
    ],
)
def test_bad_values_name_the_field_and_the_allowed_range(override, field, allowed):
    with pytest.raises(SceneError) as exc:
        load_preset("zhou-planar", [override])
    assert exc.value.field == field
    assert allowed in str(exc.value)
    assert str(exc.value).startswith(field)


def test_missing_key_is_named():
    data = preset_data("zhou-planar")
    del data["silo"]["orifice_width"]
    with pytest.raises(SceneError) as exc:
        scene_from_dict(data)
    assert exc.value.field == "silo.orifice_width"
    assert "missing" in str(exc.value)


def test_exactly_one_viscosity_cap():
    # an override of one form replaces the preset's other form ...
    data = apply_overrides(preset_data("zhou-planar"), ["material.viscosity_cap=1000"])
    assert "viscosity_cap_scaled" not in data["material"]
    assert scene_from_dict(data).eta_max == 1000
    # ... a file that gives both is refused
    data["material"]["viscosity_cap_scaled"] = 100.0
    with pytest.raises(SceneError, match="exactly one"):
        scene_from_dict(data)


def test_scene_file_roundtrip(tmp_path):
    s = load_preset("zhou-planar")
    p = tmp_path / "s.toml"
    p.write_text(to_toml(s.to_dict()))
    assert load_scene_file(p) == s


def test_unknown_preset_lists_the_allowed_ones():
    with pytest.raises(SceneError) as exc:
        load_preset("no-such-silo")
    assert "zhou-planar" in str(exc.value)


def test_reference_covers_every_field():
    md = reference_markdown()
    for key in (
        "orifice_width",
        "fill_height",
        "viscosity_cap_scaled",
        "cells_across",
        "max_granular_courant",
        "pressure_floor",
    ):
        assert f"`{key}`" in md
    assert "zhou-planar" in preset_names()


def test_committed_scene_reference_is_current():
    from pathlib import Path

    doc = Path(__file__).resolve().parent.parent / "docs" / "scene-reference.md"
    assert doc.read_text().strip() == reference_markdown().strip(), (
        "docs/scene-reference.md is stale: foamsilo scene-reference > docs/scene-reference.md"
    )


# ---------------------------------------------------------------- gas coupling

GAS = ["silo.thickness=0.025", "material.wall_friction=0.1", 'gas.mode="injection"',
       "gas.q_air_scaled=0.5", "gas.permeability_scaled=1", "gas.inertial=false"]  # fmt: skip


def test_gas_scene_derived_values():
    s = load_preset("zhou-planar", GAS)
    assert s.gas_coupled and s.wall_friction
    g, L = 9.81, 0.1
    assert s.q_air_per_depth == pytest.approx(0.5 * math.sqrt(g * L**3))
    assert s.q_air == pytest.approx(s.q_air_per_depth * 0.025)
    # zeta = kappa rho sqrt(g/L)/eta_f = 1
    assert s.permeability * 2500 * math.sqrt(g / L) / 1.8e-5 == pytest.approx(1.0)
    assert s.inertial_permeability is None
    ergun = load_preset("zhou-planar", ['gas.mode="closed-top"'])
    phi, d = 0.6, 0.1 / 90
    assert ergun.permeability == pytest.approx((1 - phi) ** 3 * d**2 / (150 * phi**2))
    assert ergun.inertial_permeability == pytest.approx((1 - phi) ** 3 * d**2 / (1.75 * phi))
    assert ergun.q_air == 0.0 and ergun.gas_coupled


def test_air_flow_units():
    base = ["silo.thickness=0.025", 'gas.mode="injection"']
    lpm = load_preset("zhou-planar", base + ["gas.q_air_lpm=12"])
    si = load_preset("zhou-planar", base + ["gas.q_air=2e-4"])
    assert lpm.q_air == pytest.approx(si.q_air) == pytest.approx(2e-4)
    assert lpm.q_air_per_depth == pytest.approx(2e-4 / 0.025)


@pytest.mark.parametrize(
    ("overrides", "field", "text"),
    [
        (['gas.mode="injection"'], "gas.q_air", "exactly one"),
        (['gas.mode="injection"', "gas.q_air=1e-3", "gas.q_air_lpm=5"], "gas.q_air", "exactly one"),
        (['gas.mode="injection"', "gas.q_air=1e-3"], "silo.thickness", "thickness"),
        (["gas.q_air=1e-3"], "gas.q_air", "only for gas.mode = 'injection'"),
        (['gas.mode="closed-top"', "gas.q_air_lpm=3"], "gas.q_air_lpm", "injection"),
        (["material.wall_friction=0.1"], "material.wall_friction", "silo.thickness"),
        (['gas.mode="sideways"'], "gas.mode", "'open-top', 'closed-top', 'injection'"),
        (["gas.permeability=1e-10", "gas.permeability_scaled=1"], "gas.permeability", "not both"),
        (["gas.packing_fraction=1.2"], "gas.packing_fraction", "< 1"),
        (["gas.inertial=1"], "gas.inertial", "true, false"),
        (['gas.mode="closed-top"', "gas.taps=[0.1, 0.5]"], "gas.taps[1]", "< silo.height (0.4 m)"),
        (['gas.mode="closed-top"', "gas.taps=[-0.1]"], "gas.taps[0]", "a number > 0 m"),
        (['gas.mode="closed-top"', "gas.taps=0.1"], "gas.taps", "a list of numbers"),
        (["gas.taps=[0.1]"], "gas.taps", "open-top silo has no pore pressure"),
    ],
)
def test_gas_errors_name_the_field(overrides, field, text):
    with pytest.raises(SceneError) as exc:
        load_preset("zhou-planar", overrides)
    assert exc.value.field == field
    assert text in str(exc.value)


def test_empty_override_unsets_a_key():
    s = load_preset("zhou-planar-gas", ['gas.mode="open-top"', "gas.q_air_scaled="])
    assert not s.gas_coupled and s.gas.q_air_scaled is None
    with pytest.raises(SceneError):  # without unsetting, the preset's flow is refused
        load_preset("zhou-planar-gas", ['gas.mode="open-top"'])


def test_zhou_planar_gas_preset():
    s = load_preset("zhou-planar-gas")
    L = s.silo.width
    assert s.silo.thickness == pytest.approx(0.25 * L)
    assert s.material.wall_friction == 0.1
    assert s.gas.permeability_scaled == 1.0 and not s.gas.inertial
    assert s.gas.permeability_ratio == 100
    assert s.q_air_per_depth / math.sqrt(9.81 * L**3) == pytest.approx(0.5)


def test_pressure_taps_reach_the_probes_and_roundtrip(tmp_path):
    from foamsilo.case import template_context

    s = load_preset("zhou-planar", ['gas.mode="closed-top"', "gas.taps=[0.1, 0.2]"])
    assert s.gas.taps == (0.1, 0.2)
    probes = template_context(s)["axis_probes"]
    assert {0.1, 0.2} <= set(probes) and probes == sorted(probes)
    path = tmp_path / "s.toml"
    path.write_text(to_toml(s.to_dict()))
    assert load_scene_file(path).gas.taps == (0.1, 0.2)


def test_user_guide_example_scene_is_valid(tmp_path):
    import re
    from pathlib import Path

    guide = (Path(__file__).resolve().parent.parent / "docs" / "index.md").read_text()
    toml = re.search(r"```toml\n(.*?)```", guide, re.S).group(1)
    (tmp_path / "s.toml").write_text(toml)
    s = load_scene_file(tmp_path / "s.toml")
    assert s.representation == "axisymmetric"  # auto: a centred cylinder needs no 3D mesh
    assert s.gas.taps == (0.05, 0.1, 0.2)


def test_the_stress_coupling_follows_the_column():
    """Implicit where a column's wall stress carries the pressure (docs/solver.md, "Tall columns")."""
    from foamsilo.scene import load_preset

    coupling = {n: load_preset(n).stress_pressure_coupling for n in (
        "zhou-planar", "zhou-cyl-bottom", "zhou-rect-bottom", "zhou-planar-gas",
        "zhou-cyl-lateral", "zhou-cyl-lateral-rect", "venier-test2")}  # fmt: skip
    assert coupling == {
        "zhou-planar": "lagged",  # 3.9 widths
        "zhou-cyl-bottom": "implicit",  # axisymmetric
        "zhou-rect-bottom": "implicit",  # quasi-2D wall friction
        "zhou-planar-gas": "implicit",  # wall friction, gas-coupled
        "zhou-cyl-lateral": "implicit",  # 3D, 12.5 diameters
        "zhou-cyl-lateral-rect": "implicit",  # 3D, 8.3 diameters
        "venier-test2": "lagged",  # 3D, 1.5 diameters
    }
    tall = load_preset("zhou-planar", ["silo.height=2.0", "silo.fill_height=1.95"])
    assert tall.stress_pressure_coupling == "implicit"
    # the boundary: 10 widths planar, 5 diameters in a cylinder (A/P = L/2, D/4)
    planar = load_preset("zhou-planar", ["silo.height=1.2", "silo.fill_height=0.99"])
    assert planar.stress_pressure_coupling == "lagged"
    for fill, expected in ((20.9, "lagged"), (21.1, "implicit")):  # D = 4.2 m
        column = load_preset("venier-test2", ["silo.height=22", f"silo.fill_height={fill}"])
        assert column.stress_pressure_coupling == expected
    forced = load_preset("zhou-cyl-lateral", ["numerics.stress_pressure_coupling='lagged'"])
    assert forced.stress_pressure_coupling == "lagged"


def test_a_feeder_solves_its_pressure_tighter():
    """1e-10 with a feeder, 1e-7 for a free discharge, a user's value kept."""
    assert load_preset("venier-test2").p_tolerance == 1e-10
    assert load_preset("zhou-cyl-bottom").p_tolerance == 1e-7
    assert load_preset("venier-test2", ["numerics.p_tolerance=1e-8"]).p_tolerance == 1e-8
