"""The mu(I) viscosity model in the real solver, on a prescribed shear field.

One frozen-flow step of siloFoam (U and p held, the mixture viscosity
evaluated) on the coarse planar mesh.  U = (g0 y, 0, 0) is uniform shear
(|gammaDot| = g0 exactly under Gauss-linear gradients); the granular
pressure is set to vary over 8.5 decades across the width, so that the
row of cells covers the pressure floor, the whole mu(I) curve and the cap.
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from foamsilo.case import create_case
from foamsilo.foam import read_internal_field, run_utility, write_internal_field

from .conftest import coarse_planar, frozen_flow_step

pytestmark = pytest.mark.openfoam

G0 = 10.0  # 1/s


def mu_i_nu(p, shear, d, rho, law, eta_max, p_min):
    """Reference implementation of Zhou et al. eq. 9 with the cap and floor."""
    pp = np.maximum(p, p_min)
    inertial = shear * d / np.sqrt(pp / rho)
    mu = np.vectorize(law.mu)(inertial)
    return np.minimum(mu * pp / shear, eta_max) / rho


@pytest.mark.parametrize("rheology", ["mu-i", "barker-gray"])
def test_solver_viscosity_is_capped_mu_i(tmp_path, openfoam, solver, rheology):
    """The plain law, and Barker & Gray's regularised one (its I1 and A from C++)."""
    scene = coarse_planar(**{"material.rheology": rheology})
    case = create_case(scene, tmp_path / "visc", openfoam).path
    frozen_flow_step(case, 1e-7)
    run_utility(openfoam, case, "postProcess", "-func", "writeCellCentres", "-time", "0")
    C = read_internal_field(case / "0" / "C")
    x, y = C[:, 0], C[:, 1]
    L, H = scene.silo.width, scene.silo.height

    U = np.zeros_like(C)
    U[:, 0] = G0 * y
    write_internal_field(case / "0" / "U", U)
    # grains everywhere, and p_rgh = p_target - rho g (hRef - y) so that the
    # solver's p = p_rgh + rho gh is p_target (its written p is used below)
    rho = scene.material.density
    shutil.copy(case / "0.orig" / "alpha.granular", case / "0")  # ASCII template
    write_internal_field(case / "0" / "alpha.granular", np.ones(len(C)))
    p_target = 10 ** (-1.5 + 8.5 * x / L)
    gh = scene.gravity * (scene.silo.fill_height - y)
    write_internal_field(case / "0" / "p_rgh", p_target - rho * gh)

    run_utility(openfoam, case, str(solver.executable), log_name="siloFoam")
    t = case / "1e-07"
    nu = read_internal_field(t / "nu1")
    p = read_internal_field(t / "p")
    assert np.allclose(read_internal_field(t / "U"), U)  # frozen
    assert np.allclose(p, p_target, rtol=1e-6, atol=1e-6)

    m = scene.material
    law = m.friction_law
    expected = mu_i_nu(p, G0, m.grain_diameter, m.density, law, scene.eta_max, scene.p_min)
    dx = scene.cell_size
    # away from the side walls (no-slip breaks the uniform shear there) and
    # the top and bottom boundaries
    inner = (x > dx) & (x < L - dx) & (y > dx) & (y < H - dx)
    assert inner.sum() > 500
    np.testing.assert_allclose(nu[inner], expected[inner], rtol=1e-6)

    eta = nu[inner] * m.density
    pp = p[inner]
    inertial = G0 * m.grain_diameter / np.sqrt(np.maximum(pp, scene.p_min) / m.density)
    # the test covers: the cap ...
    assert np.sum(np.isclose(eta, scene.eta_max, rtol=1e-9)) > 20
    # ... the pressure floor ...
    assert np.sum(pp < scene.p_min) > 20
    # ... and the rising part of mu(I) (I above I0/4, mu well above mu_s)
    mu_eff = eta * G0 / np.maximum(pp, scene.p_min)
    rising = inertial > 0.1
    assert rising.sum() > 20 and np.all(mu_eff[rising] > m.mu_s + 0.05)
    assert mu_eff.max() < m.mu_s + m.delta_mu
    # ... and, regularised, the low-I curve below I1, uncapped, where it is
    # more than 1% under the plain law
    if rheology == "barker-gray":
        below = (inertial < 0.5 * law.i1) & ~np.isclose(eta, scene.eta_max, rtol=1e-9)
        assert below.sum() > 20
        plain = np.vectorize(law.plain)(inertial[below])
        assert np.all(mu_eff[below] < 0.99 * plain)


@pytest.mark.parametrize(("edit", "words"), [({"alpha": 2.5}, "0 < alpha < 2"),
                                             ({"muInf": None}, "muInf")])  # fmt: skip
def test_regularised_law_coefficients_are_required_and_checked(tmp_path, openfoam, solver,
                                                               edit, words):  # fmt: skip
    """A hand-edited muIRegularisedCoeffs with alpha out of range, or no muInf, stops."""
    from foamsilo.errors import FoamError
    from foamsilo.foam import edit_dict

    scene = coarse_planar(**{"run.end_time": 0.01, "run.write_interval": 0.01,
                             "material.rheology": "barker-gray"})  # fmt: skip
    case = create_case(scene, tmp_path / "reg", openfoam).path
    with edit_dict(case / "constant" / "transportProperties") as tp:
        coeffs = tp["granular"]["muIRegularisedCoeffs"]
        for key, value in edit.items():
            if value is None:
                del coeffs[key]
            else:
                coeffs[key] = value
    with pytest.raises(FoamError) as err:
        run_utility(openfoam, case, str(solver.executable), log_name="siloFoam")
    assert words in err.value.output


def test_a_misspelt_pressure_name_is_a_fatal_error_not_the_cap(tmp_path, openfoam, solver):
    """muICoeffs.pName naming no field used to run the whole case at the cap, silently."""
    from foamsilo.foam import edit_dict

    scene = coarse_planar(**{"run.end_time": 0.01, "run.write_interval": 0.01})
    case = create_case(scene, tmp_path / "pname", openfoam).path
    with edit_dict(case / "constant" / "transportProperties") as tp:
        tp["granular"]["muICoeffs"]["pName"] = "pGranular"
    from foamsilo.errors import FoamError

    with pytest.raises(FoamError) as err:
        run_utility(openfoam, case, str(solver.executable), log_name="siloFoam")
    assert "pGranular" in err.value.output and "muICoeffs.pName" in err.value.output


COURANT = "courant"  # the cases that need numerics.face_smoothing = 'courant'


@pytest.mark.parametrize(("key", "value", "words", "smoothing"), [
    ("openBoundaryAcceleration", "faces", "must be face or cell, not faces", "step"),
    ("openBoundaryAcceleration", None, "openBoundaryAcceleration", "step"),
    ("stressPressureCoupling", "explicit", "must be implicit or lagged, not explicit", "step"),
    ("stressPressureCoupling", None, "stressPressureCoupling", "step"),
    ("stressPressureDivergence", 0, "stressPressureDivergence must be in (0, 1], not 0",
     "step"),
    ("stressPressureDivergence", None, "stressPressureDivergence", "step"),
    ("outerChangeLimit", 1.5, "outerChangeLimit must be 0 (never) or in (0, 1], not 1.5",
     "step"),
    ("outerChangeLimit", None, "outerChangeLimit", "step"),
    ("rhieChowScale", 2, "rhieChowScale must be in (0, 2), not 2", "step"),
    ("rhieChowScale", None, "rhieChowScale", "step"),
    ("viscosityInterpolation", "geometric", "must be harmonic or linear, not geometric",
     "step"),
    ("viscosityInterpolation", None, "viscosityInterpolation", "step"),
    ("startUpViscosityInterpolation", "geometric", "must be harmonic or linear, not geometric",
     "step"),
    ("startUpViscosityInterpolation", None, "startUpViscosityInterpolation", "step"),
    ("startUpEnd", -1, "startUpEnd must be >= 0, not -1", "step"),
    ("startUpEnd", None, "startUpEnd", "step"),
    ("faceSmoothing", "grid", "must be courant or step, not grid", "step"),
    ("faceSmoothing", None, "faceSmoothing", "step"),
    ("faceSmoothingMaxRatio", 0.5,
     "faceSmoothingMaxRatio >= 1, not 0.5, 0.005048187773 and 0.5", COURANT),
    ("faceSmoothingCourant", 0, "faceSmoothingCourant and faceSmoothingMaxStep must be > 0",
     COURANT),
    ("faceSmoothingMaxStep", None, "faceSmoothingMaxStep", COURANT),
])  # fmt: skip
def test_the_projection_switches_are_required_and_checked(tmp_path, openfoam, solver,
                                                         key, value, words, smoothing):  # fmt: skip
    """A hand-edited fvSolution with no or a wrong PIMPLE switch of the projection stops.

    The Courant smoothing's numbers are read only with faceSmoothing courant.
    """
    from foamsilo.errors import FoamError
    from foamsilo.foam import edit_dict

    scene = coarse_planar(**{"run.end_time": 0.01, "run.write_interval": 0.01,
                             "numerics.face_smoothing": f"'{smoothing}'"})  # fmt: skip
    case = create_case(scene, tmp_path / "switch", openfoam).path
    with edit_dict(case / "system" / "fvSolution") as fv:
        if value is None:
            del fv["PIMPLE"][key]
        else:
            fv["PIMPLE"][key] = value
    with pytest.raises(FoamError) as err:
        run_utility(openfoam, case, str(solver.executable), log_name="siloFoam")
    assert words in err.value.output


def test_the_implicit_coupling_needs_the_mu_i_law(tmp_path, openfoam, solver):
    """d tau/d p comes from the granular law: a Newtonian granular phase cannot give it."""
    from foamsilo.errors import FoamError
    from foamsilo.foam import edit_dict

    scene = coarse_planar(**{"run.end_time": 0.01, "run.write_interval": 0.01,
                             "numerics.stress_pressure_coupling": "'implicit'"})  # fmt: skip
    case = create_case(scene, tmp_path / "newtonian", openfoam).path
    with edit_dict(case / "constant" / "transportProperties") as tp:
        tp["granular"]["transportModel"] = "Newtonian"
        tp["granular"]["nu"] = 0.01
    with pytest.raises(FoamError) as err:
        run_utility(openfoam, case, str(solver.executable), log_name="siloFoam")
    assert "stressPressureCoupling implicit needs a mu(I) law" in err.value.output
