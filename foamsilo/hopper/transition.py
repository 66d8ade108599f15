"""Hoppers with an abrupt change of wall angle (Gremaud & Matthews sec. 6, Fig. 8).

An upper hopper of half angle Theta_w meets a lower one of half angle
theta_w at the wall point Q = (R0, Theta_w) = (r0, theta_w). The upper
hopper carries its radial field; on the arc Gamma_0 = {r = r0} of the lower
hopper's coordinates that field is interpolated, rotated into the lower
frame (S = Q S_U Q^T with the angle Theta - theta between the two radial
directions), and the DG solver marches down the lower hopper from there.

Lengths are in units of r0 (r0 = 1, tau0 = 0); the apexes lie on the axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from foamsilo.hopper.dg import DGResult, HopperDG, HyperbolicityLostError, _stop
from foamsilo.hopper.radial import Dim, HopperError, Material, RadialField, radial_field


@dataclass
class Junction:
    """Geometry of the wall-angle change, r0 = 1.

    Attributes
    ----------
    upper, lower
        Half angles Theta_w and theta_w [rad].
    r_upper
        R0, the distance of Q from the upper apex.
    apex_shift
        Height of the upper apex above the lower one (negative: below).
    """

    upper: float
    lower: float

    @property
    def r_upper(self) -> float:
        """R0 = sin theta_w / sin Theta_w."""
        return math.sin(self.lower) / math.sin(self.upper)

    @property
    def apex_shift(self) -> float:
        """Height of the upper apex above the lower one."""
        return math.cos(self.lower) - self.r_upper * math.cos(self.upper)

    def upper_coordinates(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R, Theta) of the points (r = 1, theta) of Gamma_0."""
        x, z = np.sin(theta), np.cos(theta) - self.apex_shift
        return np.hypot(x, z), np.arctan2(x, z)


def initial_state(field: RadialField, junction: Junction, theta: np.ndarray) -> np.ndarray:
    """(T_rr, T_rt) on Gamma_0 in the lower hopper's frame, shape (2, ...) [Pa].

    Points of Gamma_0 outside the upper hopper (|Theta| > Theta_w, which
    happens only next to Q for a steeper lower hopper) take the upper wall's
    values.
    """
    big_r, big_t = junction.upper_coordinates(np.asarray(theta, float))
    big_t = np.clip(big_t, -junction.upper, junction.upper)
    st = field.stresses(big_t)
    t_rr, t_rt, t_tt = big_r * st["Trr"], big_r * st["Trt"], big_r * st["Ttt"]
    d = big_t - theta  # angle from e_r (lower) to e_R (upper)
    c, s = np.cos(d), np.sin(d)
    # S_lower = Q S_U Q^T, Q = [[c, -s], [s, c]]
    rr = c * c * t_rr - 2 * c * s * t_rt + s * s * t_tt
    rt = c * s * t_rr + (c * c - s * s) * t_rt - c * s * t_tt
    return np.stack([rr, rt])


def solve_transition(
    dim: Dim,
    upper_deg: float,
    lower_deg: float,
    material: Material,
    depth: float = 0.95,
    records: int = 200,
    **scheme: Any,
) -> tuple[DGResult, HopperDG]:
    """March down the lower hopper of a wall-angle transition to ``depth`` (r = 1 - depth).

    With ``upper_deg == lower_deg`` this is the radial field's preservation
    test (Fig. 10) and the result carries the error history. ``scheme`` goes
    to :class:`HopperDG` (``k``, ``cells``, ``tvb_m``, ``cfl``; default P1,
    N = 400).

    Raises
    ------
    HopperError
        No radial field in the upper hopper, or depth outside (0, 1).
    """
    if not 0.0 < depth < 1.0:
        raise HopperError(f"depth = {depth:g}: allowed 0 < depth < 1 (fraction of r0)")
    field = radial_field(dim, upper_deg, material)
    junction = Junction(math.radians(upper_deg), math.radians(lower_deg))
    if not 0.0 < lower_deg < 90.0:
        raise HopperError(f"theta_w = {lower_deg:g} deg: allowed 0 < theta_w < 90")
    dg = HopperDG(dim, junction.lower, material, **{"k": 1, "cells": 400, **scheme})
    tau_end = -math.log(1.0 - depth)
    same = math.isclose(upper_deg, lower_deg)
    reference: Any = None
    if same:
        reference = (lambda th: field.stresses(th)["Trr"], lambda th: field.stresses(th)["Trt"])
        u0 = dg.project(*reference)
    else:
        u0 = dg.project(
            lambda th: initial_state(field, junction, th)[0],
            lambda th: initial_state(field, junction, th)[1],
        )
    psi0 = np.abs(dg.psi(u0)) if _defined(dg, u0) else None
    if psi0 is None or psi0.max() >= material.psi_hyperbolic:
        i = np.unravel_index(int(np.argmax(psi0)), psi0.shape) if psi0 is not None else (0, 0)
        exc = HyperbolicityLostError(
            0.0, float(dg.theta_q[i]), material.psi_hyperbolic, material.psi_hyperbolic
        )
        empty = np.zeros((0, 5 * dg.n))
        return DGResult(
            np.zeros(0),
            dg.theta_q.ravel(),
            empty,
            empty,
            None,
            0,
            0.0,
            "hyperbolicity_lost",
            _stop(exc),
        ), dg
    return dg.solve(u0, tau_end, reference=reference, records=records), dg


def _defined(dg: HopperDG, u: np.ndarray) -> bool:
    q = dg.values(u)
    return bool(np.all(q[0] > 0) and np.all(dg.beta * q[0] ** 2 + dg.gamma * q[1] ** 2 > 0))
