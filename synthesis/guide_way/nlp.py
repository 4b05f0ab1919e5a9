"""The IPOPT stage of the redesign: the spline's control points held to every rule of the guide way.

Decision variables: the control points P (n x 2): those the spec gives (``[spline] control``, start 0
their init values, within their bounds), else each within ``[spline] move`` mm of the convex fit (start
0 the fit).  Structural rows (exact, no back-off): every key point, every key tangent's direction
(M'(u_k) x t_k = 0, M'(u_k) . t_k >= v_min) and |OM| having its minimum at the fold
(|M'|^2 + M . M'' >= v_min^2 / 2 there).  Rules: the same sampled rules as the check
(:func:`synthesis.guide_way.scene.rules_of` on the control points as CasADi symbols; the pressure-angle
samples are those outside the fold window on the path of start 0).  Objective: the smoothness energy
relative to the fit's, so 1 when the fit already meets every rule.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from synthesis.core.ipopt import CompiledNLP
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import ObjectiveParts, Problem, per_rule_backoff
from synthesis.errors import SpecError
from synthesis.guide_way import scene as sc
from synthesis.guide_way import spline as sp

#: back-off of each sampled rule, x its scale, so the rules hold between the samples too (reach: none,
#: it is met with equality at the fold by construction)
BACKOFF = {"reach": 0.0, "arm_turns_forward": 0.01, "no_undercut": 0.01, "pressure_angle": 0.02}


def names_of(n: int) -> list[str]:
    return [f"P{j}_{c}" for c in ("x", "y") for j in range(n)]


def control_of(x, n: int):
    """(n, 2) control points from the decision vector (x coordinates first)."""
    if isinstance(x, (ca.SX, ca.MX)):
        return ca.horzcat(x[:n], x[n:])
    x = np.asarray(x, float)
    return np.column_stack([x[:n], x[n:]])


def design_box(spec, fit) -> tuple[np.ndarray, np.ndarray]:
    """Start 0 and the bounds (2n x 2) of the control points: the spec's ``[spline] control`` where it gives them
    (a fixed coordinate has lo = hi), else the convex fit, each coordinate within ``move`` of it."""
    from synthesis.spec.common import bounds_of, value_of

    given = spec.spline.control
    if given is None:
        init = np.concatenate([fit.control[:, 0], fit.control[:, 1]])
        return init, np.column_stack([init - spec.spline.move, init + spec.spline.move])
    coordinates = [point[k] for k in (0, 1) for point in given]         # x coordinates first, as names_of
    return (np.array([value_of(v) for v in coordinates], float),
            np.array([bounds_of(v) for v in coordinates], float))


def pressure_masks_at(spec, control: np.ndarray, samples: int) -> list[np.ndarray]:
    """The samples the NLP holds the pressure-angle rule at: those outside the fold window on the path of
    ``control`` (start 0, the design box's init: the spec's control points, else the convex fit), as the check
    finds them on its path."""
    return sc.spline_scene(spec, samples, control, window_edges=False).pressure_masks


class FixedGuide:
    """A conic (published) guide way: nothing to optimise; the driver refuses it as bad input (exit 2)."""

    def __init__(self, spec):
        values = spec.design_values()
        self.names = list(values)
        self.init = np.array(list(values.values()), float)
        self.bounds = np.column_stack([self.init, self.init])


class GuideNLP:
    def __init__(self, spec, fit, elastic: bool = False):
        s = spec.spline
        n = s.control_points
        self.spec, self.n, self.fit = spec, n, fit
        self.names = names_of(n)
        self.init, self.bounds = design_box(spec, fit)
        x = ca.SX.sym("P", 2 * n)
        control = control_of(x, n)
        samples = spec.solver.samples_per_segment
        try:
            self.masks = masks = pressure_masks_at(spec, control_of(self.init, n), samples)
        except SpecError as exc:                        # start 0's path cannot be driven by the arm
            from synthesis.guide_way.check import whose_path

            raise SpecError(f"{whose_path(spec)}, start 0: {exc}") from None
        rules = sc.rules_of(spec, sc.symbolic_arms(spec, control, samples), masks)
        h = sp.energy_matrix(n)
        energy = ca.bilin(ca.DM(h), control[:, 0], control[:, 0]) + ca.bilin(ca.DM(h), control[:, 1], control[:, 1])
        self.problem = Problem("guide_way", x, self.bounds[:, 0], self.bounds[:, 1], self._structural(control),
                               rules, ObjectiveParts(f=energy / fit.energy), hard_in_elastic=("reach",),
                               backoff=per_rule_backoff(lambda rule: BACKOFF.get(rule.name, 0.0)),
                               ipopt="standard", max_iter=spec.solver.max_iter, x_units=["mm"] * (2 * n),
                               structural_units=self._structural_units, objective_unit="")
        self.compiled = CompiledNLP(self.problem, elastic)

    def _structural(self, control) -> list:
        keys = sc.spline_path(self.spec, None).keys
        v_min = self.spec.spline.min_speed * keys.length
        rows, units = [], []
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

    def solve(self, start: int, x0) -> StartOutcome:
        out = self.compiled.solve(start, np.asarray(x0, float))
        design = dict(zip(self.names, (float(v) for v in out.x[: 2 * self.n])))
        return StartOutcome.of(out, design, out.objective)
