"""Discontinuous Galerkin solver of the hopper stress equations (Gremaud & Matthews sec. 5).

The steady stresses of a Mohr-Coulomb material in a wedge (2D) or cone (3D),
in tau = -ln r (time-like, down the hopper) and theta (space-like, axis to
wall), form the strictly hyperbolic system (eq. 12)::

    d_tau U + d_theta F(U) = G(tau, theta, U),   U = (T_rr, T_rt),
    F(U) = -(T_rt, h(T_rr, T_rt)),               T_tt = h (eq. 9, passive state)

with G of eq. 7 (cone) or eq. 11 (wedge). Discretisation as in the paper:
P^k elements (k = 0, 1, 2) with a Legendre basis (diagonal mass matrix),
5-point Gauss quadrature, the local Lax-Friedrichs flux whose viscosity is
the largest eigenvalue of the Roe matrix given in the paper, the symmetry
condition at the axis (T_rr even, T_rt odd), the wall condition
T_rr = chi_w T_rt imposed on the incoming characteristic, third-order TVD
Runge-Kutta in tau with the (TVB-corrected) minmod limiter applied in
characteristic variables after every stage, and the step restriction
lambda_max dtau/dtheta <= 1/(2k+1).

Everything is vectorised over cells with NumPy; one right-hand side is a few
dozen array operations of length N.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.polynomial import legendre

from foamsilo.hopper.radial import Dim, HopperError, Material, sokolovskii


class HyperbolicityLostError(HopperError):
    """|psi| reached pi/4 - delta/2: the equation of state (9) has no real root.

    Attributes
    ----------
    tau, theta
        Where (tau = -ln r, theta in rad).
    psi
        The Sokolovskii angle there [rad].
    """

    def __init__(self, tau: float, theta: float, psi: float, limit: float) -> None:
        self.tau, self.theta, self.psi, self.limit = tau, theta, psi, limit
        super().__init__(
            f"hyperbolicity lost at tau = {tau:.4f} (r = {math.exp(-tau):.4g} r0), "
            f"theta = {math.degrees(theta):.3f} deg: |psi| = {math.degrees(abs(psi)):.3f} deg "
            f"reached pi/4 - delta/2 = {math.degrees(limit):.3f} deg, where T_tt = h(T_rr, T_rt) "
            "(eq. 9) has no real value and the stress system stops being hyperbolic in tau "
            "(the characteristics no longer point down the hopper)"
        )


# 5-point Gauss-Legendre rule on [-1, 1]
_XI, _W = legendre.leggauss(5)


def _basis(k: int) -> tuple[np.ndarray, np.ndarray]:
    """P_m(xi_l) and P_m'(xi_l), m = 0..k, at the Gauss points."""
    phi = np.empty((k + 1, 5))
    dphi = np.empty((k + 1, 5))
    for m in range(k + 1):
        c = np.zeros(m + 1)
        c[m] = 1.0
        phi[m] = legendre.legval(_XI, c)
        dphi[m] = legendre.legval(_XI, legendre.legder(c))
    return phi, dphi


class _Job(NamedTuple):
    """One march: initial coefficients, tau range, record marks, reference values."""

    u: np.ndarray
    tau0: float
    tau_end: float
    marks: np.ndarray
    ref: tuple[np.ndarray, np.ndarray]


@dataclass
class DGResult:
    """The solution down the hopper.

    Attributes
    ----------
    tau
        Recorded tau values.
    theta
        Gauss points of every cell, (N, 5) flattened [rad].
    t_rr, t_rt
        Stresses at ``theta`` for each recorded tau, (n_tau, 5N) [Pa].
    error
        Largest difference to the reference field at each recorded tau,
        relative to the largest |T_rr| there (None without a reference).
    steps, wall_s
        Time steps taken and wall time of the integration.
    status
        ``ok``, or ``hyperbolicity_lost`` with ``stop`` describing where.
    """

    tau: np.ndarray
    theta: np.ndarray
    t_rr: np.ndarray
    t_rt: np.ndarray
    error: np.ndarray | None
    steps: int
    wall_s: float
    status: str = "ok"
    stop: dict[str, float] | None = None
    coefficients: np.ndarray | None = field(default=None, repr=False)


class HopperDG:
    """DG P^k discretisation of the stress system on 0 <= theta <= theta_w.

    Parameters
    ----------
    dim
        2 (wedge) or 3 (cone).
    theta_w
        Half opening angle of the hopper [rad].
    material
        Internal and wall friction, rho g.
    k
        Polynomial degree (0, 1 or 2).
    cells
        Number of cells N across the half hopper.
    tvb_m
        TVB constant of the corrected minmod, relative to the local |T_rr|
        (0: plain minmod).
    cfl
        Fraction of the step limit lambda_max dtau/dtheta = 1/(2k+1).
    """

    def __init__(
        self,
        dim: Dim,
        theta_w: float,
        material: Material,
        k: int = 1,
        cells: int = 100,
        tvb_m: float = 50.0,
        cfl: float = 1.0,
    ) -> None:
        if dim not in (2, 3):
            raise HopperError(f"dim = {dim}: allowed 2 (wedge) or 3 (cone)")
        if k not in (0, 1, 2):
            raise HopperError(f"k = {k}: allowed 0, 1, 2")
        if cells < 2:
            raise HopperError(f"cells = {cells}: allowed >= 2")
        if not 0 < cfl <= 1:
            raise HopperError(f"cfl = {cfl:g}: allowed 0 < cfl <= 1")
        self.dim, self.theta_w, self.m, self.k, self.n = dim, theta_w, material, k, cells
        self.tvb_m, self.cfl = tvb_m, cfl
        s = material.s
        self.s = s
        # eq. 9 as h(a, b) = alpha a + sqrt(beta a^2 + gamma b^2)
        self.alpha = (1 + s * s) / (1 - s * s)
        self.beta = 4 * s * s / (1 - s * s) ** 2
        self.gamma = -4 / (1 - s * s)
        self.dtheta = theta_w / cells
        self.centres = (np.arange(cells) + 0.5) * self.dtheta
        self.theta_q = self.centres[:, None] + 0.5 * self.dtheta * _XI[None, :]
        self.phi, self.dphi = _basis(k)
        self.sign = (-1.0) ** np.arange(k + 1)  # P_m(-1)
        self.inv_mass = (2 * np.arange(k + 1) + 1) / self.dtheta
        # quadrature-weighted basis for the volume integrals
        self.w_dphi = np.ascontiguousarray((_W[None, :] * self.dphi).T)  # (5, K)
        self.w_phi = np.ascontiguousarray((0.5 * self.dtheta * _W[None, :] * self.phi).T)
        self.cos_q, self.sin_q = np.cos(self.theta_q), np.sin(self.theta_q)
        self.cot_q = self.cos_q / self.sin_q
        self.lambda_max = 0.0

    # -------------------------------------------------------------- projection
    def project(self, t_rr: Any, t_rt: Any) -> np.ndarray:
        """L2 projection (Pi_V) of functions of theta onto P^k: coefficients (2, N, K)."""
        a = np.asarray(t_rr(self.theta_q), float)
        b = np.asarray(t_rt(self.theta_q), float)
        vals = np.stack([a, b])  # (2, N, 5)
        return vals @ (_W[:, None] * self.phi.T) * ((2 * np.arange(self.k + 1) + 1) / 2)

    def values(self, u: np.ndarray) -> np.ndarray:
        """Values at the Gauss points, (2, N, 5)."""
        return u @ self.phi

    # ---------------------------------------------------------------- physics
    def _h(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        disc = self.beta * a * a + self.gamma * b * b
        return self.alpha * a + np.sqrt(np.maximum(disc, 0.0)), disc

    def eigenvalues(self, a: Any, b: Any) -> tuple[np.ndarray, np.ndarray]:
        """Eigenvalues lambda_1 < 0 < lambda_2 of the Jacobian F'(U) at (T_rr, T_rt)."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        x = np.sqrt(self.beta * a * a + self.gamma * b * b)
        p = self.alpha + self.beta * a / x
        q = self.gamma * b / x
        root = np.sqrt(q * q + 4 * p)
        return (-q - root) / 2, (-q + root) / 2

    def flux(self, a: Any, b: Any) -> np.ndarray:
        """F(U) = -(T_rt, h(T_rr, T_rt))."""
        return -np.stack([np.asarray(b, float), self._h(np.asarray(a), np.asarray(b))[0]])

    def _roe_speed(
        self, al: np.ndarray, bl: np.ndarray, ar: np.ndarray, br: np.ndarray
    ) -> np.ndarray:
        """|largest eigenvalue| of the paper's Roe matrix A_{j+1/2}."""
        xl = np.sqrt(np.maximum(self.beta * al * al + self.gamma * bl * bl, 0.0))
        xr = np.sqrt(np.maximum(self.beta * ar * ar + self.gamma * br * br, 0.0))
        xb = 0.5 * (xl + xr)
        p = self.alpha + self.beta * 0.5 * (al + ar) / xb
        q = self.gamma * 0.5 * (bl + br) / xb
        # A = -[[0, 1], [p, q]]: eigenvalues (-q -+ sqrt(q^2 + 4p)) / 2
        return 0.5 * (np.abs(q) + np.sqrt(np.maximum(q * q + 4 * p, 0.0)))

    def _wall_state(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the outside state at the wall (incoming characteristic from T_rr = chi_w T_rt)."""
        l1, l2 = self.eigenvalues(a, b)
        # right eigenvectors of F' = -[[0, 1], [p, q]]: r_i = (1, -lambda_i)
        r11, r21, r12, r22 = 1.0, -l1, 1.0, -l2
        det = r11 * r22 - r12 * r21
        u2 = (-r21 * a + r11 * b) / det  # second row of R^-1 applied to U
        chi = self.m.chi_w
        u1 = (-r12 + chi * r22) / (r11 - chi * r21) * u2
        return r11 * u1 + r12 * u2, r21 * u1 + r22 * u2

    def source(self, tau: float, a: np.ndarray, b: np.ndarray, h: np.ndarray) -> np.ndarray:
        """G of eq. 7 (cone) or eq. 11 (wedge) at the Gauss points."""
        w = self.m.rho_g * math.exp(-tau)
        s = self.s
        if self.dim == 3:
            f = 0.5 * (3 - s) * a + self.cot_q * b - 0.5 * (3 + s) * h + w * self.cos_q
            g = self.cot_q * (0.5 * (1 - s) * h - 0.5 * (1 + s) * a) + 3 * b - w * self.sin_q
        else:
            f = a - h + w * self.cos_q
            g = 2 * b - w * self.sin_q
        return np.stack([f, g])

    # ------------------------------------------------------------- operators
    def rhs(self, u: np.ndarray, tau: float) -> np.ndarray:
        """dU/dtau of the semi-discretisation (18)."""
        q = u @ self.phi  # (2, N, 5)
        a, b = q[0], q[1]
        h, disc = self._h(a, b)
        if disc.min() <= 0.0 or a.min() <= 0.0:
            self._lost(u, tau)
        vol = np.stack([-b, -h]) @ self.w_dphi + self.source(tau, a, b, h) @ self.w_phi
        right = u.sum(axis=2)  # U(theta_{j+1/2}^-)
        left = u @ self.sign  # U(theta_{j-1/2}^+)
        n = self.n
        ul = np.empty((2, n + 1))
        ur = np.empty((2, n + 1))
        ul[:, 1:] = right
        ur[:, :-1] = left
        ul[0, 0], ul[1, 0] = left[0, 0], -left[1, 0]  # mirror at the axis
        ur[0, n:], ur[1, n:] = self._wall_state(right[0, -1:], right[1, -1:])
        hl, dl = self._h(ul[0], ul[1])
        hr, dr = self._h(ur[0], ur[1])
        if min(dl.min(), dr.min()) <= 0.0:
            self._lost(u, tau)
        speed = self._roe_speed(ul[0], ul[1], ur[0], ur[1])
        self.lambda_max = float(speed.max())
        fl = np.stack([-ul[1], -hl])
        fr = np.stack([-ur[1], -hr])
        hflux = 0.5 * (fl + fr - speed * (ur - ul))  # (2, N+1)
        du = vol - hflux[:, 1:, None] + hflux[:, :-1, None] * self.sign
        return du * self.inv_mass

    def limit(self, u: np.ndarray) -> np.ndarray:
        """Corrected minmod limiter in characteristic variables (Lambda Pi)."""
        if self.k == 0:
            return u
        mean = u[:, :, 0]
        dev_r = u[:, :, 1:].sum(axis=2)  # U_{j+1/2}^- - mean
        dev_l = -(u[:, :, 1:] @ self.sign[1:])  # mean - U_{j-1/2}^+
        # the axis: the mirrored neighbour (T_rr even, T_rt odd); the wall:
        # no neighbour, the one-sided difference stands for both
        ghost_l = np.array([mean[0, 0], -mean[1, 0]])
        ext = np.concatenate([ghost_l[:, None], mean], axis=1)
        d_minus = mean - ext[:, :-1]
        d_plus = np.empty_like(mean)
        d_plus[:, :-1] = d_minus[:, 1:]
        d_plus[:, -1] = d_minus[:, -1]
        l1, l2 = self.eigenvalues(mean[0], mean[1])
        # R = [[1, 1], [-l1, -l2]], R^-1 = [[-l2, -1], [l1, 1]] / (l1 - l2)
        det = l1 - l2

        def to_char(v: np.ndarray) -> np.ndarray:
            return np.stack([(-l2 * v[0] - v[1]) / det, (l1 * v[0] + v[1]) / det])

        cr, cl = to_char(dev_r), to_char(dev_l)
        cp, cm = to_char(d_plus), to_char(d_minus)
        bound = self.tvb_m * self.dtheta**2 * np.abs(mean[0])
        mr, ml = _tvb_minmod(cr, cp, cm, bound), _tvb_minmod(cl, cp, cm, bound)
        changed = np.any((mr != cr) | (ml != cl), axis=0)
        if not changed.any():
            return u
        slope = _minmod(to_char(u[:, :, 1]), cp, cm)
        new = np.stack([slope[0] + slope[1], -l1 * slope[0] - l2 * slope[1]])  # R slope
        out = u.copy()
        out[:, changed, 1] = new[:, changed]
        out[:, changed, 2:] = 0.0
        return out

    def _lost(self, u: np.ndarray, tau: float) -> None:
        """Raise where |T_rt / T_rr| >= tan delta, i.e. |psi| >= pi/4 - delta/2."""
        q = u @ self.phi
        a, b = q[0], q[1]
        ratio = np.where(a > 0, np.abs(b) / np.maximum(a, 1e-300), np.inf)
        i = np.unravel_index(int(np.argmax(ratio)), a.shape)
        lim = self.m.psi_hyperbolic
        raise HyperbolicityLostError(tau, float(self.theta_q[i]), lim, lim)

    def psi(self, u: np.ndarray) -> np.ndarray:
        """Sokolovskii angle at the Gauss points, (N, 5) [rad]."""
        q = u @ self.phi
        h, _ = self._h(q[0], q[1])
        return sokolovskii(q[0], q[1], h)[1]

    # --------------------------------------------------------------- marching
    def solve(
        self,
        u0: np.ndarray,
        tau_end: float,
        tau0: float = 0.0,
        reference: Any = None,
        records: int = 200,
        engine: str = "compiled",
    ) -> DGResult:
        """March from tau0 to tau_end with TVD RK3 and the limiter after each stage.

        Parameters
        ----------
        u0
            Initial coefficients (2, N, k+1), e.g. from :meth:`project`.
        tau_end, tau0
            The march, in tau = -ln r.
        reference
            ``(T_rr(theta), T_rt(theta))`` per unit r: a radial field whose
            ``e^-tau`` scaling is the exact solution; gives the error history.
        records
            Number of equal tau intervals at which the solution is kept.
        engine
            ``compiled`` (numba, :mod:`foamsilo.hopper._kernel`) or ``numpy``
            (this class's operators; slow, the reference implementation).

        A loss of hyperbolicity (|psi| >= pi/4 - delta/2 anywhere) ends the
        march with ``status = "hyperbolicity_lost"`` and where it happened.
        """
        if engine not in ("compiled", "numpy"):
            raise HopperError(f"engine {engine!r}: allowed 'compiled', 'numpy'")
        if not tau_end > tau0:
            raise HopperError(f"tau_end = {tau_end:g} must be > tau0 = {tau0:g}")
        # C-contiguous float arrays: one compiled specialisation only
        ref = (np.zeros((0, 5)), np.zeros((0, 5)))
        if reference is not None:
            ref = (
                np.ascontiguousarray(reference[0](self.theta_q), float),
                np.ascontiguousarray(reference[1](self.theta_q), float),
            )
        job = _Job(np.array(u0, float), tau0, tau_end, np.linspace(tau0, tau_end, records + 1),
                   ref)  # fmt: skip
        t0 = time.perf_counter()
        march = self._march_compiled if engine == "compiled" else self._march_numpy
        u, taus, rr, rt, errs, steps, stop = march(job)
        status = "ok" if stop is None else "hyperbolicity_lost"
        return DGResult(
            taus,
            self.theta_q.ravel(),
            rr,
            rt,
            errs if reference is not None else None,
            steps,
            time.perf_counter() - t0,
            status,
            stop,
            u,
        )

    def _march_compiled(self, job: _Job) -> tuple[Any, ...]:
        from foamsilo.hopper import _kernel

        nrec = len(job.marks)
        out_tau = np.zeros(nrec)
        out_rr = np.zeros((nrec, 5 * self.n))
        out_rt = np.zeros((nrec, 5 * self.n))
        out_err = np.zeros(nrec)
        par = (float(self.dim), self.s, self.alpha, self.beta, self.gamma, self.m.chi_w,
               self.m.rho_g)  # fmt: skip
        geo = (self.cos_q, self.sin_q, self.cot_q, self.phi, self.w_dphi, self.w_phi)
        vec = (self.sign, self.inv_mass)
        st, steps, n_done, tau, cell, quad = _kernel.march(
            job.u, job.tau0, job.tau_end, self.k, self.dtheta, self.cfl, self.m.psi_hyperbolic,
            self.tvb_m * self.dtheta**2, par, geo, vec, job.marks, *job.ref, out_tau,
            out_rr, out_rt, out_err,
        )  # fmt: skip
        stop = None
        if st != 0:
            theta = float(self.theta_q[max(cell, 0), quad])
            exc = HyperbolicityLostError(
                float(tau), theta, self.m.psi_hyperbolic, self.m.psi_hyperbolic
            )
            stop = _stop(exc)
        k = n_done
        return (job.u, out_tau[:k], out_rr[:k], out_rt[:k], out_err[:k], int(steps), stop)

    def _march_numpy(self, job: _Job) -> tuple[Any, ...]:
        u = self.limit(job.u)
        tau0, tau_end, marks = job.tau0, job.tau_end, job.marks
        ref = job.ref if job.ref[0].size else None
        tau = tau0
        taus: list[float] = []
        rr: list[np.ndarray] = []
        rt: list[np.ndarray] = []
        errs: list[float] = []
        nxt, steps, stop = 0, 0, None
        limit_psi = self.m.psi_hyperbolic
        try:
            self.rhs(u, tau)  # sets lambda_max
            while True:
                while nxt < len(marks) and marks[nxt] <= tau + 1e-12:
                    q = self.values(u)
                    taus.append(tau)
                    rr.append(q[0].ravel())
                    rt.append(q[1].ravel())
                    if ref is not None:
                        e = math.exp(-tau)
                        diff = max(np.abs(q[0] - e * ref[0]).max(), np.abs(q[1] - e * ref[1]).max())
                        errs.append(diff / (e * np.abs(ref[0]).max()))
                    nxt += 1
                if tau >= tau_end - 1e-12:
                    break
                dt = self.cfl * self.dtheta / ((2 * self.k + 1) * max(self.lambda_max, 1e-12))
                dt = min(dt, tau_end - tau)
                u1 = self.limit(u + dt * self.rhs(u, tau))
                u2 = self.limit(0.75 * u + 0.25 * (u1 + dt * self.rhs(u1, tau + dt)))
                u = self.limit(u / 3 + 2 / 3 * (u2 + dt * self.rhs(u2, tau + 0.5 * dt)))
                tau += dt
                steps += 1
                psi = np.abs(self.psi(u))
                if psi.max() >= limit_psi:
                    i = np.unravel_index(int(np.argmax(psi)), psi.shape)
                    raise HyperbolicityLostError(
                        tau, float(self.theta_q[i]), float(psi[i]), limit_psi
                    )
                self.rhs(u, tau)  # lambda_max of the new state, as the compiled march
        except HyperbolicityLostError as exc:
            stop = _stop(exc)
        return (u, np.array(taus), np.array(rr), np.array(rt), np.array(errs), steps, stop)


def _stop(exc: HyperbolicityLostError) -> dict[str, Any]:
    return {
        "tau": exc.tau,
        "theta": exc.theta,
        "theta_deg": math.degrees(exc.theta),
        "psi": exc.psi,
        "limit": exc.limit,
        "message": str(exc),
    }


def _minmod(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    s = np.sign(a)
    same = (s == np.sign(b)) & (s == np.sign(c))
    return np.where(same, s * np.minimum(np.abs(a), np.minimum(np.abs(b), np.abs(c))), 0.0)


def _tvb_minmod(a: np.ndarray, b: np.ndarray, c: np.ndarray, bound: np.ndarray) -> np.ndarray:
    return np.where(np.abs(a) <= bound, a, _minmod(a, b, c))
