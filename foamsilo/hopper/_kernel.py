"""Compiled march of the hopper DG solver (numba), the same scheme as :mod:`dg`.

:class:`foamsilo.hopper.dg.HopperDG` holds the readable NumPy form of each
operator; this module loops over cells in compiled code so that a whole
march (tens of thousands of RK stages) costs seconds, not minutes. The two
are checked against each other in the tests.

Arguments are packed as in :meth:`HopperDG._kernel_args`: ``par`` = (dim, s,
alpha, beta, gamma, chi_w, rho g) with the equation of state
h(a, b) = alpha a + sqrt(beta a^2 + gamma b^2); ``geo`` = (cos, sin, cot at
the Gauss points, P_m(xi_l), weighted P_m', weighted P_m); ``vec`` =
(P_m(-1), inverse mass).
"""

# ruff: noqa: ANN001, ANN201, ANN202 -- numba-compiled functions, typed at compile time

from __future__ import annotations

import math

import numpy as np
from numba import njit

LOST = 1


@njit(cache=True, inline="always")
def _at(u, j, q, phi):
    """(T_rr, T_rt) of cell j at Gauss point q."""
    a = 0.0
    b = 0.0
    for m in range(u.shape[2]):
        a += u[0, j, m] * phi[m, q]
        b += u[1, j, m] * phi[m, q]
    return a, b


@njit(cache=True, inline="always")
def _edge(u, j, side):
    """(T_rr, T_rt) of cell j at its right (side = +1) or left (-1) edge."""
    a = 0.0
    b = 0.0
    w = 1.0
    for m in range(u.shape[2]):
        a += u[0, j, m] * w
        b += u[1, j, m] * w
        w *= side
    return a, b


@njit(cache=True, inline="always")
def _eigen(a, b, al, be, ga):
    """Eigenvalues lambda_1 < 0 < lambda_2 of F'(U) = -[[0, 1], [p, q]]."""
    x = math.sqrt(max(be * a * a + ga * b * b, 1e-300))
    p = al + be * a / x
    q = ga * b / x
    root = math.sqrt(q * q + 4 * p)
    return (-q - root) / 2, (-q + root) / 2


@njit(cache=True, inline="always")
def _wall(a, b, al, be, ga, chi):
    """Wall ghost state: outgoing characteristic kept, incoming from T_rr = chi T_rt."""
    l1, l2 = _eigen(a, b, al, be, ga)
    r11, r21, r12, r22 = 1.0, -l1, 1.0, -l2
    u2 = (-r21 * a + r11 * b) / (r11 * r22 - r12 * r21)
    u1 = (-r12 + chi * r22) / (r11 - chi * r21) * u2
    return r11 * u1 + r12 * u2, r21 * u1 + r22 * u2


@njit(cache=True)
def rhs(u, tau, par, geo, vec, du):
    """dU/dtau into ``du``; returns (status, cell, lambda_max)."""
    dim, s, al, be, ga, chi, rho_g = par
    cos_q, sin_q, cot_q, phi, w_dphi, w_phi = geo
    sign, inv_mass = vec
    n, kk = u.shape[1], u.shape[2]
    w = rho_g * math.exp(-tau)
    for j in range(n):
        for m in range(kk):
            du[0, j, m] = 0.0
            du[1, j, m] = 0.0
        for q in range(5):
            a, b = _at(u, j, q, phi)
            disc = be * a * a + ga * b * b
            if disc <= 0.0 or a <= 0.0:
                return LOST, j, 0.0
            h = al * a + math.sqrt(disc)
            if dim == 3:
                c = cot_q[j, q]
                f = 0.5 * (3 - s) * a + c * b - 0.5 * (3 + s) * h + w * cos_q[j, q]
                g = c * (0.5 * (1 - s) * h - 0.5 * (1 + s) * a) + 3 * b - w * sin_q[j, q]
            else:
                f = a - h + w * cos_q[j, q]
                g = 2 * b - w * sin_q[j, q]
            for m in range(kk):
                du[0, j, m] += -b * w_dphi[q, m] + f * w_phi[q, m]
                du[1, j, m] += -h * w_dphi[q, m] + g * w_phi[q, m]
    lam = 0.0
    h0p = 0.0
    h1p = 0.0
    for i in range(n + 1):  # interface theta_{i-1/2}
        if i == 0:  # the axis: mirror (T_rr even, T_rt odd)
            ar, br = _edge(u, 0, -1.0)
            a_l, b_l = ar, -br
        else:
            a_l, b_l = _edge(u, i - 1, 1.0)
            if i == n:
                ar, br = _wall(a_l, b_l, al, be, ga, chi)
            else:
                ar, br = _edge(u, i, -1.0)
        dl = be * a_l * a_l + ga * b_l * b_l
        dr = be * ar * ar + ga * br * br
        if dl <= 0.0 or dr <= 0.0:
            return LOST, min(i, n - 1), 0.0
        xl = math.sqrt(dl)
        xr = math.sqrt(dr)
        xb = 0.5 * (xl + xr)
        # the paper's Roe matrix, largest |eigenvalue|: the Lax-Friedrichs viscosity
        p = al + be * 0.5 * (a_l + ar) / xb
        q2 = ga * 0.5 * (b_l + br) / xb
        sp = 0.5 * (abs(q2) + math.sqrt(max(q2 * q2 + 4 * p, 0.0)))
        lam = max(lam, sp)
        h0 = 0.5 * (-b_l - br - sp * (ar - a_l))
        h1 = 0.5 * (-(al * a_l + xl) - (al * ar + xr) - sp * (br - b_l))
        if i > 0:  # close cell i-1
            for m in range(kk):
                du[0, i - 1, m] = (du[0, i - 1, m] - h0 + sign[m] * h0p) * inv_mass[m]
                du[1, i - 1, m] = (du[1, i - 1, m] - h1 + sign[m] * h1p) * inv_mass[m]
        h0p = h0
        h1p = h1
    return 0, -1, lam


@njit(cache=True, inline="always")
def _mm(a, b, c):
    if a > 0 and b > 0 and c > 0:
        return min(a, min(b, c))
    if a < 0 and b < 0 and c < 0:
        return max(a, max(b, c))
    return 0.0


@njit(cache=True)
def limit(u, par, tvb_bound, sign):
    """Corrected minmod in characteristic variables, in place."""
    _, _, al, be, ga, _, _ = par
    n, kk = u.shape[1], u.shape[2]
    if kk == 1:
        return
    mean0 = u[0, :, 0].copy()
    mean1 = u[1, :, 0].copy()
    for j in range(n):
        a = mean0[j]
        b = mean1[j]
        l1, l2 = _eigen(a, b, al, be, ga)
        det = l1 - l2
        # neighbour differences: the mirror at the axis, one-sided at the wall
        if j == 0:
            dm0, dm1 = 0.0, 2 * b
        else:
            dm0, dm1 = a - mean0[j - 1], b - mean1[j - 1]
        if j == n - 1:
            dp0, dp1 = dm0, dm1
        else:
            dp0, dp1 = mean0[j + 1] - a, mean1[j + 1] - b
        r0, r1 = _edge(u, j, 1.0)
        e0, e1 = _edge(u, j, -1.0)
        r0, r1, e0, e1 = r0 - a, r1 - b, a - e0, b - e1
        # to characteristic variables: R^-1 = [[-l2, -1], [l1, 1]] / det
        cr0, cr1 = (-l2 * r0 - r1) / det, (l1 * r0 + r1) / det
        cl0, cl1 = (-l2 * e0 - e1) / det, (l1 * e0 + e1) / det
        cp0, cp1 = (-l2 * dp0 - dp1) / det, (l1 * dp0 + dp1) / det
        cm0, cm1 = (-l2 * dm0 - dm1) / det, (l1 * dm0 + dm1) / det
        bound = tvb_bound * abs(a)
        changed = False
        for v, pp, mm in ((cr0, cp0, cm0), (cr1, cp1, cm1), (cl0, cp0, cm0), (cl1, cp1, cm1)):
            if abs(v) > bound and _mm(v, pp, mm) != v:
                changed = True
        if changed:
            s0 = _mm((-l2 * u[0, j, 1] - u[1, j, 1]) / det, cp0, cm0)
            s1 = _mm((l1 * u[0, j, 1] + u[1, j, 1]) / det, cp1, cm1)
            u[0, j, 1] = s0 + s1
            u[1, j, 1] = -l1 * s0 - l2 * s1
            for m in range(2, kk):
                u[0, j, m] = 0.0
                u[1, j, m] = 0.0


@njit(cache=True)
def _record(u, tau, phi, ref_rr, ref_rt, row, out_rr, out_rt):
    """Keep the values at the Gauss points; return the error to the reference."""
    e = math.exp(-tau)
    emax = 0.0
    scale = 0.0
    for j in range(u.shape[1]):
        for q in range(5):
            a, b = _at(u, j, q, phi)
            out_rr[row, 5 * j + q] = a
            out_rt[row, 5 * j + q] = b
            if ref_rr.shape[0] > 0:
                ra = e * ref_rr[j, q]
                emax = max(emax, max(abs(a - ra), abs(b - e * ref_rt[j, q])))
                scale = max(scale, abs(ra))
    return emax / scale if scale > 0 else 0.0


@njit(cache=True)
def _worst_psi(u, par, phi):
    """Largest |psi| at the Gauss points and where; (inf, j, q) off the cone."""
    _, _, al, be, ga, _, _ = par
    worst, wj, wq = 0.0, 0, 0
    for j in range(u.shape[1]):
        for q in range(5):
            a, b = _at(u, j, q, phi)
            disc = be * a * a + ga * b * b
            if disc <= 0.0 or a <= 0.0:
                return math.inf, j, q
            psi = abs(0.5 * math.atan2(-b, 0.5 * (al * a + math.sqrt(disc) - a)))
            if psi > worst:
                worst, wj, wq = psi, j, q
    return worst, wj, wq


@njit(cache=True)
def _combine(out, a, x, b, y, dt, du):
    """Set out = a x + b (y + dt du), elementwise, without temporaries."""
    o, xf, yf, df = out.ravel(), x.ravel(), y.ravel(), du.ravel()
    for i in range(o.shape[0]):
        o[i] = a * xf[i] + b * (yf[i] + dt * df[i])


@njit(cache=True)
def march(u, tau0, tau_end, k, dtheta, cfl, psi_limit, tvb_bound, par, geo, vec, marks,
          ref_rr, ref_rt, out_tau, out_rr, out_rt, out_err):  # fmt: skip
    """TVD RK3 march; returns (status, steps, n_records, tau, cell, quad point)."""
    du = np.empty_like(u)
    u1 = np.empty_like(u)
    u2 = np.empty_like(u)
    phi = geo[3]
    limit(u, par, tvb_bound, vec[0])
    st, cell, lam = rhs(u, tau0, par, geo, vec, du)
    if st != 0:
        return st, 0, 0, tau0, cell, 0
    tau, steps, nrec = tau0, 0, 0
    while True:
        while nrec < marks.shape[0] and marks[nrec] <= tau + 1e-12:
            out_err[nrec] = _record(u, tau, phi, ref_rr, ref_rt, nrec, out_rr, out_rt)
            out_tau[nrec] = tau
            nrec += 1
        if tau >= tau_end - 1e-12:
            return 0, steps, nrec, tau, -1, 0
        dt = min(cfl * dtheta / ((2 * k + 1) * max(lam, 1e-12)), tau_end - tau)
        # TVD RK3 (Shu-Osher), the limiter after each stage
        _combine(u1, 0.0, u, 1.0, u, dt, du)
        limit(u1, par, tvb_bound, vec[0])
        st, cell, _ = rhs(u1, tau + dt, par, geo, vec, du)
        if st != 0:
            return st, steps, nrec, tau + dt, cell, 0
        _combine(u2, 0.75, u, 0.25, u1, dt, du)
        limit(u2, par, tvb_bound, vec[0])
        st, cell, _ = rhs(u2, tau + 0.5 * dt, par, geo, vec, du)
        if st != 0:
            return st, steps, nrec, tau + 0.5 * dt, cell, 0
        _combine(u, 1.0 / 3.0, u, 2.0 / 3.0, u2, dt, du)
        limit(u, par, tvb_bound, vec[0])
        tau += dt
        steps += 1
        worst, wj, wq = _worst_psi(u, par, phi)
        if worst >= psi_limit:
            return LOST, steps, nrec, tau, wj, wq
        st, cell, lam = rhs(u, tau, par, geo, vec, du)
        if st != 0:
            return st, steps, nrec, tau, cell, 0
