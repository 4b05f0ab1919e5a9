"""The comb-finger NLP: r, e, alpha, omega, b, rho maximising the combing angle theta (eq 21) subject to the
rules of :func:`synthesis.kinds.comb_finger.check.rules_of` on CasADi symbols (exact AD); the clearance to the
other unit is sampled over the finger's turn."""

from __future__ import annotations

import math

import casadi as ca

from synthesis.kinds.comb_finger.check import rules_of, trace
from synthesis.core.ipopt import CompiledNLP
from synthesis.core.kind import KindNLP
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import ObjectiveParts, Operating, Problem, operating_symbols_wanted
from synthesis.spec.design_info import units_of
from synthesis.kinds.comb_finger.spec import NAMES, CombFingerSpec
from synthesis.spec.common import design_box

#: the objective is -theta / THETA_SCALE (deg): unit-sized gradients
THETA_SCALE = 10.0


class CombFingerNLP(KindNLP):
    """Built once per spec; :meth:`solve` runs IPOPT from one start."""

    def __init__(self, spec: CombFingerSpec, elastic: bool = False):
        self.spec = spec
        variables = spec.variables()
        self.names = list(NAMES)
        self.bounds, self.init = design_box(variables, NAMES)
        x = ca.SX.sym("x", len(NAMES))
        # the tolerance analysis's build only: both operating conditions symbols, so its report shows d rule /
        # d condition for them (0: the machine speed enters the combing angle, the objective, and the row spacing
        # only unit_within_row's limit, a number -- no rule's value reads either)
        op = spec.operation
        self.operating = ([Operating("machine_speed", ca.SX.sym("machine_speed"), op.machine_speed, "m/s"),
                           Operating("row_spacing", ca.SX.sym("row_spacing"), op.row_spacing, "mm")]
                          if operating_symbols_wanted() else [])
        tr = trace(spec, {n: x[i] for i, n in enumerate(NAMES)}, spec.solver.turn_samples,
                   self.operating[0].symbol if self.operating else None)
        theta_deg = tr.theta * (180.0 / math.pi)
        # the reported combing angle at the spec's machine speed (free of the analysis's symbol)
        shown = (ca.substitute(theta_deg, self.operating[0].symbol, ca.SX(op.machine_speed)) if self.operating
                 else theta_deg)
        self.theta = ca.Function("theta", [x], [shown])
        self.problem = Problem("comb_finger", x, self.bounds[:, 0], self.bounds[:, 1], [], rules_of(spec, tr),
                               ObjectiveParts(f=-theta_deg / THETA_SCALE), ipopt="tight", max_iter=spec.solver.max_iter,
                               x_units=units_of(spec, NAMES), objective_unit="deg", operating=self.operating)
        self.compiled = CompiledNLP(self.problem, elastic)

    def solve(self, start: int, x0) -> StartOutcome:
        out = self.compiled.solve(start, x0)
        xs = out.x[:len(NAMES)]
        design = {n: float(v) for n, v in zip(NAMES, xs)}
        binding = [] if self.compiled.elastic else self.compiled.active_rules(out)
        at_bound = [n for n, v, (a, b) in zip(NAMES, xs, self.bounds) if b > a and min(v - a, b - v) <= 1e-6 * max(1.0, abs(v))]
        return StartOutcome.of(out, design, float(self.theta(xs)), binding_rules=binding, variables_at_bounds=at_bound)
