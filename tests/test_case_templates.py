"""Template rendering (no OpenFOAM needed) and atomic case writing."""

from __future__ import annotations

import re

import pytest

from foamsilo.case import render_templates, template_list
from foamsilo.scene import load_preset


def _entry(text: str, key: str) -> str:
    m = re.search(r"^\s*" + re.escape(key) + r"\s+([^;]+);", text, re.M)
    assert m, f"{key} not found"
    return m.group(1).strip()


def _balanced(text: str) -> bool:
    body = re.sub(r"//.*", "", text)
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    return body.count("{") == body.count("}") and body.count("(") == body.count(")")


@pytest.fixture
def rendered(tmp_path):
    scene = load_preset("zhou-planar", ["mesh.cells_across=32"])
    files = render_templates(scene, tmp_path)
    return scene, tmp_path, files


def test_every_file_renders_and_is_balanced(rendered):
    scene, case, files = rendered
    assert files == template_list(scene)
    for f in files:
        text = (case / f).read_text()
        assert "FoamFile" in text and _balanced(text), f


def test_mu_i_coefficients_reach_the_solver_dictionary(rendered):
    scene, case, _ = rendered
    tp = (case / "constant/transportProperties").read_text()
    granular = tp[tp.index("granular") : tp.index("air\n")]
    assert _entry(granular, "transportModel") == "muI"
    assert float(_entry(granular, "rho")) == 2500
    assert float(_entry(granular, "mus")) == 0.4
    assert float(_entry(granular, "deltaMu")) == 0.28
    assert float(_entry(granular, "I0")) == 0.4
    assert float(_entry(granular, "d")) == pytest.approx(0.1 / 90, rel=1e-9)
    assert float(_entry(granular, "etaMax")) == pytest.approx(scene.eta_max, rel=1e-9)
    assert float(_entry(granular, "pMin")) == pytest.approx(scene.p_min, rel=1e-9)
    assert float(_entry(tp, "sigma")) == 0


def test_boundary_conditions_of_the_planar_silo(rendered):
    _, case, _ = rendered
    p = (case / "0/p_rgh").read_text()
    # zero granular pressure at the orifice (Zhou III.B) and at the open top
    assert re.search(r"orifice\s*\{\s*type\s+prghPressure;\s*p\s+uniform 0;", p)
    assert re.search(r"atmosphere\s*\{\s*type\s+prghTotalPressure;", p)
    u = (case / "0/U").read_text()
    assert re.search(r"walls\s*\{\s*type\s+noSlip;", u)
    for f in ("0/U", "0/p_rgh", "0/alpha.granular"):
        assert re.search(r"frontAndBack\s*\{\s*type\s+empty;", (case / f).read_text()), f


def test_control_and_gravity(rendered):
    scene, case, _ = rendered
    cd = (case / "system/controlDict").read_text()
    assert _entry(cd, "application") == "siloFoam"
    assert float(_entry(cd, "endTime")) == scene.run.end_time
    assert float(_entry(cd, "maxCo")) == scene.run.max_courant
    assert "orificeFlow" in cd and "alphaPhi0.granular" in cd
    g = (case / "constant/g").read_text()
    assert "(0 -9.81 0)" in g
    assert float(_entry((case / "constant/hRef").read_text(), "value")) == scene.silo.fill_height
    fs = (case / "system/fvSolution").read_text()
    assert _entry(fs, "momentumPredictor") == "yes"


def test_parallel_dictionary_only_when_needed(tmp_path):
    serial = load_preset("zhou-planar")
    assert "system/decomposeParDict" not in template_list(serial)
    par = load_preset("zhou-planar", ["run.n_procs=2"])
    files = render_templates(par, tmp_path)
    assert "system/decomposeParDict" in files
    assert _entry((tmp_path / "system/decomposeParDict").read_text(), "numberOfSubdomains") == "2"


def test_no_pore_pressure_machinery_in_a_dry_silo(rendered):
    _, case, files = rendered
    assert not any(f.split("/")[-1] in ("pf", "porePressureProperties", "topoSetDict",
                                        "wallFrictionProperties") for f in files)  # fmt: skip
    cd = (case / "system/controlDict").read_text()
    assert "pf" not in re.findall(r"fields\s*\(([^)]*)\)", cd)[0]
    assert "porePressureAxis" not in cd
    assert '"pf.*"' not in (case / "system/fvSolution").read_text()


def test_gas_scene_gets_the_pore_pressure_files(tmp_path):
    scene = load_preset("zhou-planar-gas", ["mesh.cells_across=32"])
    files = render_templates(scene, tmp_path)
    for f in ("0/pf", "constant/porePressureProperties", "system/topoSetDict",
              "constant/wallFrictionProperties"):  # fmt: skip
        assert f in files, f
    pp = (tmp_path / "constant/porePressureProperties").read_text()
    assert float(_entry(pp, "permeability")) == pytest.approx(scene.permeability, rel=1e-9)
    assert "inertialPermeability" not in pp  # Darcy
    # the planar mesh is one cell thick: the flow per depth times the cell size
    inj = float(_entry(pp, "injectionFlux"))
    assert inj == pytest.approx(scene.q_air_per_depth * scene.cell_size, rel=1e-9)
    pf = (tmp_path / "0/pf").read_text()
    assert re.search(r"orifice\s*\{\s*type\s+fixedValue;\s*value\s+uniform 0;", pf)
    assert re.search(r"atmosphere\s*\{\s*type\s+fixedGradient;", pf)
    cd = (tmp_path / "system/controlDict").read_text()
    assert "porePressureAxis" in cd and "orificeZoneGradient" in cd
    wf = (tmp_path / "constant/wallFrictionProperties").read_text()
    assert float(_entry(wf, "frictionCoefficient")) == 0.1
    assert float(_entry(wf, "thickness")) == pytest.approx(0.025)


def test_forchheimer_entries_when_inertial(tmp_path):
    scene = load_preset("zhou-planar-gas", ["gas.inertial=true"])
    render_templates(scene, tmp_path)
    pp = (tmp_path / "constant/porePressureProperties").read_text()
    assert float(_entry(pp, "inertialPermeability")) == pytest.approx(
        scene.inertial_permeability, rel=1e-9
    )


def test_the_face_viscosity_reaches_the_solver(tmp_path):
    """numerics.viscosity_interpolation becomes the PIMPLE key siloFoam requires."""
    from foamsilo.foam.dictionary import read_dict

    for mean in ("linear", "harmonic"):
        scene = load_preset("zhou-cyl-bottom", [f"numerics.viscosity_interpolation={mean}"])
        render_templates(scene, tmp_path / mean)
        pimple = read_dict(tmp_path / mean / "system/fvSolution")["PIMPLE"]
        assert pimple["viscosityInterpolation"] == mean


def test_the_start_up_face_viscosity_reaches_the_solver_with_the_start_ups_end(tmp_path):
    """numerics.start_up_viscosity_interpolation and the start-up's end, one discharge time.

    By default harmonic in an axisymmetric scene, linear in planar and 3D
    ones; a value given is taken in any.
    """
    from foamsilo.case.templates import START_UP
    from foamsilo.foam.dictionary import read_dict
    from foamsilo.post.steady import START

    # the start-up the solver's switch ends is the one the steady window skips
    assert START_UP == START
    cases = [
        ("hopper-conical", [], "harmonic"),
        ("zhou-planar", [], "linear"),
        ("zhou-cyl-lateral-rect", [], "linear"),
        ("hopper-conical", ["numerics.start_up_viscosity_interpolation=linear"], "linear"),
        ("zhou-cyl-lateral-rect", ["numerics.start_up_viscosity_interpolation=harmonic"],
         "harmonic"),
    ]  # fmt: skip
    for k, (preset, overrides, mean) in enumerate(cases):
        scene = load_preset(preset, overrides)
        render_templates(scene, tmp_path / str(k))
        pimple = read_dict(tmp_path / str(k) / "system/fvSolution")["PIMPLE"]
        assert pimple["startUpViscosityInterpolation"] == mean, (preset, overrides)
        assert pimple["viscosityInterpolation"] == "linear"
    # sqrt(D/g), the hopper's outlet D = 30 mm
    hopper = read_dict(tmp_path / "0" / "system/fvSolution")["PIMPLE"]
    assert float(hopper["startUpEnd"]) == pytest.approx((0.03 / 9.81) ** 0.5, rel=1e-9)


def test_the_outer_growth_and_change_limits_follow_the_coupling(tmp_path):
    """By default a step is taken again at half the share only where there is one.

    With the implicit stress-pressure coupling (the wedges, wall friction, tall
    columns) siloFoam gets ``outerGrowthLimit`` 2 and ``outerChangeLimit``
    0.05; with the lagged one (the planar silo) 0 and 0, never; a scene's own
    values (the lab silo's preset sets both to 0) are written as given.
    """
    from foamsilo.foam.dictionary import read_dict

    cases = [
        ("venier-test1", [], 2.0, 0.05),
        ("zhou-rect-bottom", [], 2.0, 0.05),
        ("zhou-planar", [], 0.0, 0.0),
        ("zhou-planar", ["numerics.stress_pressure_coupling=implicit"], 2.0, 0.05),
        ("zhou-cyl-bottom", [], 0.0, 0.0),
        ("venier-test1", ["numerics.outer_growth_limit=0"], 0.0, 0.05),
        ("venier-test1", ["numerics.outer_growth_limit=5"], 5.0, 0.05),
        ("venier-test1", ["numerics.outer_change_limit=0"], 2.0, 0.0),
        ("venier-test1", ["numerics.outer_change_limit=0.2"], 2.0, 0.2),
    ]
    for k, (preset, sets, growth, change) in enumerate(cases):
        render_templates(load_preset(preset, sets), tmp_path / str(k))
        pimple = read_dict(tmp_path / str(k) / "system/fvSolution")["PIMPLE"]
        assert float(pimple["outerGrowthLimit"]) == growth, (preset, sets)
        assert float(pimple["outerChangeLimit"]) == change, (preset, sets)
