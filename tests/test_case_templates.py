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
    assert not any("p_f" in f or "pf" in f.split("/")[-1] for f in files)
    assert "Darcy" not in (case / "constant/transportProperties").read_text()
