"""The IPOPT stage of the redesign: the spline's control points held to every rule of the guide way.

Decision variables: the control points P (n x 2): those the spec gives (``[spline] control``, start 0
their init values, within their bounds), else each within ``[spline] move`` mm of the convex fit (start
0 the fit); then one parameter u_e per edge of the fold window (auxiliary, within its stretch).
Structural rows (exact, no back-off): every key point, every key tangent's direction
(M'(u_k) x t_k = 0, M'(u_k) . t_k >= v_min), |OM| having its minimum at the fold
(|M'|^2 + M . M'' >= v_min^2 / 2 there) and each edge's arm angle, theta(M(u_e)) = the fold's
-/+ the window.  Rules: the same sampled rules as the check
(:func:`synthesis.kinds.guide_way.scene.rules_of` on the control points as CasADi symbols; the pressure-angle
samples are those outside the fold window on the path of start 0, and the window's edges u_e).
Objective: the smoothness energy relative to the fit's, so 1 when the fit already meets every rule.
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np

from synthesis.core.declared import compile_problem
from synthesis.core.kind import KindNLP, Setting
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import ObjectiveParts, Problem, Row, per_rule_backoff
from synthesis.errors import SpecError
from synthesis.kinds.guide_way import scene as sc
from synthesis.kinds.guide_way.check import control_names as names_of, whose_path
from synthesis.spec.common import bounds_of, value_of
from synthesis.kinds.guide_way import spline as sp

#: back-off of each sampled rule, x its scale, so the rules hold between the samples too (reach: none,
#: it is met with equality at the fold by construction)
BACKOFF = {"reach": 0.0, "arm_turns_forward": 0.01, "no_undercut": 0.01, "pressure_angle": 0.02,
           # [dynamics.limits]: the re-check samples the path more finely than the NLP (the peak torque came 0.2 %
           # over its limit between the NLP's samples near the fold, where the arm turns fast along the path)
           "peak_input_torque": 0.01, "peak_shaking_force": 0.01, "peak_shaking_moment": 0.01}

#: IPOPT's monotone barrier: with the window's edges held, the adaptive one raised mu to 10 within a few iterations
#: from the fit at some pressure-angle limits and lost the path (smooth_redesign from start 0: 82, 81.5 and 70 deg
#: reached max_iter; monotone: 82 and 81.5 converge, 70 still does not; 85 ... 60 deg otherwise converge either
#: way to the same smoothness; GUIDE_WAY.md)
MU_STRATEGY = {"ipopt.mu_strategy": "monotone"}


def control_of(x, n: int):
    """(n, 2) control points from the decision vector (x coordinates first)."""
    if isinstance(x, (ca.SX, ca.MX)):
        # both halves are of x's one type (mypy sees each as SX or MX, a pair casadi's stubs have no overload for)
        return ca.horzcat(x[:n], x[n:])  # type: ignore[arg-type]
    x = np.asarray(x, float)
    return np.column_stack([x[:n], x[n:]])


def design_box(spec, fit) -> tuple[np.ndarray, np.ndarray]:
    """Start 0 and the bounds (2n x 2) of the control points: the spec's ``[spline] control`` where it gives them
    (a fixed coordinate has lo = hi), else the convex fit, each coordinate within ``move`` of it."""
    given = spec.spline.control
    if given is None:
        init = np.concatenate([fit.control[:, 0], fit.control[:, 1]])
        return init, np.column_stack([init - spec.spline.move, init + spec.spline.move])
    coordinates = [point[k] for k in (0, 1) for point in given]         # x coordinates first, as names_of
    return (np.array([value_of(v) for v in coordinates], float),
            np.array([bounds_of(v) for v in coordinates], float))


def start_scene(spec, control: np.ndarray, samples: int):
    """(scene, window edges) of the path of ``control`` on the NLP's samples: the samples outside the fold window
    that the NLP holds the pressure-angle rule at (start 0's: the design box's init, the spec's control points,
    else the convex fit), as the check finds them on its path, and the window's exact edges."""
    scene = sc.spline_scene(spec, samples, control, edge_samples=False)
    return scene, scene.edges


class FixedGuide(KindNLP):
    """A conic (published) guide way: nothing to optimise; the driver refuses it as bad input (exit 2)."""

    def __init__(self, spec):
        values = spec.design_values()
        self.names = list(values)
        self.init = np.array(list(values.values()), float)
        self.bounds = np.column_stack([self.init, self.init])

    def solve(self, start: int, x_design: np.ndarray) -> StartOutcome:
        # solve refuses such a spec before any start (every variable fixed): the tolerance analysis meets this
        raise SpecError("guide_way: a guide way of published conics has no NLP to solve or linearise (a [spline] "
                        "path has; `agrisynth check` evaluates the conics)")


#: how many times a start the arm cannot drive is pulled half-way towards start 0 (GuideNLP.drivable_start)
PULLS = 6


class GuideNLP(KindNLP):
    maps_its_starts = True      # a start is moved before it is solved (see its start map)

    def __init__(self, spec, fit, elastic: bool = False, setting: Setting | None = None):
        setting = setting or Setting(spec)
        s = spec.spline
        n = s.control_points
        self.spec, self.n, self.fit = spec, n, fit
        self.names = names_of(n)
        self.init, self.bounds = design_box(spec, fit)
        self.keys = sc.spline_path(spec, None).keys       # key points, tangents, the fold: read by several rows
        x = ca.SX.sym("P", 2 * n)
        control = control_of(x, n)
        samples = spec.solver.samples_per_segment
        try:
            scene, self.edges = start_scene(spec, control_of(self.init, n), samples)
        except SpecError as exc:                        # start 0's path cannot be driven by the arm
            raise SpecError(f"{whose_path(spec)}, start 0: {exc}") from None
        self.masks = masks = scene.pressure_masks
        self.edges = self._about_the_key_point(self.edges)
        # each edge of the fold window an auxiliary variable u_e, pinned by theta(M(u_e)) = the edge's arm angle
        # (a structural row) and held to the pressure-angle rule: the rule's largest value outside the window is
        # at its edge, which moves with the design (start 0's samples alone missed it by 0.8 deg)
        self.stretches = scene.spline.stretches(samples)
        u_edge = ca.SX.sym("u_edge", len(self.edges))
        edge_arms = [sc.symbolic_edge_arm(spec, control, self.stretches[e.k], u_edge[i])
                     for i, e in enumerate(self.edges)]
        rules = sc.rules_of(spec, sc.symbolic_arms(spec, control, samples), masks, edge_arms)
        if spec.dynamics is not None and spec.dynamics.has_rules():
            from synthesis.kinds.guide_way.dynamics import nlp_rules     # a spec without limits imports none of it

            rules += nlp_rules(spec, control, samples)
        h = sp.energy_matrix(n)
        energy = ca.bilin(ca.DM(h), control[:, 0], control[:, 0]) + ca.bilin(ca.DM(h), control[:, 1], control[:, 1])
        key_rows = self._structural(control)
        self._key_projection(x, key_rows)
        structural = key_rows + self._edge_rows(control, edge_arms)
        edge_lo, edge_hi = self._edge_bounds()
        lbx = np.concatenate([self.bounds[:, 0], edge_lo])
        ubx = np.concatenate([self.bounds[:, 1], edge_hi])
        self.problem = Problem("guide_way", ca.vertcat(x, u_edge), lbx, ubx, structural,
                               rules, ObjectiveParts(f=energy / fit.energy), hard_in_elastic=("reach",),
                               backoff=per_rule_backoff(lambda rule: BACKOFF.get(rule.name, 0.0)),
                               ipopt="standard", ipopt_options=MU_STRATEGY, max_iter=spec.solver.max_iter,
                               x_units=["mm"] * (2 * n) + [""] * len(self.edges),
                               structural_units=self._structural_units + ["rad"] * len(self.edges),
                               objective_unit="")
        self.compiled = compile_problem(setting, self.problem, elastic)

    def _about_the_key_point(self, edges: list) -> list:
        """Start 0's window edges measured from the arm angle at the fold's key point, where the NLP's rows put the
        fold (start 0's own path may miss it: a spec's control points), the turn nearest start 0's centre."""
        keys = self.keys
        centre = math.degrees(sc.fold_direction(keys.points[keys.index(keys.fold)]))
        return [dataclasses.replace(e, centre_deg=sc.nearest_turn(centre, e.centre_deg)) for e in edges]

    def _edge_bounds(self) -> tuple[list, list]:
        """Each u_e within its stretch and, where start 0 has several edges on one stretch, between the midpoints
        of its neighbours (each edge keeps its own root: the wrapped row has one at every crossing)."""
        lo, hi = [], []
        for e in self.edges:
            st = self.stretches[e.k].u
            same = sorted(f.u for f in self.edges if f.k == e.k)
            at = same.index(e.u)
            lo.append(st[0] if at == 0 else 0.5 * (same[at - 1] + e.u))
            hi.append(st[-1] if at == len(same) - 1 else 0.5 * (e.u + same[at + 1]))
        return lo, hi

    def _edge_rows(self, control, edge_arms: list) -> list:
        """theta(M(u_e)) - centre = sign x window (rad, the difference wrapped to (-pi, pi]), per edge; the centre
        the direction of the path's fold point (sc.fold_direction, as the re-check measures it): the key point's
        where the key rows hold, and moving with the design off them, as a tolerance analysis perturbs it."""
        w = math.radians(self.spec.rules.fold_window)
        keys = self.keys
        fold = ca.mtimes(ca.DM(sp.basis(self.n, keys.u[keys.index(keys.fold)])), control)
        centre = sc.fold_direction(fold)
        rows = []
        for e, arm in zip(self.edges, edge_arms):
            d = arm.theta - centre
            rows.append((ca.atan2(ca.sin(d), ca.cos(d)) - e.sign * w, 0.0, 0.0))
        return rows

    def _edges_at(self, x_design: np.ndarray) -> list | None:
        """The fold window's edges on the path of a design (start_scene), None where the arm cannot drive it."""
        try:
            return start_scene(self.spec, control_of(x_design, self.n), self.spec.solver.samples_per_segment)[1]
        except SpecError:
            return None

    def edges_of(self, edges: list | None) -> np.ndarray:
        """The edge variables u_e of a start from the edges of its path (:meth:`_edges_at`): start 0's where that
        path has not the same edges or the arm cannot drive it (None), within their bounds."""
        u0 = np.array([e.u for e in self.edges], float)
        if not self.edges or edges is None:
            return u0
        lo, hi = self.problem.lbx[2 * self.n:], self.problem.ubx[2 * self.n:]
        u = []
        for e, a, b in zip(self.edges, lo, hi):       # the root of the same stretch and side within its bounds
            roots = [f.u for f in edges if (f.k, f.sign) == (e.k, e.sign) and a <= f.u <= b]
            u.append(min(roots, key=lambda r: abs(r - e.u)) if roots else e.u)
        return np.clip(u, lo, hi)

    def _structural(self, control) -> list:
        keys = self.keys
        v_min = self.spec.spline.min_speed * keys.length
        rows: list[Row] = []
        units: list[str] = []
        for name, u, (kx, ky) in zip(keys.names, keys.u, keys.points):
            m = ca.mtimes(ca.DM(sp.basis(self.n, u)), control)
            rows += [(m[0] - kx, 0.0, 0.0), (m[1] - ky, 0.0, 0.0)]
            units += ["mm", "mm"]
            if name in keys.tangents:
                tx, ty = keys.tangents[name]
                m1 = ca.mtimes(ca.DM(sp.basis(self.n, u, 1)), control)
                rows += [((m1[0] * ty - m1[1] * tx) / keys.length, 0.0, 0.0), (m1[0] * tx + m1[1] * ty, v_min, None)]
                units += ["", "mm"]           # the cross product relative to the path length; the speed (mm)
        fold_u = keys.u[keys.index(keys.fold)]
        m = ca.mtimes(ca.DM(sp.basis(self.n, fold_u)), control)
        m1 = ca.mtimes(ca.DM(sp.basis(self.n, fold_u, 1)), control)
        m2 = ca.mtimes(ca.DM(sp.basis(self.n, fold_u, 2)), control)
        rows.append(((ca.sumsqr(m1) + ca.dot(m, m2)) / v_min**2, 0.5, None))
        self._structural_units = units + [""]
        return rows

    def _key_projection(self, x: ca.SX, rows: list) -> None:
        """The key-point and tangent rows are linear in the control points, A x = b: kept for
        :meth:`drivable_start` (the free coordinates' columns only: a fixed coordinate is not moved)."""
        linear = [e for e, lb, ub in rows if lb is not None and lb == ub]
        A = np.array(ca.DM(ca.Function("key_rows_jacobian", [x], [ca.jacobian(ca.vertcat(*linear), x)])(
            np.zeros(x.numel()))))
        residual = ca.Function("key_rows", [x], [ca.vertcat(*linear)])
        self._key_rows = (A, lambda v: np.array(residual(v)).ravel())

    def drivable_start(self, x0: np.ndarray) -> np.ndarray:
        """``x0``, or where the arm cannot drive its path, a start it can drive with the key points and tangents
        met: ``x0`` moved onto the key rows (the least change of its free coordinates), then, while its path leaves
        the arm's reach or the bounds, pulled half-way towards start 0 (at most PULLS times; every pull keeps the key
        rows where start 0 meets them, as the fit does), else ``x0`` as it is.  A Latin-hypercube point of the
        2 x control_points coordinates, each within `move` of the fit, misses the fold point D on |OM| = R - d and
        dips inside that circle: IPOPT then stopped at its first evaluation (Invalid_Number_Detected, 0 iterations;
        4 of 6 starts at a 70 deg limit).  A function of x0 alone: deterministic for any worker count."""
        return self._drivable(x0)[0]

    def _drivable(self, x0) -> tuple[np.ndarray, list | None]:
        """(:meth:`drivable_start`, the edges of its path, None where the arm cannot drive it): one scene a start."""
        x0 = np.asarray(x0, float)
        edges = self._edges_at(x0)
        if edges is not None:           # as it is, where the arm can drive it (start 0, the spec's or the fit)
            return x0, edges
        A, residual = self._key_rows
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        free = hi > lo
        on_keys = x0.copy()
        on_keys[free] -= np.linalg.lstsq(A[:, free], residual(x0), rcond=None)[0]
        for k in range(PULLS + 1):
            x = self.init + 0.5 ** k * (on_keys - self.init)
            if np.any(x < lo) or np.any(x > hi):
                continue
            edges = self._edges_at(x)
            if edges is not None:
                return x, edges
        return x0, None

    def solve(self, start: int, x0) -> StartOutcome:
        x0, edges = self._drivable(x0)
        out = self.compiled.solve(start, np.concatenate([x0, self.edges_of(edges)]))
        design = dict(zip(self.names, (float(v) for v in out.x[: 2 * self.n])))
        return StartOutcome.of(out, design, out.objective)
