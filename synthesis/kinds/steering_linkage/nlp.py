"""The steering-trapezoid problem: minimise the largest steering error over 0 .. the maximum inside lock.

Decision variables: arm length r (mm), base angle gamma (deg) (fixed ones get lo = hi), the outer lock
alpha_k (rad) at every sampled inside lock beta_k, and the epigraph variable t (deg, the objective's
extra variable).  Structural rows close the loop at every sample (|T_R(alpha_k) - T_L(beta_k)| = l,
exact AD, no acos: defined at every iterate); the signed transmission angles keep the straight-ahead
assembly (the other one has a negative angle) and away from the dead centre.  The objective is the
smooth epigraph of the minimax error:

    min t   s.t.   -t <= alpha_k - alpha_Ackermann(beta_k) <= t   (deg) at every sample
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.core.declared import Declared
from synthesis.core.kind import Setting
from synthesis.core.problem import ObjectiveParts, Problem, per_rule_backoff
from synthesis.kinds.steering_linkage.kinematics import ackermann_outer, loop_residual, outer_lock, transmission_angles
from synthesis.spec.common import design_box
from synthesis.kinds.steering_linkage.spec import SteeringSpec
from synthesis.kinds.steering_linkage.check import lock_grid, rules_of

DEG = math.pi / 180.0
NAMES = ("arm_length", "base_angle")
#: sampled rules: tightened by the spec's backoff so they hold between the samples too
SAMPLED = ("tie_rod_transmission_angle",)


def problem(setting: Setting) -> Declared:
    """The problem of one spec: a start's outer locks from the closed form, its epigraph variable at the start's own
    largest error."""
    spec = setting.spec
    bounds, init = design_box(spec.variables(), NAMES)
    v, req = spec.vehicle, spec.requirements
    w, w_over_l = v.kingpin_spacing, v.kingpin_spacing / v.wheelbase
    locks = lock_grid(req.max_inside_lock, spec.solver.samples)[1:]        # beta = 0 is straight ahead
    n = locks.size
    z = ca.SX.sym("z", 2 + n)
    r, gamma, alpha = z[0], z[1] * DEG, z[2:]
    beta = ca.DM(locks)
    structural = [(loop_residual(beta, alpha, w, r, gamma), 0.0, 0.0)]
    mu_o, mu_i = transmission_angles(beta, alpha, w, r, gamma)
    rules = rules_of(spec, r, ca.vertcat(mu_o, mu_i) / DEG)
    error = (alpha - ackermann_outer(beta, w_over_l)) / DEG
    t = ca.SX.sym("max_error_deg")
    objective = ObjectiveParts(f=t, extra=t, extra_lb=[0.0], extra_ub=[90.0], extra_init=[1.0],
                               rows=[(t - error, 0.0, None), (t + error, 0.0, None)], extra_units=["deg"],
                               row_units=["deg", "deg"])
    lbx = np.concatenate([bounds[:, 0], np.full(n, -0.5 * math.pi)])
    ubx = np.concatenate([bounds[:, 1], np.full(n, 0.5 * math.pi)])
    backoff = spec.solver.backoff
    declared = Problem("steering_linkage", z, lbx, ubx, structural, rules, objective,
                       backoff=per_rule_backoff(lambda rule: backoff if rule.name in SAMPLED else 1e-7),
                       ipopt="tight", max_iter=spec.solver.max_iter,
                       # z: arm length (mm), base angle (deg), the outer wheel's angles (rad); the loop
                       # residual is relative to the kingpin spacing squared (a plain number)
                       x_units=["mm", "deg"] + ["rad"] * n, structural_units=[""], objective_unit="deg")

    def start(x0: np.ndarray, elastic: bool) -> tuple[np.ndarray, list | None]:
        r, gamma = (float(v) for v in x0)
        alpha0 = alpha_guess(locks, w, w_over_l, r, gamma)
        err0 = np.abs(alpha0 - np.asarray(ackermann_outer(ca.DM(locks), w_over_l), float).ravel()).max()
        # the epigraph variable starts at the start's own largest error (the elastic form's extras are slacks)
        return np.concatenate([[r, gamma], alpha0]), None if elastic else [math.degrees(err0)]

    return Declared(declared, list(NAMES), bounds, init, start=start,
                    design=lambda x: {"arm_length": float(x[0]), "base_angle": float(x[1])})


def alpha_guess(locks: np.ndarray, w: float, w_over_l: float, r: float, gamma_deg: float) -> np.ndarray:
    """The outer locks of a start: the closed form where the trapezoid assembles, Ackermann beyond."""
    closed = np.asarray(outer_lock(ca.DM(locks), w, r, gamma_deg * DEG), float).ravel()
    ack = np.asarray(ackermann_outer(ca.DM(locks), w_over_l), float).ravel()
    return np.where(np.isfinite(closed), closed, ack)
