"""The spring-shaped law ([bspline] minimise = "spring_force"): the rise and the return fitted together with the
spring of a translating follower, for the least spring force at full stroke, in one convex problem.

The follower's contact force at cam speed omega (:mod:`synthesis.kinds.clamp_cam.kinematics.follower_dynamics`) is
F = N(phi, omega) / cos(alpha) with the numerator

    N = F0 + k s - Q_gravity + m s'' omega^2        (N; s mm, s'' = d2s/dphi2 mm/rad^2, m kg, 1e-3 m/mm)

linear in the spline's coefficients (s, s'' are) and in the preload F0 for a given stiffness k.  The problem, on
the fit's samples of the rise and the return (the samples of the existing fit, its knots and the NLP's samples,
so the NLP finds the law's rows held where it reads them) and the two dwells:

    minimise    F0 + k h   (+ a secondary term, below)
    subject to  the existing fit's end conditions (C2 joins), 0 <= S <= 1, S' >= 0
                N(phi, omega_jump) >= 0                       jump rows: contact kept up to min_jump_speed
                N(phi, omega) >= min_contact_force            at the operating speed; conservative: F = N / cos
                                                              alpha >= N where N >= 0, so this asks more than
                                                              F >= the limit (below)
                |s' - e| <= tan(limit) (s + s0)               the pressure angle, s0 = sqrt(r0^2 - e^2)
                |s''| omega^2 <= max_acceleration             (when the spec has one; at every u: on the control
                                                              points of S'', whose hull holds the curve)
                F0 within the preload's bounds

For the translating follower tan(alpha) = (s' - e) / (s + s0) with r0 the pitch base radius (the kind's
base_radius, the roller centre's distance at rest: cam_follower.Translating.rest_distance), so for the given cam
|tan alpha| <= t is the pair of linear rows above.  Every limit is held with the margin the NLP holds it with
(the spec's backoff x the rule's scale): the law fixes the pressure angle, which the NLP cannot change on a given
cam, and the re-check on the 10x finer grid reads the rows between the samples too.  Between the fit's samples
(8 per span) the pressure angle rose by at most 0.006 deg over the laws fitted for the library's 1.5x cam, the
same with four acceleration caps and on a 58 mm cam where the return's limit binds: well inside the 0.05-0.1 deg
margin of a backoff of 0.01-0.02.

The exact contact row, N >= min_contact_force x cos(alpha) with cos(alpha) = (s + s0) / |(s + s0, s' - e)|, has
no convex form: at a sample with s and N given it asks |s' - e| >= a bound, two intervals of s'.  The NLP holds the
exact row, so the fitted law is never refused for it; the cost is optimality.  On the library's 1.5x cam the
contact rows bind on the return beside the jump rows (at up to 40 deg of pressure angle, where they ask 1 / cos
alpha = 1.3 x too much): a refit with the first law's cos(alpha) frozen at each sample (not a bound: the new law's
angles differ) reached 4.040 N at full stroke against this fit's 4.095 N, where the near dwell's 2 N then binds.

The stiffness is a number: the spec's, or the lower bound of a free stiffness.  With both F0 and k free the rows
hold the product k s of two unknowns; holding k at its lower bound loses nothing for these rows: from any
feasible (F0, k), (F0 + (k - k_lo) h, k_lo) is feasible (its spring force F0 + k s + (k - k_lo)(h - s) is no
smaller at any s <= h) with the same force at full stroke -- provided the preload may rise by (k - k_lo) h: a
preload given as a number with a free stiffness is refused by the spec, and when the preload's upper bound is what
makes the fit infeasible its message says to widen it or to give the stiffness as a number.  (The force is larger
below full stroke, which only an upper limit on the force, the Hertz stress, could mind; the NLP keeps both spring
variables and re-checks it.)

The secondary term, SECONDARY x the existing fit's objective (each segment's peak |S''| relative to the
cycloidal law's, plus its tiny tie-break): the rows only bind where the spring decelerates the follower, so many
laws share the least spring force; this picks the gentlest of them (the rise, which no row binds, is the
acceleration-optimal one) and makes the fit reproducible.
cvxpy is imported here only, as in bspline_law.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from synthesis.errors import SolverError
from synthesis.kinds.clamp_cam.bspline_law import (TIE_BREAK, OptimisedLaw, SplineLaw, _basis, _knots,
                                                   joined_to_the_dwells)
from synthesis.kinds.clamp_cam.kinematics.motion_laws import cycloidal

#: weight of the existing fit's objective next to the spring force (relative to SpringShaping.force_scale)
SECONDARY = 1e-4
#: N per (kg mm/s^2)
MM = 1e-3


@dataclass(frozen=True)
class SpringShaping:
    """What the spring-shaped fit reads of a spec, as numbers (hashable: one fit per set of them).

    Speeds rad/s, forces N, lengths mm, angles deg; each limit already tightened by the NLP's margin."""

    mass: float
    gravity_load: float                      # m (g . d), N: constant along a translating follower
    stiffness: float                         # N/mm
    preload_bounds: tuple[float, float]      # N
    jump_speed: float | None                 # rows N(omega) >= 0 at this speed
    operating_speed: float
    min_contact_force: float | None          # rows N(operating_speed) >= this
    base_radius: float                       # pitch base circle
    offset: float
    pressure_angle_deg: tuple[float, float]  # (rise, return) limits
    nlp_samples: int                         # the NLP's samples per motion segment, rows there too

    @property
    def rest_distance(self) -> float:
        """s0 = sqrt(r0^2 - e^2), mm."""
        return math.sqrt(self.base_radius**2 - self.offset**2)

    def force_scale(self, stroke: float, shortest_deg: float) -> float:
        """A spring force of the problem's size, N: the cycloidal law's peak inertia over the shorter motion
        segment at the jump speed (or the operating speed), plus k h."""
        speed = self.jump_speed if self.jump_speed is not None else self.operating_speed
        inertia = self.mass * MM * stroke * cycloidal().peaks["acceleration"] / math.radians(shortest_deg) ** 2
        return inertia * speed**2 + self.stiffness * stroke


def _grid(spans: int, degree: int, samples_per_span: int, nlp_samples: int) -> np.ndarray:
    knots = _knots(spans, degree)
    return np.unique(np.concatenate([np.linspace(0.0, 1.0, spans * samples_per_span + 1), knots,
                                     np.linspace(0.0, 1.0, nlp_samples)]))


def _derivative_control_points(knots: np.ndarray, degree: int, order: int) -> np.ndarray:
    """(n - order, n): the control points of the order-th derivative of a spline (itself a B-spline of degree
    ``degree - order``) as a linear map of its n coefficients: d_i = p (c_(i+1) - c_i) / (t_(i+p+1) - t_(i+1)),
    applied ``order`` times."""
    m, t, p = np.eye(len(knots) - degree - 1), knots, degree
    for _ in range(order):
        rows = len(m) - 1
        m = (m[1:] - m[:-1]) * p / (t[p + 1:p + 1 + rows] - t[1:1 + rows])[:, None]
        t, p = t[1:-1], p - 1
    return m


def fit_spring_shaped_law(stroke: float, segments_deg: dict[str, float], shaping: SpringShaping, spans: int = 32,
                          degree: int = 5, samples_per_span: int = 8,
                          max_acceleration: float | None = None) -> OptimisedLaw:
    """Fit the rise and the return for the least spring force at full stroke (module docstring).

    stroke: h, mm; segments_deg: {"rise": deg, "return": deg}; max_acceleration: mm/s^2 at the operating speed
    (already tightened), or None.  The result's ``spring`` holds the fitted preload (the NLP's start), the
    stiffness and the force at full stroke.  Raises SolverError when no law of this spline and no preload within
    its bounds meets the rows."""
    knots = _knots(spans, degree)
    n = len(knots) - degree - 1
    u = _grid(spans, degree, samples_per_span, shaping.nlp_samples)
    B0, B1, B2, B3 = (_basis(knots, degree, u, k) for k in range(4))
    acceleration_points = _derivative_control_points(knots, degree, 2)
    reference = cycloidal().peaks["acceleration"]
    h, k, s0, e = stroke, shaping.stiffness, shaping.rest_distance, shaping.offset
    lo, hi = shaping.preload_bounds
    preload = cp.Variable(name="preload")
    constraints = [preload >= lo, preload <= hi]
    # the dwells: s = 0 (rest) and s = h (full stroke), s'' = 0
    held = [preload - shaping.gravity_load, preload + k * h - shaping.gravity_load]
    for numerator in held:
        if shaping.jump_speed is not None:
            constraints.append(numerator >= 0.0)
        if shaping.min_contact_force is not None:
            constraints.append(numerator >= shaping.min_contact_force)
    secondary, coefficient_vars = [], {}
    for name, sign, limit_deg in (("rise", 1.0, shaping.pressure_angle_deg[0]),
                                  ("return", -1.0, shaping.pressure_angle_deg[1])):
        beta = math.radians(segments_deg[name])
        c = cp.Variable(n - 6, name=f"c_{name}")
        full = joined_to_the_dwells(c)
        S, dS, ddS = B0 @ full, B1 @ full, B2 @ full
        s = h * S if sign > 0 else h * (1.0 - S)
        ds, dds = sign * h * dS / beta, sign * h * ddS / beta**2
        peak = cp.Variable(name=f"peak_{name}", nonneg=True)
        constraints += [S >= 0.0, S <= 1.0, dS >= 0.0, cp.abs(ddS) <= peak]
        spring = preload + k * s - shaping.gravity_load
        if shaping.jump_speed is not None:
            constraints.append(spring + shaping.mass * MM * shaping.jump_speed**2 * dds >= 0.0)
        if shaping.min_contact_force is not None:
            constraints.append(spring + shaping.mass * MM * shaping.operating_speed**2 * dds
                               >= shaping.min_contact_force)
        slope = math.tan(math.radians(limit_deg))
        constraints += [ds - e <= slope * (s + s0), e - ds <= slope * (s + s0)]
        if max_acceleration is not None:
            # on the control points of S'': a B-spline lies within their hull, so the cap holds at every u, not only
            # at the samples (between which this law's steep acceleration overshoots by 0.2 % at 8 per span)
            limit = max_acceleration * beta**2 / (h * shaping.operating_speed**2)
            constraints.append(cp.abs(acceleration_points @ full) <= limit)
        smooth = cp.sum_squares(B3 @ full) / (len(u) * (reference * 2.0 * math.pi) ** 2)
        secondary.append(peak / reference + TIE_BREAK * smooth)
        coefficient_vars[name] = c
    scale = shaping.force_scale(h, min(segments_deg.values()))
    objective = (preload + k * h) / scale + SECONDARY * cp.sum(cp.hstack(secondary))
    problem = cp.Problem(cp.Minimize(objective), constraints)
    problem.solve(solver=cp.CLARABEL)
    if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        if problem.status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
            raise SolverError(
                "bspline.minimise = 'spring_force': no law of this spline meets the spring's rows on the given cam "
                f"with the preload within [{lo:g}, {hi:g}] N (the pressure angle limits, the jump speed, the "
                f"contact force{', the acceleration limit' if max_acceleration is not None else ''}); widen the "
                f"preload's bounds (the fit holds the stiffness at {k:g} N/mm, its lower bound: a stiffer spring needs "
                f"room above the preload), give the stiffness as a number, lengthen the return or the rise, or "
                f"enlarge the cam (cvxpy/CLARABEL said: "
                f"{problem.status})")
        raise SolverError(f"the spring-shaped law's convex problem failed: cvxpy/CLARABEL said {problem.status}")

    laws = {}
    for name, c in coefficient_vars.items():
        coef = joined_to_the_dwells(np.asarray(c.value, dtype=float))
        laws[name] = SplineLaw("optimised_spring_force", tuple(knots.tolist()), tuple(coef.tolist()), degree)
    ratio = {name: laws[name].peaks["acceleration"] / reference for name in laws}
    f0 = float(np.asarray(preload.value, dtype=float))
    spring = {"preload": f0, "stiffness": k, "force_at_full_stroke": f0 + k * h, "unit": "N",
              "ratio_to_cycloidal_of": "acceleration"}
    return OptimisedLaw(laws["rise"], laws["return"], "spring_force", str(problem.status), "CLARABEL", ratio, spring)
