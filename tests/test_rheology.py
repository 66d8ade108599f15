"""The mu(I) law's well-posedness and Barker & Gray's partial regularisation (plain Python).

Barker et al. (2015, eq. 3.9): the incompressible mu(I) equations are well
posed where C(I) = 4 nu^2 - 4 nu + mu^2 (1 - nu/2)^2 < 0, nu = I mu'/mu.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from foamsilo.analytic.rheology import FrictionLaw
from foamsilo.errors import FoamsiloError, SceneError
from foamsilo.scene import load_preset

STARON = {"mu_s": 0.4, "delta_mu": 0.28, "i0": 0.4}


def test_the_plain_law_is_ill_posed_at_low_and_high_inertial_number():
    law = FrictionLaw(**STARON)
    i1 = law.i1
    # Barker et al. 2015 find the plain law ill-posed below I ~ 1e-2 and
    # above I ~ 1 for such constants; here I1 = 0.0307
    assert 0.01 < i1 < 0.05
    assert law.well_posedness(0.9 * i1) > 0 > law.well_posedness(1.1 * i1)
    assert law.well_posedness(0.3) < 0
    assert law.well_posedness(5.0) > 0
    # mu_inf > 0 makes it well posed to higher I (Barker & Gray sec. 6)
    assert FrictionLaw(**STARON, mu_inf=0.05).well_posedness(5.0) < 0


def test_the_regularised_law_is_continuous_and_well_posed_below_i1():
    law = FrictionLaw(**STARON, alpha=1.9)
    i1 = law.i1
    assert law.mu(i1 * (1 - 1e-9)) == pytest.approx(law.plain(i1), rel=1e-7)
    # the low-I curve sqrt(alpha/ln(A/I)): nu = mu^2/(2 alpha), and its C
    for i in np.logspace(-12, math.log10(i1), 60)[:-1]:
        mu = law.mu(i)
        nu = mu**2 / (2 * law.alpha)
        numeric = (math.log(law.mu(i * 1.0001)) - math.log(law.mu(i / 1.0001))) / (
            2 * math.log(1.0001)
        )
        assert numeric == pytest.approx(nu, rel=1e-4)
        assert 4 * nu * nu - 4 * nu + mu * mu * (1 - nu / 2) ** 2 < 0
        assert mu < law.plain(i)  # below mu_s: the grains creep
    # above I1 the plain law, unchanged
    assert law.mu(0.2) == FrictionLaw(**STARON).mu(0.2)


def test_inverse_of_the_law():
    for law in (FrictionLaw(**STARON), FrictionLaw(**STARON, alpha=1.9),
                FrictionLaw(**STARON, mu_inf=0.05, alpha=1.9)):  # fmt: skip
        for mu in (0.405, 0.41, 0.5, 0.65):
            assert law.mu(law.inertial_number(mu)) == pytest.approx(mu, rel=1e-10)
    reg = FrictionLaw(**STARON, alpha=1.9)
    # below mu_s only the regularised law flows: I = A exp(-alpha/mu^2)
    assert reg.inertial_number(0.35) == pytest.approx(reg.a * math.exp(-1.9 / 0.35**2))
    with pytest.raises(FoamsiloError, match="must lie in"):
        FrictionLaw(**STARON).inertial_number(0.35)
    with pytest.raises(FoamsiloError, match="must lie in"):
        reg.inertial_number(0.7)
    with pytest.raises(FoamsiloError, match="0 < alpha < 2"):
        FrictionLaw(**STARON, alpha=2.0)


def test_scene_keys_of_the_regularised_law():
    m = load_preset("zhou-planar", ["material.rheology=barker-gray"]).material
    assert m.friction_law == FrictionLaw(**STARON, mu_inf=0.0, alpha=1.9)
    m = load_preset("zhou-planar", ["material.rheology=barker-gray", "material.mu_inf=0.05",
                                    "material.regularisation_alpha=1.5"]).material  # fmt: skip
    assert m.friction_law == FrictionLaw(**STARON, mu_inf=0.05, alpha=1.5)
    with pytest.raises(SceneError, match=r"material\.mu_inf.*only for material\.rheology"):
        load_preset("zhou-planar", ["material.mu_inf=0.05"])
    with pytest.raises(SceneError, match=r"material\.regularisation_alpha"):
        load_preset("zhou-planar", ["material.rheology=barker-gray",
                                    "material.regularisation_alpha=2"])  # fmt: skip
    with pytest.raises(SceneError, match=r"material\.rheology"):
        load_preset("zhou-planar", ["material.rheology=bingham"])
