"""Zhou et al. 2019: Table I, eqs 1-3, 17-25, against limits and the paper's numbers."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from foamsilo.analytic import zhou
from foamsilo.analytic.zhou import (
    LPM,
    NoPhysicalRootError,
    flow_direction,
    gas_assisted,
    kappa_inertial,
    kappa_viscous,
    q0_bottom,
    q0_lateral,
    q_impermeable,
    reduced_flow_rate,
)

NV = [0.0, 1e-3, 0.3, 1.0, 3.0, 30.0, 1e3]
NI = [0.0, 1e-3, 0.2, 0.99, 1.0, 1.01, 5.0, 1e3]


def test_table_1_to_the_digit():
    t = zhou.TABLE_I
    c = t["cyl-bottom"]
    assert (c.C0, c.beta, c.alpha_D, c.lam, c.xi_phi) == (0.69, 0.08, 0.81, 1, 0.83)
    assert c.widths == (0.020, 0.040, 0.060) and c.heights == (0.540,)
    assert c.orifice_sizes == (0.010, 0.020)
    c = t["cyl-lateral-disk"]
    assert (c.beta, c.alpha_D, c.C0l, c.lam, c.xi_phi) == (0.08, 0.82, 0.36, 0.27, None)
    assert c.orifice_sizes == (0.010, 0.020, 0.030) and c.widths == (0.040,)
    c = t["cyl-lateral-rect"]
    assert (c.beta, c.alpha_D, c.C0l, c.alpha_W, c.gamma2, c.lam, c.xi_phi) == (
        0.07, 0.45, 0.49, 0.59, 1.13, 0.27, 0.96)  # fmt: skip
    assert c.orifice_widths == (0.005, 0.010)
    c = t["rect-bottom"]
    assert (c.C0, c.beta, c.alpha_D, c.lam, c.xi_phi) == (0.86, 0.08, 0.81, 1, 1)
    assert c.heights == (0.500,) and c.orifice_widths == (0.0035,)
    c = t["rect-lateral"]
    assert (c.beta, c.alpha_D, c.C0l, c.alpha_W, c.gamma2, c.lam, c.xi_phi) == (
        0.19, None, 0.41, 0.64, 0.56, 0.23, 1)  # fmt: skip
    assert c.orifice_sizes == (0.010, 0.020)


def test_lambda_is_the_squared_ratio_of_lateral_to_bottom_prefactors():
    # sec. V: lambda = (C0l/C0)^2, to the two digits of Table I
    t = zhou.TABLE_I
    assert (t["cyl-lateral-disk"].C0l / t["cyl-bottom"].C0) ** 2 == pytest.approx(0.27, abs=0.005)
    assert (t["rect-lateral"].C0l / t["rect-bottom"].C0) ** 2 == pytest.approx(0.23, abs=0.005)


def test_unknown_configuration_lists_the_valid_ones():
    with pytest.raises(Exception, match="cyl-bottom"):
        zhou.config("hexagonal")


def test_eq1_by_hand():
    # d = 538 um, D = 10 mm, phi_b = 0.6: G = 1 - 0.81 exp(-0.08 * 10/0.538)
    G = 1 - 0.81 * math.exp(-0.08 * 10 / 0.538)
    expected = 0.69 * 0.6 * 2500 * G * math.pi * 0.01**2 / 4 * math.sqrt(9.81 * 0.01)
    assert q0_bottom(0.01, 538e-6, 0.6) == pytest.approx(expected, rel=1e-12)
    assert expected == pytest.approx(0.02080, abs=5e-5)  # 20.8 g/s, Fig. 2a scale


def test_eq24_by_hand():
    D, W, d = 0.02, 0.01, 538e-6
    F = (1 + 1.13 * D / W) ** -0.5
    G = (1 - 0.45 * math.exp(-0.07 * D / d)) * (1 - 0.59 * math.exp(-0.07 * W / d))
    expected = 0.49 * 2500 * 0.6 * G * F * W * math.sqrt(9.81 * D**3)
    got = q0_lateral(D, W, d, 0.6, 2500, 0.49, 0.45, 0.59, 0.07, 1.13)
    assert got == pytest.approx(expected, rel=1e-12)


def test_eq3_and_ergun():
    assert q_impermeable(12 * LPM, 0.6) == pytest.approx(2500 * 0.6 * 2e-4)
    phi, d = 0.55, 300e-6
    assert kappa_viscous(phi, d) == pytest.approx((1 - phi) ** 3 * d**2 / (150 * phi**2))
    assert kappa_inertial(phi, d) == pytest.approx((1 - phi) ** 3 * d**2 / (1.75 * phi))
    assert kappa_viscous(phi, d) / kappa_inertial(phi, d) == pytest.approx(1.75 / (150 * phi))


@pytest.mark.parametrize(("nv", "ni"), list(itertools.product(NV, NI)))
def test_balanced_air_flow_gives_q0(nv, ni):
    """Qtilde = 1: no relative flow at the orifice, Q = Q0 for any Nv, Ni."""
    assert reduced_flow_rate(1.0, nv, ni) == 1.0


@pytest.mark.parametrize(("nv", "ni"), list(itertools.product(NV, NI)))
@pytest.mark.parametrize("qt", [0.0, 0.2, 0.7, 1.3, 4.0, 50.0])
def test_root_satisfies_the_model_and_lies_between_1_and_qtilde(qt, nv, ni):
    qb = float(reduced_flow_rate(qt, nv, ni))
    assert min(1.0, qt) - 1e-12 <= qb <= max(1.0, qt) + 1e-12
    s = math.copysign(1.0, qt - qb) if qt != qb else 0.0
    residual = qb**2 - (1 + nv * (qt - qb) + s * ni * (qt - qb) ** 2)
    assert abs(residual) <= 1e-9 * max(1.0, qt**2, nv * qt, ni * qt**2)


def test_darcy_closed_form():
    qt = np.linspace(0, 20, 41)
    for nv in (0.1, 1.0, 10.0):
        exact = (-nv + np.sqrt(nv**2 + 4 * (1 + nv * qt))) / 2
        np.testing.assert_allclose(reduced_flow_rate(qt, nv, 0.0), exact, rtol=1e-13)


def test_large_inertial_drag_pushes_the_grains_out_at_the_air_rate():
    """Ni -> infinity: Qbar -> Qtilde (the air does not pass, it pushes)."""
    for qt in (0.3, 2.0, 10.0):
        # Qtilde - Qbar ~ sqrt(|1 - Qtilde^2| / Ni)
        assert reduced_flow_rate(qt, 1.0, 1e9) == pytest.approx(qt, rel=1e-3)


def test_vanishing_coupling_gives_the_open_top_rate():
    for qt in (0.0, 0.5, 3.0, 30.0):
        # Qbar - 1 ~ Nv Qtilde/2 + Ni Qtilde^2/2
        assert reduced_flow_rate(qt, 1e-9, 1e-9) == pytest.approx(1.0, abs=1e-6)


def test_sign_change_between_co_and_counter_current():
    qt = np.array([0.0, 0.5, 0.99, 1.0, 1.01, 2.0, 10.0])
    qb = reduced_flow_rate(qt, 2.0, 0.5)
    np.testing.assert_array_equal(flow_direction(qt), [-1, -1, -1, 0, 1, 1, 1])
    assert np.all(qb[qt < 1] < 1) and np.all(qb[qt > 1] > 1)
    assert np.all(np.diff(qb) > 0)  # more air, more grains


def test_no_physical_root_says_why():
    with pytest.raises(NoPhysicalRootError, match="Nv"):
        reduced_flow_rate(2.0, -1.0, 0.0)
    with pytest.raises(NoPhysicalRootError, match="Qtilde"):
        reduced_flow_rate(-0.5, 1.0, 0.0)


def test_gas_assisted_by_hand_d190_12lpm():
    r = gas_assisted("cyl-bottom", 190e-6, 12 * LPM, D=0.01, phi_b=0.6)
    # phi_o = 0.83 * 0.6 * (1 - 0.81 exp(-0.08 * 10/0.19))
    phi_o = 0.83 * 0.6 * (1 - 0.81 * math.exp(-0.08 * 10 / 0.19))
    assert r.phi_o == pytest.approx(phi_o, rel=1e-12)
    kv = (1 - phi_o) ** 3 * (190e-6) ** 2 / (150 * phi_o**2)
    S = math.pi * 0.01**2 / 4
    nv = 1.8e-5 * r.Q0 / (phi_o**2 * 2500**2 * kv * 9.81 * S)
    assert r.Nv == pytest.approx(nv, rel=1e-12)
    assert r.Q_air_reduced == pytest.approx(phi_o * 2500 * 2e-4 / r.Q0, rel=1e-12)
    assert r.direction == 1 and r.Q0 < r.Q < r.Q_impermeable
    assert r.Q_reduced == pytest.approx(reduced_flow_rate(r.Q_air_reduced, r.Nv, r.Ni))


def test_closed_top_slows_and_injection_speeds_up():
    for d in (190e-6, 538e-6, 1129e-6):
        closed = gas_assisted("cyl-bottom", d, 0.0, D=0.01)
        injected = gas_assisted("cyl-bottom", d, 12 * LPM, D=0.01)
        assert closed.Q < closed.Q0 < injected.Q
        assert closed.direction == -1


def test_small_grains_tend_to_the_impermeable_limit():
    # d -> 0: permeability -> 0, Q -> phi_o rho_p Q_air (eq. 3 with phi_o)
    ratios = [
        (r := gas_assisted("cyl-bottom", d, 20 * LPM, D=0.01)).Q / (r.phi_o * 2500 * 20 * LPM)
        for d in (50e-6, 10e-6, 2e-6)
    ]
    assert ratios[0] < ratios[1] < ratios[2] < 1.0
    assert ratios[2] == pytest.approx(1.0, rel=1e-3)


def test_zone_correction_and_lateral_gravity():
    full = gas_assisted("cyl-bottom", 375e-6, 12 * LPM, D=0.01)
    zone = gas_assisted("cyl-bottom", 375e-6, 12 * LPM, D=0.01, A=0.68)
    assert zone.Nv == pytest.approx(0.68 * full.Nv) and zone.Q0 < zone.Q < full.Q
    lat = gas_assisted("cyl-lateral-rect", 375e-6, 12 * LPM, D=0.02, W=0.01)
    # g -> lambda g: N_v, N_i divided by lambda = 0.27
    from foamsilo.analytic.zhou import reduced_numbers

    nv, ni = reduced_numbers(lat.Q0, lat.phi_o, 375e-6, lat.S_o)
    assert lat.Nv == pytest.approx(nv / 0.27) and lat.Ni == pytest.approx(ni / 0.27)


def test_darcy_switch():
    r = gas_assisted("cyl-bottom", 190e-6, 12 * LPM, D=0.01, inertial=False)
    assert r.Ni == 0.0
    assert r.Q_reduced == pytest.approx(
        (-r.Nv + math.sqrt(r.Nv**2 + 4 * (1 + r.Nv * r.Q_air_reduced))) / 2
    )


def test_bad_input_is_named():
    with pytest.raises(Exception, match="phi_b"):
        gas_assisted("cyl-bottom", 190e-6, 0.0, phi_b=1.2)
    with pytest.raises(Exception, match="q_air"):
        gas_assisted("cyl-bottom", 190e-6, -1.0)
    with pytest.raises(Exception, match="phi_o"):
        gas_assisted("cyl-lateral-disk", 190e-6, 0.0)
