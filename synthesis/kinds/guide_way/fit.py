"""The convex stage of the redesign: the smoothest periodic claw path through the key points and tangents.

One quadratic program (cvxpy, Clarabel) in the control points P of the periodic cubic B-spline
(:mod:`synthesis.kinds.guide_way.spline`) and one speed lambda_k per key tangent:

    minimise    sum_j |M'''_j|^2 / n                          (curvature variation of the claw path)
    subject to  M(u_k)  = K_k                                  every key point (the fold moved onto R - d)
                M'(u_k) = lambda_k t_k,  lambda_k >= v_min     every key tangent (t_k a unit direction)
                D . M''(u_D) >= -v_min^2 / 2                   |OM| has a minimum at the fold: the path stays
                                                               outside the circle R - d near D, since
                                                               (|M|^2)'' = 2 (|M'|^2 + M . M'') > 0 there
The equalities are then met exactly (to 1e-12 mm) by a least-norm correction of the solver's answer.
The rules that depend on the arm (undercut, pressure angle, reach, arm direction) are not convex in P:
the IPOPT stage (:mod:`synthesis.kinds.guide_way.nlp`) holds the path to them, starting here.
cvxpy is imported here only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from synthesis.errors import SolverError, SpecError
from synthesis.kinds.guide_way import spline as sp
from synthesis.kinds.guide_way.scene import spline_path


@dataclass(frozen=True)
class Fit:
    control: np.ndarray            # (n, 2) control points, mm
    energy: float                  # sum_j |M'''_j|^2 / n at the fit
    speeds: dict                   # key -> lambda_k, mm per unit u
    status: str


def _solved(variable: cp.Variable) -> np.ndarray:
    """A variable's value after a solve that ended optimal (cvxpy then sets every variable of the problem)."""
    value = variable.value
    assert value is not None, "an optimal solve sets every variable's value"
    return value


def fit_path(spec) -> Fit:
    s = spec.spline
    n = s.control_points
    keys = spline_path(spec, None).keys
    _reachable(spec, keys)
    # the convex problem in units of the path length L (control points / L, speeds / L): in mm its numbers spanned
    # 1e-3 (the energy / L^2) to 1e5 (v_min^2), and CLARABEL stopped short of the optimum ("InsufficientProgress")
    # on smooth_redesign without the tangent at E, an optional field
    scale = keys.length
    v_min = s.min_speed
    qx, qy = cp.Variable(n), cp.Variable(n)
    d3 = sp.third_differences(n)
    cons = []
    lam = {}
    for name, u, (kx, ky) in zip(keys.names, keys.u, keys.points):
        b0 = sp.basis(n, u)[0]
        cons += [b0 @ qx == kx / scale, b0 @ qy == ky / scale]
        if name in keys.tangents:
            tx, ty = keys.tangents[name]
            b1 = sp.basis(n, u, 1)[0]
            lam[name] = cp.Variable()
            cons += [b1 @ qx == lam[name] * tx, b1 @ qy == lam[name] * ty, lam[name] >= v_min]
    fold_u = keys.u[keys.index(keys.fold)]
    fx, fy = keys.points[keys.index(keys.fold)]
    b2 = sp.basis(n, fold_u, 2)[0]
    cons.append((fx / scale) * (b2 @ qx) + (fy / scale) * (b2 @ qy) >= -0.5 * v_min**2)
    # the energy n^5 sum |third differences|^2, divided by n^5 L^2 for the solver (same minimiser)
    problem = cp.Problem(cp.Minimize(cp.sum_squares(d3 @ qx) + cp.sum_squares(d3 @ qy)), cons)
    try:
        problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError as exc:
        raise SolverError(f"spline fit: the convex solver failed ({exc}); check [spline] keys and tangents, or "
                          f"change control_points") from None
    if problem.status not in ("optimal", "optimal_inaccurate") or qx.value is None:
        raise SolverError(f"spline fit: the key points and tangents admit no spline ({problem.status}); "
                          f"check [spline] keys and tangents, or raise control_points")
    speeds = {k: float(_solved(v)) * scale for k, v in lam.items()}
    control = _exact(keys, n, np.column_stack([_solved(qx), _solved(qy)]) * scale, speeds)
    h = sp.energy_matrix(n)
    energy = float(control[:, 0] @ h @ control[:, 0] + control[:, 1] @ h @ control[:, 1])
    return Fit(control, energy, speeds, problem.status)


def _reachable(spec, keys: sp.Keys) -> None:
    """SpecError naming the first key point the claw tip cannot reach (|OM| outside [R - d, R + d]): the fit would
    otherwise be asked for a spline through it and fail as an infeasible convex problem that names no point."""
    arm = spec.arm
    lo, hi = arm.radius - arm.claw, arm.radius + arm.claw
    slack = 1e-9 * hi         # keys_of moves the fold point onto |OM| = R - d exactly: its hypot may be an ulp below
    for name, (x, y) in zip(keys.names, keys.points):
        r = math.hypot(float(x), float(y))
        if not lo - slack <= r <= hi + slack:
            wx, wy = spec.points[name]       # as the user wrote it (the fold point may have been moved)
            raise SpecError(f"points.{name} = [{float(wx):g}, {float(wy):g}]: the claw tip cannot reach it: |OM| = "
                            f"{r:.4g} mm lies outside [R - d, R + d] = [{lo:.4g}, {hi:.4g}] mm (arm.radius, arm.claw)")


def _exact(keys: sp.Keys, n: int, control: np.ndarray, speeds: dict) -> np.ndarray:
    """The least change of the control points meeting every key point and tangent exactly (given the speeds)."""
    rows, rhs = [], []
    z = np.zeros(n)
    for name, u, (kx, ky) in zip(keys.names, keys.u, keys.points):
        b0 = sp.basis(n, u)[0]
        rows += [np.concatenate([b0, z]), np.concatenate([z, b0])]
        rhs += [kx, ky]
        if name in speeds:
            b1 = sp.basis(n, u, 1)[0]
            tx, ty = keys.tangents[name]
            rows += [np.concatenate([b1, z]), np.concatenate([z, b1])]
            rhs += [speeds[name] * tx, speeds[name] * ty]
    a, b = np.array(rows), np.array(rhs)
    x = np.concatenate([control[:, 0], control[:, 1]])
    x = x - np.linalg.lstsq(a, a @ x - b, rcond=None)[0]
    return np.column_stack([x[:n], x[n:]])
