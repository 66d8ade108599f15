"""Exact solutions (Bagnold, Janssen, Darcy slot) and the fitting routines."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from foamsilo.analytic import exact, fit, zhou
from foamsilo.analytic.beverloo import beverloo_2d, beverloo_2d_constant
from foamsilo.cli import main

# --------------------------------------------------------------------- Bagnold

MU = dict(mu_s=0.4, delta_mu=0.28, i0=0.4)


def test_bagnold_profile_satisfies_mu_of_i_everywhere():
    theta, h, d, rho, g = math.radians(27.0), 0.02, 1e-3, 2500.0, 9.81
    z = np.linspace(0, h, 2001)
    u = exact.bagnold_velocity(z, h, theta, d=d, **MU)
    shear = np.gradient(u, z)
    p = rho * g * math.cos(theta) * (h - z)
    inner = (z > 1e-3 * h) & (z < 0.98 * h)  # one-sided differences at the ends
    inertial = shear[inner] * d / np.sqrt(p[inner] / rho)
    mu = MU["mu_s"] + MU["delta_mu"] / (MU["i0"] / inertial + 1)
    np.testing.assert_allclose(mu, math.tan(theta), rtol=1e-4)
    assert u[0] == 0.0  # no slip
    ubar = exact.bagnold_mean_velocity(h, theta, d=d, **MU)
    assert ubar == pytest.approx(np.trapezoid(u, z) / h, rel=1e-6)
    assert ubar == pytest.approx(0.6 * u[-1], rel=1e-12)  # Bagnold: 3/5


def test_bagnold_outside_the_flowing_range_is_an_error():
    with pytest.raises(Exception, match="no steady flow"):
        exact.bagnold_inertial_number(math.atan(0.35), **MU)
    with pytest.raises(Exception, match="no steady flow"):
        exact.bagnold_inertial_number(math.atan(0.70), **MU)


# --------------------------------------------------------------------- Janssen


def test_janssen_limits():
    R = exact.hydraulic_radius("cylinder", 0.06)
    assert R == pytest.approx(0.015)
    assert exact.hydraulic_radius("slot", 0.1) == pytest.approx(0.05)
    assert exact.hydraulic_radius("box", 0.06, 0.0035) == pytest.approx(
        0.06 * 0.0035 / (2 * 0.0635)
    )
    s = np.array([1e-6, 10.0])
    sv = exact.janssen_vertical_stress(s, 1500, R, 0.5, 0.3)
    assert sv[0] == pytest.approx(1500 * 9.81 * 1e-6, rel=1e-4)  # hydrostatic near the top
    assert sv[1] == pytest.approx(1500 * 9.81 * R / (0.5 * 0.3), rel=1e-9)  # saturation
    assert exact.janssen_wall_pressure(s, 1500, R, 0.5, 0.3)[1] == pytest.approx(0.5 * sv[1])


# ----------------------------------------------------------------------- Darcy


def _slot(x, y):
    return exact.darcy_slit_pressure(x, y, 1e-3, 1e-9, 1.8e-5, 0.025, 0.1)


def test_darcy_slot_boundary_conditions_and_far_field():
    L, q, k, eta = 0.1, 1e-3, 1e-9, 1.8e-5
    # p = 0 on the slot
    assert np.allclose(_slot(np.linspace(-0.012, 0.012, 9), 0.0), 0.0, atol=1e-9)
    # no flux through the bottom wall and the side walls (one-sided
    # differences: error h p''/2, far below the far-field gradient)
    h = 1e-7
    far_grad = eta * q / (k * L)
    xw = np.linspace(0.014, 0.049, 8)
    assert np.allclose((_slot(xw, h) - _slot(xw, 0.0)) / h, 0.0, atol=1e-4 * far_grad)
    yw = np.linspace(0.01, 0.3, 8)
    assert np.allclose((_slot(0.05, yw) - _slot(0.05 - h, yw)) / h, 0.0, atol=1e-4 * far_grad)
    # uniform far-field gradient eta q/(kappa L)
    far = (_slot(0.02, 0.31) - _slot(0.02, 0.30)) / 0.01
    assert far == pytest.approx(eta * q / (k * L), rel=1e-6)
    # the gas flux through a line above the slot is q (mass conservation)
    x = np.linspace(-L / 2, L / 2, 4001)
    y0, dy = 0.02, 1e-6
    grad = (_slot(x, y0 + dy) - _slot(x, y0 - dy)) / (2 * dy)
    assert np.trapezoid(k / eta * grad, x) == pytest.approx(q, rel=1e-5)


def test_darcy_slot_is_harmonic():
    x, y, h = 0.013, 0.01, 1e-4
    lap = (_slot(x + h, y) + _slot(x - h, y) + _slot(x, y + h) + _slot(x, y - h)
           - 4 * _slot(x, y)) / h**2  # fmt: skip
    assert abs(lap) < 1e-6 * abs(_slot(x, y)) / h**2


def test_darcy_slot_gradient_ratio_is_l_over_d():
    """Zhou sec. III.B: grad at the orifice = (L/D) x grad far from it."""
    L, D = 0.1, 0.025
    y = 1e-9
    x = 0.5 * D * np.sin(np.linspace(-np.pi / 2, np.pi / 2, 20001))  # dense at the edges
    g0 = _slot(x, y) / y
    mean_at_slot = np.trapezoid(g0, x) / D
    far = 1.8e-5 * 1e-3 / (1e-9 * L)
    assert mean_at_slot / far == pytest.approx(L / D, rel=2e-3)


def test_darcy_column():
    assert exact.darcy_column_gradient(0.01, 1e-10, 1.8e-5) == pytest.approx(1.8e-5 * 0.01 / 1e-10)
    f = exact.darcy_column_gradient(0.01, 1e-10, 1.8e-5, kappa_i=1e-8, rho_f=1.2, d=2e-4)
    assert f == pytest.approx(1.8e-5 * 0.01 / 1e-10 + 1.2 * 2e-4 * 1e-4 / 1e-8)


# --------------------------------------------------------------------- Beverloo


def test_beverloo_2d_constant_from_the_paper():
    assert beverloo_2d_constant() == pytest.approx(1.28)
    L, rho = 0.1, 2500.0
    q = beverloo_2d(0.25 * L, rho)
    assert q / (rho * math.sqrt(9.81 * L**3)) == pytest.approx(0.16, rel=1e-12)
    assert beverloo_2d(0.5 * L, rho) / q == pytest.approx(2**1.5)  # D^(3/2)


# ----------------------------------------------------------------------- fits


def test_open_top_fit_recovers_table_1():
    rng = np.random.default_rng(1)
    D = np.repeat([0.010, 0.020], 7)
    d = np.tile(np.array([124, 190, 375, 538, 762, 1129, 1347]) * 1e-6, 2)
    Q = zhou.q0_bottom(D, d, 0.6, C0=0.69, alpha_D=0.81, beta=0.08)
    noisy = Q * (1 + 0.01 * rng.standard_normal(Q.size))
    r = fit.fit_open_top(D, d, noisy, 0.6)
    for name, true in (("C0", 0.69), ("alpha_D", 0.81), ("beta", 0.08)):
        assert abs(r.values[name] - true) < 4 * r.sigmas[name], name
    exact_fit = fit.fit_open_top(D, d, Q, 0.6)
    assert exact_fit.values["C0"] == pytest.approx(0.69, rel=1e-6)
    assert exact_fit.rms_relative_residual < 1e-8


def test_phi_o_and_xi_phi_fits_recover_the_model():
    qa = np.array([0, 1, 2, 5, 10, 20, 30]) * zhou.LPM
    Q = np.array([gas_q(375e-6, x, phi_o=0.45) for x in qa])
    r = fit.fit_phi_o("cyl-bottom", 375e-6, qa, Q, D=0.01)
    assert r.values["phi_o"] == pytest.approx(0.45, rel=1e-6)
    d = np.repeat([190e-6, 538e-6], len(qa))
    qq = np.tile(qa, 2)
    Qx = np.array([zhou.gas_assisted("cyl-bottom", di, x, D=0.01).Q
                   for di, x in zip(d, qq, strict=True)])  # fmt: skip
    rx = fit.fit_xi_phi("cyl-bottom", d, qq, Qx, D=0.01)
    assert rx.values["xi_phi"] == pytest.approx(0.83, rel=1e-6)


def gas_q(d, qa, phi_o):
    return zhou.gas_assisted("cyl-bottom", d, qa, D=0.01, phi_o=phi_o).Q


# ------------------------------------------------------------------------ CLI


def test_cli_gas_contract(capsys):
    code = main(["analytic", "gas", "--preset", "cyl-bottom", "--d", "190e-6", "--q-air-lpm",
                 "12", "--silo-width", "0.06", "--orifice", "0.01", "--phi-b", "0.6",
                 "--rho-p", "2500", "--A", "1", "--json"])  # fmt: skip
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("Q", "Q0", "Nv", "Ni", "phi_o", "Q_air_reduced"):
        assert isinstance(out[key], float), key
    ref = zhou.gas_assisted("cyl-bottom", 190e-6, 12 * zhou.LPM, D=0.01)
    assert out["Q"] == pytest.approx(ref.Q)
    assert main(["analytic", "gas", "--d", "190e-6", "--q-air-lpm", "12", "--no-inertial",
                 "--json"]) == 0  # fmt: skip
    assert json.loads(capsys.readouterr().out)["Ni"] == 0.0


def test_cli_fits_from_csv(tmp_path, capsys):
    f = tmp_path / "open.csv"
    rows = ["D,d,Q"]
    for D in (0.01, 0.02):
        for d in (190e-6, 375e-6, 538e-6, 1129e-6):
            rows.append(f"{D},{d},{zhou.q0_bottom(D, d, 0.6)}")
    f.write_text("\n".join(rows))
    assert main(["analytic", "fit-open-top", str(f), "--json"]) == 0
    v = json.loads(capsys.readouterr().out)["values"]
    assert v["C0"] == pytest.approx(0.69, rel=1e-5)


def test_figures(tmp_path):
    from foamsilo.analytic.figures import all_figures

    paths = all_figures(tmp_path)
    assert len(paths) == 4
    assert all(p.stat().st_size > 20_000 for p in paths)
