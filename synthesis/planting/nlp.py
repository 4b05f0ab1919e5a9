"""The planting-arm NLP: every rule of a planting_fourbar spec as an IPOPT constraint.

Decision variables: the free design variables (fixed ones get lo = hi), the crank angles of
P1-P6, and for the robust objective the smallest normalised margin tau.  The precision points are
where the path meets the seedbed lines and the soil, written as equalities on their crank angles,
so IPOPT sees smooth constraints instead of min/max over samples.  The lowest point is stationary
(vy = 0) and no sample of the turn lies lower.  This is the only module that calls ``nlpsol``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from constraints import Rule
from constraints.acceleration import acceleration_sign_rule
from constraints.angles import entry_angle_rule
from constraints.depth import depth_rule
from constraints.grashof import grashof_rule
from constraints.precision_points import p4p6_rule, seedbed_rules
from constraints.speed import p2_speed_rule
from constraints.transmission import transmission_rules
from synthesis.ipopt_log import captured_stdout
from synthesis.kinematics.planting_arm import link_function, tip_derivatives
from synthesis.planting.scene import POINTS, TWO_PI, PlantingScene, find_precision_points
from synthesis.spec.common import bounds_of, value_of
from synthesis.spec.planting import PlantingFourbarSpec

MIN_GAP = math.radians(1.0)          # smallest crank-angle gap between consecutive precision points
ANGLES = {"zeta", "phi", "seedbed_tilt"}


@dataclass
class StartOutcome:
    start: int
    design: dict[str, float]
    theta: dict[str, float]
    objective: float
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str
    x: np.ndarray


def _append_rows(rows: list, lbg: list, ubg: list, expr, lb, ub) -> None:
    """Append each element of a scalar or vector expression as one constraint row with [lb, ub]."""
    expr = ca.vec(ca.SX(expr))
    rows += [expr[i] for i in range(expr.numel())]
    lbg += [lb] * expr.numel()
    ubg += [ub] * expr.numel()


class PlantingNLP:
    """Built once per spec; :meth:`solve` runs one IPOPT solve from a start point."""

    def __init__(self, spec: PlantingFourbarSpec, elastic: bool = False):
        self.spec = spec
        self.elastic = elastic
        self.names = list(spec.variables())
        self.bounds = np.array([bounds_of(v) for v in spec.variables().values()], dtype=float)
        self.init = np.array([value_of(v) for v in spec.variables().values()], dtype=float)
        x = ca.SX.sym("x", len(self.names))
        th = ca.SX.sym("theta", 6)
        v = {n: x[i] for i, n in enumerate(self.names)}
        angles = dict(zip(POINTS, (th[i] for i in range(6))))
        geometry = self._geometry(v, angles)          # the P1-P6 states, shared by both builders
        self.rules = self._rules(v, angles, geometry)

        rows, lbg, ubg, scales, owners = [], [], [], [], []
        for expr, lb, ub in self._structural(angles, geometry):
            _append_rows(rows, lbg, ubg, expr, lb, ub)
        n_struct = len(rows)
        for k, rule in enumerate(self.rules):
            # tighten by backoff x scale: sampled rules must still hold between the samples
            tighten = spec.solver.backoff * rule.scale
            for expr, lb, ub in rule.rows():
                expr = ca.vec(ca.SX(expr))
                for i in range(expr.numel()):
                    rows.append(expr[i])
                    lbg.append(-ca.inf if lb is None else lb + tighten)
                    ubg.append(ca.inf if ub is None else ub - tighten)
                    scales.append(rule.scale)
                    owners.append(k)
        g_rule = rows[n_struct:]
        if not elastic:
            objective, extra_x, extra_lb, extra_ub, extra_rows = self._objective(x, v, th, g_rule, lbg[n_struct:],
                                                                                 ubg[n_struct:], scales)
        else:
            # one slack per rule, on all its rows; minimising their sum names the conflicting rules
            s = ca.SX.sym("slack", len(self.rules))
            extra_x = s
            extra_lb = [0.0] * len(self.rules)
            extra_ub = [ca.inf] * len(self.rules)
            relaxed = []
            for r, lb, ub, k in zip(g_rule, lbg[n_struct:], ubg[n_struct:], owners):
                sc = self.rules[k].scale
                relaxed.append((r + sc * s[k], lb, ca.inf) if lb != -ca.inf else None)
                relaxed.append((r - sc * s[k], -ca.inf, ub) if ub != ca.inf else None)
            relaxed = [t for t in relaxed if t is not None]
            rows = rows[:n_struct] + [t[0] for t in relaxed]
            lbg = lbg[:n_struct] + [t[1] for t in relaxed]
            ubg = ubg[:n_struct] + [t[2] for t in relaxed]
            objective = ca.sum1(s)
            extra_rows = []
        for expr, lb, ub in extra_rows:
            _append_rows(rows, lbg, ubg, expr, lb, ub)
        self.n_extra = extra_x.numel()
        self._lbx = np.concatenate([self.bounds[:, 0], np.full(6, -4 * math.pi), np.array(extra_lb, dtype=float)])
        self._ubx = np.concatenate([self.bounds[:, 1], np.full(6, 6 * math.pi), np.array(extra_ub, dtype=float)])
        self._lbg, self._ubg = np.array(lbg, dtype=float), np.array(ubg, dtype=float)
        self.g = ca.vertcat(*rows)
        self.decision = ca.vertcat(x, th, extra_x)
        self.objective = objective
        self.g_function = ca.Function("g", [self.decision], [self.g])
        opts = {"ipopt.print_level": 5, "print_time": False,
                "ipopt.max_iter": spec.solver.max_iter, "ipopt.tol": 1e-8,
                "ipopt.acceptable_tol": 1e-6, "ipopt.mu_strategy": "adaptive",
                "ipopt.sb": "yes"}
        self.solver = ca.nlpsol("planting", "ipopt", {"x": self.decision, "f": objective, "g": self.g}, opts)

    # ------------------------------------------------------------------ model pieces

    def _arm(self, v) -> tuple:
        rad = math.pi / 180.0
        return ca.vertcat(v["l1"], v["l2"], v["l3"], v["l4"], v["l5"], v["zeta"] * rad, v["phi"] * rad)

    def _state(self, p, theta):
        spec = self.spec
        omega = spec.operation.crank_speed * TWO_PI / 60.0
        pos, d1, d2 = tip_derivatives(spec.arm.branch)(theta, p)
        return pos, d1 * omega, d2 * omega**2

    def _geometry(self, v, th):
        spec = self.spec
        p = self._arm(v)
        st = {n: self._state(p, th[n]) for n in POINTS}
        tilt = v["seedbed_tilt"] * math.pi / 180.0
        normal = (-ca.sin(tilt), ca.cos(tilt))

        def height(pos):
            return normal[0] * (pos[0] - v["seedbed_x"]) + normal[1] * (pos[1] - v["seedbed_y"])

        soil = v["soil_level"] if spec.soil.level is not None else st["P5"][0][1] + spec.soil.analysis_depth
        return p, st, normal, height, soil

    def _structural(self, th, geometry):
        """Definitions of P1-P6 (equalities, crossing directions, order) and the lowest-point bound."""
        spec = self.spec
        p, st, normal, height, soil = geometry
        rows = [
            (st["P4"][0][1] - soil, 0.0, 0.0), (st["P6"][0][1] - soil, 0.0, 0.0),    # on the soil line
            (st["P5"][1][1], 0.0, 0.0),                                                # lowest: vy = 0
            (height(st["P3"][0]), 0.0, 0.0),
            (height(st["P2"][0]) - spec.seedbed.thickness, 0.0, 0.0),
            (height(st["P1"][0]) - spec.seedbed.seedling_height, 0.0, 0.0),
            (st["P4"][1][1], -ca.inf, 0.0), (st["P6"][1][1], 0.0, ca.inf),             # entering / leaving
        ]
        for n in ("P1", "P2", "P3"):                                                   # passing into the mat
            rows.append((normal[0] * st[n][1][0] + normal[1] * st[n][1][1], -ca.inf, 0.0))
        order = ("P5", "P6", "P1", "P2", "P3", "P4")
        for a, b in zip(order, order[1:]):
            rows.append((th[b] - th[a], MIN_GAP, ca.inf))
        rows.append((th["P5"] + TWO_PI - th["P4"], MIN_GAP, ca.inf))
        n = spec.solver.samples_per_turn
        samples = [th["P5"] + TWO_PI * k / n for k in range(1, n)]
        f = tip_derivatives(spec.arm.branch).map(len(samples))
        ys = f(ca.horzcat(*samples), p)[0][1, :]
        rows.append((ca.vec(ys) - st["P5"][0][1], 0.0, ca.inf))
        return rows

    def _rules(self, v, th, geometry) -> list[Rule]:
        spec, lim = self.spec, self.spec.rules
        p, st, _, _, _ = geometry
        omega = spec.operation.crank_speed * TWO_PI / 60.0
        fwd = spec.operation.forward_speed * 1000.0
        pos = {n: (st[n][0][0], st[n][0][1]) for n in POINTS}
        rules = seedbed_rules(pos["P1"], pos["P2"], pos["P3"], lim.p1p3, lim.p2p3, lim.collinearity)
        rules.append(entry_angle_rule(st["P4"][1][0] + fwd, st["P4"][1][1], lim.entry_angle_min))
        rules.append(depth_rule(pos["P4"][1], pos["P5"][1], lim.depth))
        t4, t6 = (th["P4"] - TWO_PI) / omega, th["P6"] / omega
        rules.append(p4p6_rule((pos["P4"][0] + fwd * t4, pos["P4"][1]), (pos["P6"][0] + fwd * t6, pos["P6"][1]),
                               lim.p4p6_min))
        rules.append(p2_speed_rule(st["P2"][1][0], st["P2"][1][1], lim.p2_speed_min))
        n = spec.solver.samples_per_phase
        s = np.linspace(0.0, 1.0, n)
        f = tip_derivatives(spec.arm.branch).map(n)
        acc_scale = omega**2 * value_of(spec.arm.l2)
        signs = lim.acceleration
        for phase, a, b, sign in (("hold", "P3", "P4", signs.hold), ("throw", "P4", "P5", signs.throw),
                                  ("release", "P5", "P6", signs.release)):
            ta, tb = th[a], th[b] + (TWO_PI if b == "P5" else 0.0)
            grid = ca.horzcat(*[ta + si * (tb - ta) for si in s])
            ay = ca.vec(f(grid, p)[2][1, :]) * omega**2
            rules.append(acceleration_sign_rule(phase, ay, sign, acc_scale))
        rules.append(grashof_rule(v["l1"], v["l2"], v["l3"], v["l4"]))
        m = spec.solver.samples_per_turn
        mu = link_function(spec.arm.branch).map(m)(np.linspace(0.0, TWO_PI, m, endpoint=False).reshape(1, -1), p)[0]
        rules += transmission_rules(ca.vec(mu) * (180.0 / math.pi), lim.transmission_angle)
        return rules

    def _objective(self, x, v, th, rule_rows, lbg, ubg, scales):
        """(f, extra decision vars, their bounds, extra constraint rows) for the spec's objective."""
        name = self.spec.objective.name
        if name == "nearest":
            width = np.maximum(self.bounds[:, 1] - self.bounds[:, 0], 1e-9)
            f = ca.sumsqr((x - self.init) / width)
            return f, ca.SX(0, 1), [], [], []
        if name == "robust":
            tau = ca.SX.sym("tau")
            rows = []
            for r, lb, ub, sc in zip(rule_rows, lbg, ubg, scales):
                if lb != -ca.inf:
                    rows.append(((r - lb) / sc - tau, 0.0, ca.inf))
                if ub != ca.inf:
                    rows.append(((ub - r) / sc - tau, 0.0, ca.inf))
            return -tau, tau, [-ca.inf], [10.0], rows
        # smooth: minimise the peak squared acceleration over the turn
        spec = self.spec
        omega = spec.operation.crank_speed * TWO_PI / 60.0
        m = spec.solver.samples_per_turn
        p = self._arm(v)
        grid = np.linspace(0.0, TWO_PI, m, endpoint=False).reshape(1, -1)
        acc = tip_derivatives(spec.arm.branch).map(m)(grid, p)[2] * omega**2
        z = ca.SX.sym("peak_acc_sq")
        scale = (omega**2 * 100.0) ** 2
        rows = [((z - ca.vec(ca.sum1(acc**2)) / scale), 0.0, ca.inf)]
        return z, z, [0.0], [ca.inf], rows

    # ------------------------------------------------------------------ solving

    def theta_guess(self, values: dict[str, float]) -> np.ndarray:
        """Crank angles of P1-P6 for a start: the numeric precision points where they exist."""
        scene = PlantingScene.from_spec(self.spec, values)
        try:
            pts = find_precision_points(scene)
            th5 = pts.theta["P5"]
        except Exception:   # a start that does not assemble: spread the points over the turn
            pts, th5 = None, 0.0
        spread = {"P5": 0.0, "P6": 0.6, "P1": 2.5, "P2": 3.2, "P3": 3.6, "P4": 5.4}
        out = []
        for n in POINTS:
            t = pts.theta[n] if pts is not None else None
            out.append(th5 + spread[n] if t is None else t)
        return np.array(out)

    def objective_value(self, design: dict[str, float], fvalue: float) -> float:
        """The objective in report units: nearest and robust as solved; smooth as peak |a| in mm/s^2."""
        if self.spec.objective.name == "robust":
            return -fvalue
        if self.spec.objective.name == "smooth":
            omega = self.spec.operation.crank_speed * TWO_PI / 60.0
            return math.sqrt(max(fvalue, 0.0)) * omega**2 * 100.0
        return fvalue

    def solve(self, start: int, x_design: np.ndarray) -> StartOutcome:
        values = dict(zip(self.names, x_design))
        theta0 = self.theta_guess(values)
        extra0 = np.zeros(self.n_extra)
        x0 = np.concatenate([x_design, theta0, extra0])
        t0 = time.perf_counter()
        with captured_stdout() as log:
            sol = self.solver(x0=x0, lbx=self._lbx, ubx=self._ubx, lbg=self._lbg, ubg=self._ubg)
        wall = time.perf_counter() - t0
        stats = self.solver.stats()
        xs = np.asarray(sol["x"]).ravel()
        design = dict(zip(self.names, (float(v) for v in xs[: len(self.names)])))
        theta = dict(zip(POINTS, (float(t) for t in xs[len(self.names): len(self.names) + 6])))
        return StartOutcome(start, design, theta, float(sol["f"]), stats["return_status"], bool(stats["success"]),
                            int(stats["iter_count"]), wall, log(), xs)

    def slack_values(self, outcome_x: np.ndarray) -> dict[str, float]:
        """Elastic NLP only: each rule's slack at a solution (x, theta, slacks...)."""
        s = outcome_x[-len(self.rules):]
        return {r.name: float(v) for r, v in zip(self.rules, s)}
