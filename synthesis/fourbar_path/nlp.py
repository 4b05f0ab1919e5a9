"""The path-synthesis NLP of a fourbar_path spec; the only module of the kind that calls ``nlpsol``.

    minimise   sum_i |P(theta2_i; design) - T_i|^2          (mm^2, the field's standard objective)
    over       r1 r2 r3 r4 rcx rcy x0 y0 theta0  (+ theta2_1..theta2_N when the timing is free)
    subject to Grashof class (3 linear rows), transmission angle (2 exact rows over a turn),
               loop closure (grashof = "any"), sequence of the angles (linear, free timing)

P is the closed-form coupler point (kinematics.coupler_point, no inverse cosine).  The crank
direction of the sequence rule is an NLP *parameter* (+1 / -1), so one built solver serves starts
that go either way.  Built once per spec (per worker) and reused for every start.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from constraints import Rule
from constraints.assembly import assembly_rule
from constraints.grashof_class import grashof_class_rule
from constraints.sequence import sequence_rule
from constraints.transmission_turn import transmission_sampled_rules, transmission_turn_rules
from synthesis.ipopt_log import captured_stdout
from synthesis.fourbar_path.starts import StartMaker, StartPoint
from synthesis.kinematics.coupler_point import BRANCHES, VARIABLES, coupler_point, design_parameters
from synthesis.spec.fourbar_path import FourbarPathSpec

DEG = 180.0 / math.pi
THETA_RANGE = (-4.0 * math.pi, 6.0 * math.pi)    # bounds of the free crank angles (rad): room for one turn
BACKOFF = 1e-9                                   # relative: rows are kept this far inside their limits


@dataclass
class StartOutcome:
    start: int
    design: dict[str, float]        # r1..theta0, spec units
    crank_deg: list[float]          # crank angle of each target, deg
    direction: str                  # "ccw" / "cw" (free timing), "given" (prescribed timing)
    objective: float                # sum of squared distances, mm^2
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str
    x: np.ndarray                   # the solver's full solution vector


def segment_angles(thetas: list, per_segment: int) -> list:
    """The crank's motion from target to target, sampled: per_segment angles in each gap, ends included."""
    out = [thetas[0]]
    for a, b in zip(thetas, thetas[1:]):
        out += [a + (b - a) * k / per_segment for k in range(1, per_segment + 1)]
    return out


def path_rules(spec: FourbarPathSpec, v: dict, thetas: list, sign, samples: int) -> list[Rule]:
    """Every rule of the spec on a design ``v`` (floats or symbols) and target crank angles (rad)."""
    r = [v[n] for n in ("r1", "r2", "r3", "r4")]
    lim = spec.rules
    rules: list[Rule] = []
    full_turn = lim.grashof != "any"
    if full_turn:
        rules.append(grashof_class_rule(lim.grashof, *r))
        rules.append(assembly_rule(thetas, *r, where="at every target"))
        if lim.transmission_angle is not None:
            rules += transmission_turn_rules(*r, lim.transmission_angle)
    else:
        motion = segment_angles(thetas, samples) if len(thetas) > 1 else thetas
        rules.append(assembly_rule(motion, *r, where="at the targets and between them"))
        if lim.transmission_angle is not None:
            rules += transmission_sampled_rules(motion, *r, lim.transmission_angle)
    if not spec.timed and lim.order:
        rules.append(sequence_rule([t * DEG for t in thetas], sign, lim.direction))
    return rules


def _inner(bound: float) -> float:
    """How far inside a rule's limit the NLP keeps its row, so the strict re-check (margin >= 0) holds
    at an active rule despite IPOPT's last-digit residuals."""
    return BACKOFF * max(1.0, abs(bound))


def _rows(rules: list[Rule]) -> tuple[list, list, list]:
    g, lbg, ubg = [], [], []
    for rule in rules:
        for expr, lb, ub in rule.rows():
            expr = ca.vec(ca.SX(expr))
            for i in range(expr.numel()):
                g.append(expr[i])
                lbg.append(-ca.inf if lb is None else lb + _inner(lb))
                ubg.append(ca.inf if ub is None else ub - _inner(ub))
    return g, lbg, ubg


class PathNLP:
    """Built once per spec; :meth:`solve` runs one IPOPT solve from a start design."""

    def __init__(self, spec: FourbarPathSpec, seed: int = 0, elastic: bool = False):
        self.spec = spec
        self.elastic = elastic
        self.names = list(VARIABLES)
        self.bounds = np.array(spec.bounds_array(), dtype=float)
        self.init = np.array([spec.design_values()[n] for n in self.names], dtype=float)
        self.targets = np.array(spec.targets.points, dtype=float)
        self.branch = BRANCHES[spec.branch]
        n = len(self.targets)
        x = ca.SX.sym("x", len(self.names))
        v = dict(zip(self.names, (x[i] for i in range(len(self.names)))))
        if spec.timed:
            theta = ca.SX(0, 1)
            thetas = [math.radians(a) for a in spec.targets.crank_deg]
        else:
            theta = ca.SX.sym("theta2", n)
            thetas = [theta[i] for i in range(n)]
        sign = ca.SX.sym("direction")
        p = design_parameters(v)
        f = 0
        for th, (tx, ty) in zip(thetas, self.targets):
            px, py = coupler_point(th, p, self.branch)
            f += (px - tx) ** 2 + (py - ty) ** 2
        self.rules = path_rules(spec, v, thetas, sign, spec.solver.samples)
        self.n_theta = theta.numel()
        if not elastic:
            g, lbg, ubg = _rows(self.rules)
            extra, extra_lb = ca.SX(0, 1), []
        else:
            # one slack per rule on all its rows; minimising their sum names the rules that conflict
            extra = ca.SX.sym("slack", len(self.rules))
            extra_lb = [0.0] * len(self.rules)
            g, lbg, ubg = [], [], []
            for k, rule in enumerate(self.rules):
                rows, lo, hi = _rows([rule])
                for expr, a, b in zip(rows, lo, hi):
                    if a > -ca.inf:
                        g.append(expr + extra[k])
                        lbg.append(a)
                        ubg.append(ca.inf)
                    if b < ca.inf:
                        g.append(expr - extra[k])
                        lbg.append(-ca.inf)
                        ubg.append(b)
            f = ca.sum1(extra)
        self.decision = ca.vertcat(x, theta, extra)
        self._lbx = np.concatenate([self.bounds[:, 0], np.full(self.n_theta, THETA_RANGE[0]), extra_lb])
        self._ubx = np.concatenate([self.bounds[:, 1], np.full(self.n_theta, THETA_RANGE[1]),
                                    np.full(len(extra_lb), np.inf)])
        self._lbg, self._ubg = np.array(lbg, dtype=float), np.array(ubg, dtype=float)
        self.g = ca.vertcat(*g)
        self.objective = f
        # tol 1e-12: a zero-error fit must come out below 1e-8 mm^2, not stop at a 1e-8 KKT residual;
        # monotone barrier by default: more starts reach the global optimum than adaptive on the
        # whole-turn synthetic-truth study (starts.py); adaptive is the spec's choice for targets on a
        # short arc (tests/test_bench_fourbar_path.py, partial-arc study); no bound relaxation: an active rule ends inside its limit, not 1e-8 past it
        opts = {"ipopt.print_level": 5, "print_time": False, "ipopt.sb": "yes",
                "ipopt.max_iter": spec.solver.max_iter, "ipopt.tol": 1e-12,
                "ipopt.acceptable_tol": 1e-9, "ipopt.mu_strategy": spec.solver.mu_strategy,
                "ipopt.bound_relax_factor": 0.0}
        self.solver = ca.nlpsol("fourbar_path", "ipopt",
                                {"x": self.decision, "p": sign, "f": f, "g": self.g}, opts)
        self.direction = sign
        self.functions = ca.Function("fg", [self.decision, sign], [f, self.g])
        self.starts = StartMaker(spec, seed)

    def start(self, index: int, x_design: np.ndarray) -> StartPoint:
        """The repaired start design and crank angles IPOPT starts from (see starts.py)."""
        return self.starts(index, x_design)

    def solve(self, index: int, x_design: np.ndarray) -> StartOutcome:
        sp = self.start(index, x_design)
        x0 = np.concatenate([sp.design, sp.theta, np.zeros(len(self.rules) if self.elastic else 0)])
        t0 = time.perf_counter()
        with captured_stdout() as log:
            sol = self.solver(x0=x0, p=sp.sign, lbx=self._lbx, ubx=self._ubx, lbg=self._lbg, ubg=self._ubg)
        wall = time.perf_counter() - t0
        stats = self.solver.stats()
        xs = np.asarray(sol["x"]).ravel()
        design = dict(zip(self.names, (float(a) for a in xs[: len(self.names)])))
        if self.spec.timed:
            crank = [float(a) for a in self.spec.targets.crank_deg]
            direction = "given"
        else:
            crank = [float(a) * DEG for a in xs[len(self.names): len(self.names) + self.n_theta]]
            shift = 360.0 * math.floor(crank[0] / 360.0)       # first angle in [0, 360), the rest follow it
            crank = [a - shift for a in crank]
            direction = "ccw" if sp.sign > 0 else "cw"
        # f at the returned x, not sol["f"]: after a failure (Invalid_Number_Detected...) IPOPT can
        # return a last objective (even 0.0) that belongs to no x it returns
        objective = float(self.functions(xs, sp.sign)[0])
        if not math.isfinite(objective):
            objective = math.inf
        return StartOutcome(index, design, crank, direction, objective, stats["return_status"],
                            bool(stats["success"]), int(stats["iter_count"]), wall, log(), xs)

    def slack_values(self, x: np.ndarray) -> dict[str, float]:
        """Elastic NLP only: each rule's slack at a solution."""
        return {r.name: float(v) for r, v in zip(self.rules, x[-len(self.rules):])}
