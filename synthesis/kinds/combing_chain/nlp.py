"""The combing-chain problem: chain speed(s) (and the gear switch speed) so that every plant of the beta range
is combed into the delta window at every machine speed, on the solver's (beta, V_s) grid.

The rows are :func:`synthesis.kinds.combing_chain.check.rules_of` on CasADi symbols (eq 12 with exact AD);
objectives: the largest smallest margin to the window (an epigraph variable), or the slowest chains.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from synthesis.kinds.combing_chain import geometry as g
from synthesis.kinds.combing_chain.check import rules_of, trace
from synthesis.core.declared import Declared, binding, named
from synthesis.core.kind import Setting
from synthesis.core.problem import ObjectiveParts, Operating, Problem
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
    if len(c.speeds) == 2 and c.switch_speed is None:
        # each gear would be held to the whole machine-speed range: the same rows twice, the second gear of no use
        raise SpecError(f"{spec.kind}.chain.switch_speed: solve of two chain gears needs the machine speed at which "
                        f"gear 2 takes over (a value or {{init, bounds}}, m/s); without it every gear must serve the "
                        f"whole range, which `agrisynth check` evaluates")
    inf, sup = g.delta_limits(c.h, c.theta, c.e)
    lo, hi = window
    if hi <= inf or lo >= sup:
        raise SpecError(f"{spec.kind}.requirements.window: [{lo:g}, {hi:g}] deg: no chain speed reaches it: with "
                        f"h = {c.h:g} mm, theta = {c.theta:g} deg, e = {c.e:g} mm every plant stands between "
                        f"theta = {inf:.4g} deg (V_r -> infinity) and 180 - atan(h/e) = {sup:.4g} deg (V_r -> 0) "
                        f"before the cut")
    return lo, hi


def problem(setting: Setting) -> Declared:
    """The problem of one spec; the reported objective is the window margin (deg) or the chains' speeds summed."""
    spec = setting.spec
    window = require_window(spec)
    variables = spec.variables()
    names = list(variables)
    bounds = np.array([bounds_of(v) for v in variables.values()], dtype=float)
    init = np.array([value_of(v) for v in variables.values()], dtype=float)
    x = ca.SX.sym("x", len(names))
    design = {n: x[i] for i, n in enumerate(names)}
    # the tolerance analysis's build only: the ends of the operating ranges (machine speed, initial plant
    # angle) symbols, for d rule / d end; a solve's NLP writes them as the numbers it always did
    op = spec.operation
    operating = ([Operating(f"{name}_{end}", ca.SX.sym(f"{name}_{end}"), getattr(op, name)[i], unit)
                  for name, unit in (("machine_speed", "m/s"), ("plant_angle", "deg"))
                  for i, end in enumerate(("lo", "hi"))] if setting.operating_symbols else [])
    ends = [o.symbol for o in operating]
    tr = trace(spec, design, spec.solver.beta_samples, spec.solver.speed_samples,
               {"machine_speed": (ends[0], ends[1]), "plant_angle": (ends[2], ends[3])} if ends else None)
    rules = rules_of(spec, tr)
    speeds = [design[n] for n in spec.speed_names()]
    margin_objective = spec.objective.name == "max_window_margin" and window is not None
    if margin_objective and window is not None:       # (margin_objective says it is)
        lo, hi = window
        m = ca.SX.sym("window_margin")
        deltas = ca.vertcat(*[d for gt in tr.gears for row in gt.delta for d in row])
        objective = ObjectiveParts(f=-m, extra=m, extra_lb=[-180.0], extra_ub=[180.0], extra_init=[0.0],
                                   rows=[(deltas - lo - m, 0.0, None), (hi - deltas - m, 0.0, None)],
                                   extra_units=["deg"], row_units=["deg", "deg"])
    else:
        objective = ObjectiveParts(f=ca.sum1(ca.vertcat(*speeds)))
    declared = Problem("combing_chain", x, bounds[:, 0], bounds[:, 1], [], rules, objective,
                       ipopt="tight", x_units=units_of(spec, names),
                       objective_unit="deg" if margin_objective else "m/s", max_iter=spec.solver.max_iter,
                       operating=operating)

    def reported(out, design: dict, elastic: bool) -> float:
        if margin_objective and not elastic:
            return float(out.x[len(names)])
        return sum(design[s] for s in spec.speed_names())

    return Declared(declared, names, bounds, init, design=named(names), objective=reported,
                    details=lambda out, compiled: binding(out, compiled, names, bounds, 1e-7))
