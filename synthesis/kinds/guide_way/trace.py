"""Claw tip -> arm angle -> roller centre, with exact derivatives: one CasADi function for floats and symbols.

``arm_function(branch)`` maps a claw-tip sample (M, dM/du, d2M/du2) and the arm (R, d, r, beta)
to theta, alpha, the pivot P, the roller centre N and dN/du, d2N/du2, dtheta/du (CasADi AD of the
inverse kinematics of :mod:`synthesis.kinds.guide_way.kinematics`, chain rule through M(u)).  The same
function serves the check (numbers), the NLP (the spline's control points as symbols) and the
re-check.  From it:

    curvature of the centre line   kappa = (N' x N'') / |N'|^3          (> 0: turning left)
    pressure angle                 mu = acos(|N' . e_PN| / |N'|)
        between the guide's normal at N (the force on the roller) and the roller's velocity relative
        to the arm, which is perpendicular to PN: 0 when the guide runs along PN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from synthesis.kinds.guide_way import kinematics as ra

OUTPUTS = ("theta", "alpha", "px", "py", "nx", "ny", "n1x", "n1y", "n2x", "n2y", "theta1", "cos_phi", "rho")


@lru_cache(maxsize=None)
def arm_function(branch: float) -> ca.Function:
    """(m[2], m1[2], m2[2], arm[4] = (R, d, r, beta rad)) -> OUTPUTS (one sample)."""
    m, m1, m2, g = ca.SX.sym("m", 2), ca.SX.sym("m1", 2), ca.SX.sym("m2", 2), ca.SX.sym("arm", 4)
    R, d, r, beta = g[0], g[1], g[2], g[3]
    theta, alpha = ra.inverse(R, d, m[0], m[1], branch)
    n = ca.vertcat(*ra.roller_centre(R, r, beta, theta, alpha))
    jac = ca.jacobian(n, m)
    n1 = ca.mtimes(jac, m1)
    n2 = ca.mtimes(ca.jacobian(n1, m), m1) + ca.mtimes(jac, m2)
    theta1 = ca.dot(ca.jacobian(theta, m).T, m1)
    px, py = ra.pivot(R, theta)
    cos_phi = ra.fold_cosine(R, d, m[0], m[1])
    out = [theta, alpha, px, py, n[0], n[1], n1[0], n1[1], n2[0], n2[1], theta1, cos_phi, ca.norm_2(m)]
    return ca.Function(f"arm_{'plus' if branch > 0 else 'minus'}", [m, m1, m2, g], out, ["m", "m1", "m2", "arm"],
                       list(OUTPUTS))


def arm_vector(R: float, d: float, r: float, beta_deg: float) -> list[float]:
    return [R, d, r, math.radians(beta_deg)]


@dataclass
class Stretch:
    """Samples of the claw path on one stretch, in time order: M, M', M'' (n x 2 arrays or 2 x n SX)."""

    name: str
    branch: float
    u: np.ndarray                 # the curve parameter of each sample
    m: Any
    m1: Any
    m2: Any


@dataclass
class Arm:
    """Everything of one stretch the rules and the report read (floats: numpy arrays, symbols: SX rows)."""

    name: str
    theta: Any
    alpha: Any
    p: tuple
    n: tuple
    n1: tuple
    n2: tuple
    theta1: Any
    cos_phi: Any
    rho: Any
    m: tuple
    m1: tuple
    crank: float

    @property
    def speed(self):
        return (self.n1[0] ** 2 + self.n1[1] ** 2) ** 0.5

    @property
    def kappa(self):
        """Signed curvature of the roller-centre line, 1/mm."""
        cross = self.n1[0] * self.n2[1] - self.n1[1] * self.n2[0]
        return cross / self.speed ** 3

    @property
    def along_crank(self):
        """N' . e_PN / |N'| = cos(pressure angle) up to its sign."""
        ex, ey = (self.n[0] - self.p[0]) / self.crank, (self.n[1] - self.p[1]) / self.crank
        return (self.n1[0] * ex + self.n1[1] * ey) / self.speed

    @property
    def pressure_angle_deg(self):
        return np.degrees(np.arccos(np.clip(np.abs(np.asarray(self.along_crank, float)), 0.0, 1.0)))

    @property
    def turning(self):
        """dtheta/ds along the claw path (rad per mm): > 0 when the arm turns forward in time order."""
        return self.theta1 / (self.m1[0] ** 2 + self.m1[1] ** 2) ** 0.5


def evaluate(stretch: Stretch, arm: list[float]) -> Arm:
    """The arm over a stretch: numbers for a numeric stretch, SX expressions for a symbolic one."""
    fun = arm_function(stretch.branch)
    symbolic = isinstance(stretch.m, (ca.SX, ca.MX))
    n = stretch.u.size
    mapped = fun.map(n)
    if symbolic:
        out = mapped(stretch.m, stretch.m1, stretch.m2, ca.DM(arm))
        o = {k: out[i].T for i, k in enumerate(OUTPUTS)}
        m = (stretch.m[0, :].T, stretch.m[1, :].T)
        m1 = (stretch.m1[0, :].T, stretch.m1[1, :].T)
    else:
        mm, mm1, mm2 = (np.asarray(v, float).T for v in (stretch.m, stretch.m1, stretch.m2))
        out = mapped(mm, mm1, mm2, arm)
        o = {k: np.asarray(out[i]).ravel() for i, k in enumerate(OUTPUTS)}
        m, m1 = (mm[0], mm[1]), (mm1[0], mm1[1])
    return Arm(stretch.name, o["theta"], o["alpha"], (o["px"], o["py"]), (o["nx"], o["ny"]), (o["n1x"], o["n1y"]),
               (o["n2x"], o["n2y"]), o["theta1"], o["cos_phi"], o["rho"], m, m1, arm[2])
