"""The clamp-cam NLP: every rule of a clamp_cam spec as an IPOPT constraint (CasADi, exact AD).

Decision variables: the design variables of the spec (fixed ones get lo = hi): base radius,
roller radius, offset or pivot distance and arm length, where the rise starts and the four
segment angles; plus tau, the peak |pressure angle|, for that objective.  The rise and the return
are sampled at fixed fractions u of their length, so the normalised law values are numbers and
the segment angles enter smoothly (ds/dphi = h v(u)/beta, d2s/dphi2 = h a(u)/beta^2).  Pressure
angle and curvature are semi-infinite rules sampled here; solve re-checks them on a 10x finer grid
without CasADi.  This is the only module of the kind that calls ``nlpsol``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from constraints.base import Rule
from constraints.cam import acceleration_rule, pressure_angle_rule, undercut_rule
from synthesis.clamp_cam.motion import Timing
from synthesis.clamp_cam.scene import follower_of, omega_of, stroke_of, timing_rules
from synthesis.ipopt_log import captured_stdout
from synthesis.kinematics import cam_follower as cf
from synthesis.kinematics.motion_laws import law as closed_form_law
from synthesis.spec.clamp_cam import ClampCamSpec
from synthesis.spec.common import bounds_of, value_of

DEG = math.pi / 180.0
#: sampled rules: tightened by the backoff so they hold between the samples too (timing rows are exact)
SAMPLED = ("pressure_angle_rise", "pressure_angle_return", "no_undercut", "no_undercut_outer", "max_acceleration")


@dataclass
class StartOutcome:
    start: int
    design: dict[str, float]
    objective: float
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str
    x: np.ndarray


def _as_column(expr) -> list:
    expr = ca.vec(ca.SX(expr))
    return [expr[i] for i in range(expr.numel())]


class CamNLP:
    """Built once per spec; :meth:`solve` runs one IPOPT solve from a start point."""

    def __init__(self, spec: ClampCamSpec, optimised=None, elastic: bool = False):
        self.spec, self.elastic = spec, elastic
        variables = spec.variables()
        self.names = list(variables)
        self.bounds = np.array([bounds_of(v) for v in variables.values()], dtype=float)
        self.init = np.array([value_of(v) for v in variables.values()], dtype=float)
        x = ca.SX.sym("x", len(self.names))
        v = {n: x[i] for i, n in enumerate(self.names)}
        if spec.motion.law == "optimised":
            rise_law, return_law = optimised.rise, optimised.return_
        else:
            rise_law = return_law = closed_form_law(spec.motion.law)
        alpha, kappa, acc = self._sampled(v, rise_law, return_law)
        self.alpha_function = ca.Function("alpha", [x], [ca.vertcat(alpha["rise"], alpha["return"])])
        self.rules = self._rules(v, alpha, kappa, acc)

        rows, lbg, ubg = self._structural(v)
        n_struct = len(rows)
        owners = []
        for k, rule in enumerate(self.rules):
            tighten = spec.solver.backoff * rule.scale if rule.name in SAMPLED else 0.0
            for expr, lb, ub in rule.rows():
                for e in _as_column(expr):
                    rows.append(e)
                    lbg.append(-ca.inf if lb is None else lb + tighten)
                    ubg.append(ca.inf if ub is None else ub - tighten)
                    owners.append(k)
        extra = ca.SX(0, 1)
        extra_lb, extra_ub = [], []
        if elastic:
            # one slack per rule on all its rows; minimising their sum names the rules that conflict
            slack = ca.SX.sym("slack", len(self.rules))
            relaxed_rows, relaxed_lb, relaxed_ub = [], [], []
            for r, lb, ub, k in zip(rows[n_struct:], lbg[n_struct:], ubg[n_struct:], owners):
                sc = self.rules[k].scale
                if lb != -ca.inf:
                    relaxed_rows.append(r + sc * slack[k]), relaxed_lb.append(lb), relaxed_ub.append(ca.inf)
                if ub != ca.inf:
                    relaxed_rows.append(r - sc * slack[k]), relaxed_lb.append(-ca.inf), relaxed_ub.append(ub)
            rows = rows[:n_struct] + relaxed_rows
            lbg, ubg = lbg[:n_struct] + relaxed_lb, ubg[:n_struct] + relaxed_ub
            objective = ca.sum1(slack)
            extra, extra_lb, extra_ub = slack, [0.0] * len(self.rules), [ca.inf] * len(self.rules)
        else:
            objective, extra, extra_lb, extra_ub, more = self._objective(x, v, alpha)
            for e, lb, ub in more:
                for r in _as_column(e):
                    rows.append(r), lbg.append(lb), ubg.append(ub)
        self.n_extra = extra.numel()
        self.decision = ca.vertcat(x, extra)
        self.g = ca.vertcat(*rows)
        self.objective = objective
        self._lbx = np.concatenate([self.bounds[:, 0], np.array(extra_lb, dtype=float)])
        self._ubx = np.concatenate([self.bounds[:, 1], np.array(extra_ub, dtype=float)])
        self._lbg, self._ubg = np.array(lbg, dtype=float), np.array(ubg, dtype=float)
        self.g_function = ca.Function("g", [self.decision], [self.g])
        opts = {"ipopt.print_level": 5, "print_time": False, "ipopt.max_iter": spec.solver.max_iter,
                "ipopt.tol": 1e-9, "ipopt.acceptable_tol": 1e-7, "ipopt.sb": "yes"}
        self.solver = ca.nlpsol("clamp_cam", "ipopt", {"x": self.decision, "f": objective, "g": self.g}, opts)

    # ------------------------------------------------------------------ model pieces

    def _sampled(self, v, rise_law, return_law):
        """Pressure angle (deg) per motion segment, pitch curvature and acceleration at the samples."""
        spec = self.spec
        n = spec.solver.samples_per_segment
        u = np.linspace(0.0, 1.0, n)
        h = stroke_of(spec)
        follower = follower_of(spec, v)
        alpha, kappa, acc = {}, [], []
        for name, law, sign in (("rise", rise_law, 1.0), ("return", return_law, -1.0)):
            beta = v[name] * DEG
            s = h * (law.s(u) if sign > 0 else 1.0 - law.s(u))
            ds = sign * h * ca.DM(law.v(u)) / beta
            dds = sign * h * ca.DM(law.a(u)) / beta**2
            c = cf.roller_centre(follower, ca.DM(s), ds, dds)
            alpha[name] = cf.degrees(cf.pressure_angle(c))
            kappa.append(cf.pitch_curvature(c))
            acc.append(dds)
        # the dwells (at rest and at full stroke) count with the rise: constant angle -atan(e / s0) there
        rest = cf.roller_centre(follower, ca.DM([0.0, h]), ca.DM.zeros(2), ca.DM.zeros(2))
        alpha["rise"] = ca.vertcat(alpha["rise"], cf.degrees(cf.pressure_angle(rest)))
        return alpha, ca.vertcat(*kappa), ca.vertcat(*acc)

    def _structural(self, v) -> tuple[list, list, list]:
        """The segments fill one turn; the follower geometry exists (real s0, the arm reaches the cam)."""
        spec = self.spec
        rows = [v["rise"] + v["far_dwell"] + v["return"] + v["near_dwell"]]
        lbg, ubg = [360.0], [360.0]
        r0 = v["base_radius"]
        if spec.follower.type == "translating":
            rows.append(v["offset"] ** 2 - (0.9 * r0) ** 2)
            lbg.append(-ca.inf), ubg.append(0.0)
        else:
            a, l = v["pivot_distance"], v["arm_length"]
            rows += [r0 - (a + l), (a - l) ** 2 - r0**2]
            lbg += [-ca.inf, -ca.inf]
            ubg += [-1e-3, -1e-3]
            rest = cf.Oscillating(r0, a, l, spec.follower.side).rest_angle()
            rows.append(rest + stroke_of(spec))                     # the arm never folds past 170 deg
            lbg.append(-ca.inf), ubg.append(170.0 * DEG)
        return rows, lbg, ubg

    def _rules(self, v, alpha, kappa, acc) -> list[Rule]:
        spec, lim = self.spec, self.spec.rules
        rules = [pressure_angle_rule("rise", alpha["rise"], lim.pressure_angle_rise),
                 pressure_angle_rule("return", alpha["return"], lim.pressure_angle_return),
                 undercut_rule(kappa, v["roller_radius"], lim.min_working_radius)]
        if lim.groove:
            rules.append(undercut_rule(kappa, v["roller_radius"], lim.min_working_radius, flank="outer"))
        timing = Timing.from_design(v)
        reference = Timing.from_design(dict(zip(self.names, self.init)))
        rules += timing_rules(spec, timing, reference)
        if lim.max_acceleration is not None:
            w2 = omega_of(spec) ** 2
            scale = 1.0 if spec.follower.type == "translating" else 180.0 / math.pi
            rules.append(acceleration_rule(acc * (scale * w2), lim.max_acceleration,
                                           "mm/s^2" if scale == 1.0 else "deg/s^2"))
        return rules

    def _objective(self, x, v, alpha):
        """(f, extra variables, their bounds, extra rows) of the spec's objective."""
        name = self.spec.objective.name
        if name == "base_radius":
            return v["base_radius"] / self.init[self.names.index("base_radius")], ca.SX(0, 1), [], [], []
        if name == "nearest":
            width = np.maximum(self.bounds[:, 1] - self.bounds[:, 0], 1e-9)
            return ca.sumsqr((x - self.init) / width), ca.SX(0, 1), [], [], []
        tau = ca.SX.sym("tau")                       # peak |pressure angle|, deg
        both = ca.vertcat(alpha["rise"], alpha["return"])
        rows = [(tau - both, 0.0, ca.inf), (tau + both, 0.0, ca.inf)]
        return tau / 10.0, tau, [0.0], [90.0], rows

    # ------------------------------------------------------------------ solving

    def tau_start(self, x_design: np.ndarray) -> np.ndarray:
        """Start values of the extra variables: tau = the start design's peak |pressure angle|."""
        if self.elastic or self.n_extra == 0:
            return np.zeros(self.n_extra)
        alpha = np.asarray(self.alpha_function(x_design)).ravel()
        return np.array([float(np.max(np.abs(alpha)))])

    def objective_value(self, design: dict[str, float], fvalue: float) -> float:
        """The objective in report units: base radius mm, peak pressure angle deg, or the distance."""
        name = self.spec.objective.name
        if name == "base_radius":
            return design["base_radius"]
        if name == "pressure_angle":
            return fvalue * 10.0
        return fvalue

    def solve(self, start: int, x_design: np.ndarray) -> StartOutcome:
        x0 = np.concatenate([x_design, self.tau_start(x_design)])
        t0 = time.perf_counter()
        with captured_stdout() as log:
            sol = self.solver(x0=x0, lbx=self._lbx, ubx=self._ubx, lbg=self._lbg, ubg=self._ubg)
        wall = time.perf_counter() - t0
        stats = self.solver.stats()
        xs = np.asarray(sol["x"]).ravel()
        design = dict(zip(self.names, (float(v) for v in xs[: len(self.names)])))
        return StartOutcome(start, design, float(sol["f"]), stats["return_status"], bool(stats["success"]),
                            int(stats["iter_count"]), wall, log(), xs)

    def slack_values(self, outcome_x: np.ndarray) -> dict[str, float]:
        """Elastic NLP only: each rule's slack at a solution."""
        s = outcome_x[-len(self.rules):]
        return {r.name: float(val) for r, val in zip(self.rules, s)}
