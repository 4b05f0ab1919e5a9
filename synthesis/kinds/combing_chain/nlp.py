"""The combing-chain NLP: chain speed(s) (and the gear switch speed) so that every plant of the beta range
is combed into the delta window at every machine speed, on the solver's (beta, V_s) grid.

The rows are :func:`synthesis.kinds.combing_chain.check.rules_of` on CasADi symbols (eq 12 with exact AD);
objectives: the largest smallest margin to the window (an epigraph variable), or the slowest chains.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from synthesis.kinds.combing_chain import geometry as g
from synthesis.kinds.combing_chain.check import rules_of, trace
from synthesis.core.ipopt import CompiledNLP
from synthesis.core.kind import KindNLP
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import ObjectiveParts, Operating, Problem, operating_symbols_wanted
from synthesis.errors import SpecError
from synthesis.kinds.combing_chain.spec import CombingChainSpec
from synthesis.spec.design_info import units_of
from synthesis.spec.common import bounds_of, is_free, value_of


def require_window(spec: CombingChainSpec) -> tuple[float, float] | None:
    """The window a solve needs; SpecError (exit 2) when it is missing or no chain speed reaches it at all.
    A spec with nothing free needs none: the driver then says that nothing is free to optimise."""
    window = spec.requirements.window
    if window is None:
        if not any(is_free(v) for v in spec.variables().values()):
            return None
        raise SpecError(f"{spec.kind}: solve needs requirements.window = [lo, hi] (deg), the plant angles "
                        f"acceptable before the cut")
    c = spec.chain
    inf, sup = g.delta_limits(c.h, c.theta, c.e)
    lo, hi = window
    if hi <= inf or lo >= sup:
        raise SpecError(f"{spec.kind}.requirements.window: [{lo:g}, {hi:g}] deg: no chain speed reaches it: with "
                        f"h = {c.h:g} mm, theta = {c.theta:g} deg, e = {c.e:g} mm every plant stands between "
                        f"theta = {inf:.4g} deg (V_r -> infinity) and 180 - atan(h/e) = {sup:.4g} deg (V_r -> 0) "
                        f"before the cut")
    return lo, hi


class CombingChainNLP(KindNLP):
    """Built once per spec; :meth:`solve` runs IPOPT from one start (chain speeds, switch speed)."""

    def __init__(self, spec: CombingChainSpec, elastic: bool = False):
        self.spec = spec
        window = require_window(spec)
        variables = spec.variables()
        self.names = list(variables)
        self.bounds = np.array([bounds_of(v) for v in variables.values()], dtype=float)
        self.init = np.array([value_of(v) for v in variables.values()], dtype=float)
        x = ca.SX.sym("x", len(self.names))
        design = {n: x[i] for i, n in enumerate(self.names)}
        # the tolerance analysis's build only: the ends of the operating ranges (machine speed, initial plant
        # angle) symbols, for d rule / d end; a solve's NLP writes them as the numbers it always did
        op = spec.operation
        self.operating = ([Operating(f"{name}_{end}", ca.SX.sym(f"{name}_{end}"), getattr(op, name)[i], unit)
                           for name, unit in (("machine_speed", "m/s"), ("plant_angle", "deg"))
                           for i, end in enumerate(("lo", "hi"))] if operating_symbols_wanted() else [])
        ends = [o.symbol for o in self.operating]
        tr = trace(spec, design, spec.solver.beta_samples, spec.solver.speed_samples,
                   {"machine_speed": (ends[0], ends[1]), "plant_angle": (ends[2], ends[3])} if ends else None)
        rules = rules_of(spec, tr)
        speeds = [design[n] for n in spec.speed_names()]
        self.margin_objective = spec.objective.name == "max_window_margin" and window is not None
        if self.margin_objective:
            lo, hi = window
            m = ca.SX.sym("window_margin")
            deltas = ca.vertcat(*[d for gt in tr.gears for row in gt.delta for d in row])
            objective = ObjectiveParts(f=-m, extra=m, extra_lb=[-180.0], extra_ub=[180.0], extra_init=[0.0],
                                       rows=[(deltas - lo - m, 0.0, None), (hi - deltas - m, 0.0, None)],
                                       extra_units=["deg"], row_units=["deg", "deg"])
        else:
            objective = ObjectiveParts(f=ca.sum1(ca.vertcat(*speeds)))
        self.problem = Problem("combing_chain", x, self.bounds[:, 0], self.bounds[:, 1], [], rules, objective,
                               ipopt="tight", x_units=units_of(spec, self.names),
                               objective_unit="deg" if self.margin_objective else "m/s", max_iter=spec.solver.max_iter,
                               operating=self.operating)
        self.compiled = CompiledNLP(self.problem, elastic)

    def solve(self, start: int, x0) -> StartOutcome:
        out = self.compiled.solve(start, x0)
        n = len(self.names)
        design = {name: float(v) for name, v in zip(self.names, out.x[:n])}
        if self.margin_objective and not self.compiled.elastic:
            objective = float(out.x[n])
        else:
            objective = sum(design[s] for s in self.spec.speed_names())
        binding = [] if self.compiled.elastic else self.compiled.active_rules(out)
        at_bound = [name for name, v, (a, b) in zip(self.names, out.x[:n], self.bounds)
                    if b > a and min(v - a, b - v) <= 1e-7 * max(1.0, abs(v))]
        return StartOutcome.of(out, design, objective, binding_rules=binding, variables_at_bounds=at_bound)
