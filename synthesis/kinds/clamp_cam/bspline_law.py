"""The optimised motion law: B-spline displacements of the rise and the return from one convex problem.

Each motion segment gets a clamped B-spline S(u) on u in [0, 1] with uniform knots; the follower
moves h S(u) on the rise and h (1 - S(u)) on the return.  The problem (cvxpy, an LP plus a tiny
quadratic tie-break):

    minimise    sum over segments of  peak_seg / peak_seg(cycloidal)  +  tie-break
    subject to  S(0) = S'(0) = S''(0) = 0,  S(1) = 1, S'(1) = S''(1) = 0   (C2 joins with the dwells:
                the dwell levels 0 and h are met with zero velocity and acceleration)
                0 <= S <= 1 and S' >= 0 on a dense grid (no overshoot of the dwell levels, no reversal)
                |h S''| omega^2 / beta^2 <= max_acceleration   (optional: the timing window must allow it)

where peak_seg bounds |S''| (minimise = "acceleration") or |S'''| ("jerk") at the grid points.
The end conditions fix the first and last three control points, so continuity to the
acceleration holds exactly, not to a solver tolerance.  The tie-break (1e-7 x the mean squared
next derivative, relative) picks one optimum among equals so the law is reproducible.
cvxpy is imported here only: a spec that does not ask for the optimised law never loads it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import cvxpy as cp
import numpy as np
from scipy.interpolate import BSpline

from synthesis.errors import SolverError
from synthesis.kinds.clamp_cam.kinematics.motion_laws import cycloidal

TIE_BREAK = 1e-7


@dataclass(frozen=True)
class SplineLaw:
    """A normalised law given by a clamped B-spline on [0, 1] (held at its end values outside)."""

    name: str
    knots: tuple[float, ...]
    coefficients: tuple[float, ...]
    degree: int

    @cached_property
    def _splines(self) -> tuple[BSpline, ...]:
        spl = BSpline(np.array(self.knots), np.array(self.coefficients), self.degree, extrapolate=False)
        return (spl, spl.derivative(1), spl.derivative(2), spl.derivative(3))

    def _eval(self, order: int, u):
        u = np.asarray(u, dtype=float)
        value = self._splines[order](np.clip(u, 0.0, 1.0))
        if order > 0:
            value = np.where((u < 0.0) | (u > 1.0), 0.0, value)
        return value if value.ndim else float(value)

    def s(self, u):
        return self._eval(0, u)

    def v(self, u):
        return self._eval(1, u)

    def a(self, u):
        return self._eval(2, u)

    def j(self, u):
        return self._eval(3, u)

    @cached_property
    def peaks(self) -> dict[str, float]:
        u = np.unique(np.concatenate([np.linspace(0.0, 1.0, 20001), np.array(self.knots)]))
        return {"velocity": float(np.max(np.abs(self.v(u)))), "acceleration": float(np.max(np.abs(self.a(u)))),
                "jerk": float(np.max(np.abs(self.j(u))))}

    def to_json(self) -> dict:
        return {"knots": list(self.knots), "coefficients": list(self.coefficients), "degree": self.degree}


@dataclass(frozen=True)
class OptimisedLaw:
    rise: SplineLaw
    return_: SplineLaw
    minimise: str
    status: str
    solver: str
    #: peak of the minimised derivative divided by the cycloidal law's, per segment (the acceleration's for the
    #: spring-shaped law)
    ratio_to_cycloidal: dict[str, float] = field(default_factory=dict)
    #: the spring-shaped law's fitted spring (preload, stiffness, force at full stroke), None for the others
    spring: dict | None = None

    @property
    def warning(self) -> str | None:
        """Why the law is not to be trusted to full accuracy (cvxpy accepted an inaccurate solution), or None."""
        if self.status == cp.OPTIMAL:
            return None
        return (f"the optimised motion law comes from a convex fit that cvxpy/{self.solver} solved only to reduced "
                f"accuracy ({self.status}): its end conditions and bounds hold to that accuracy only")

    def to_json(self) -> dict:
        out = {"minimise": self.minimise, "status": self.status, "solver": self.solver,
               "accurate": self.warning is None, "ratio_to_cycloidal": self.ratio_to_cycloidal,
               "rise": self.rise.to_json(), "return": self.return_.to_json()}
        if self.spring is not None:
            out["fitted_spring"] = dict(self.spring)
        return out


def _knots(spans: int, degree: int) -> np.ndarray:
    inner = np.linspace(0.0, 1.0, spans + 1)
    return np.concatenate([np.zeros(degree), inner, np.ones(degree)])


def _basis(knots: np.ndarray, degree: int, u: np.ndarray, order: int) -> np.ndarray:
    """(len(u), n) matrix of the order-th derivative of every basis function at u."""
    n = len(knots) - degree - 1
    spl = BSpline(knots, np.eye(n), degree)
    return (spl.derivative(order) if order else spl)(u)


_ORDER = {"acceleration": 2, "jerk": 3}


def joined_to_the_dwells(inner):
    """A segment's whole coefficient vector from its inner ones: the first three 0 and the last three 1, so S, S'
    and S'' join the dwells (C2).  ``inner``: a cvxpy variable (an expression back) or its values (numpy)."""
    if isinstance(inner, np.ndarray):
        return np.concatenate([np.zeros(3), inner, np.ones(3)])
    return cp.hstack([np.zeros(3), inner, np.ones(3)])


def fit_optimised_law(stroke: float, segments_deg: dict[str, float], omega: float, minimise: str = "acceleration",
                      spans: int = 32, degree: int = 5, samples_per_span: int = 8,
                      max_acceleration: float | None = None) -> OptimisedLaw:
    """Fit the rise and the return laws in one convex problem.

    stroke: h in mm (or rad); segments_deg: {"rise": deg, "return": deg}; omega: cam speed, rad/s;
    max_acceleration: cap on |follower acceleration| in stroke units per s^2, or None.
    Raises SolverError (exit 3) naming the window when the cap cannot be met.
    """
    knots = _knots(spans, degree)
    n = len(knots) - degree - 1
    u = np.unique(np.concatenate([np.linspace(0.0, 1.0, spans * samples_per_span + 1), knots]))
    order = _ORDER[minimise]
    B0, B1, B2 = (_basis(knots, degree, u, k) for k in range(3))
    Bk = _basis(knots, degree, u, order)
    Bnext = _basis(knots, degree, u, order + 1)
    reference = cycloidal().peaks[minimise]

    problem_parts, coefficient_vars, peaks = [], {}, {}
    constraints = []
    for name in ("rise", "return"):
        c = cp.Variable(n - 6, name=f"c_{name}")
        full = joined_to_the_dwells(c)
        peak = cp.Variable(name=f"peak_{name}", nonneg=True)
        constraints += [B0 @ full >= 0.0, B0 @ full <= 1.0, B1 @ full >= 0.0,
                        cp.abs(Bk @ full) <= peak]
        if max_acceleration is not None:
            beta = math.radians(segments_deg[name])
            limit = max_acceleration * beta**2 / (stroke * omega**2)      # normalised |S''| allowed
            constraints.append(cp.abs(B2 @ full) <= limit)
        # tie-break: a tiny multiple of the mean squared next derivative, relative to its cycloidal size
        smooth = cp.sum_squares(Bnext @ full) / (len(u) * (reference * 2.0 * math.pi) ** 2)
        problem_parts.append(peak / reference + TIE_BREAK * smooth)
        coefficient_vars[name], peaks[name] = c, peak
    problem = cp.Problem(cp.Minimize(cp.sum(cp.hstack(problem_parts))), constraints)
    problem.solve(solver=cp.CLARABEL)
    # OPTIMAL_INACCURATE is accepted but not hidden: OptimisedLaw.warning puts it in the result and the rules
    if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        if max_acceleration is not None and problem.status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
            free_fit = fit_optimised_law(stroke, segments_deg, omega, "acceleration", spans, degree, samples_per_span)
            need = {name: stroke * omega**2 * getattr(free_fit, attr).peaks["acceleration"]
                    / math.radians(segments_deg[name]) ** 2 for name, attr in (("rise", "rise"), ("return", "return_"))}
            worst = max(need, key=need.__getitem__)
            raise SolverError(
                f"rules.max_acceleration: the optimised law cannot meet the timing: the {worst} window of "
                f"{segments_deg[worst]:g} deg needs a peak follower acceleration of at least {need[worst]:.6g} "
                f"(smallest any C2 B-spline of this size reaches) > max_acceleration {max_acceleration:g}; "
                f"lengthen the {worst} or raise the limit (cvxpy/CLARABEL said: {problem.status})")
        raise SolverError(f"the optimised law's convex problem failed: cvxpy/CLARABEL said {problem.status}")

    laws = {}
    for name, c in coefficient_vars.items():
        coef = joined_to_the_dwells(np.asarray(c.value, dtype=float))
        laws[name] = SplineLaw(f"optimised_{minimise}", tuple(knots.tolist()), tuple(coef.tolist()), degree)
    ratio = {name: laws[name].peaks[minimise] / reference for name in laws}
    return OptimisedLaw(laws["rise"], laws["return"], minimise, str(problem.status), "CLARABEL", ratio)
