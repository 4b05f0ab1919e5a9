"""The comb-finger problem: r, e, alpha, omega, b, rho maximising the combing angle theta (eq 21) subject to the
rules of :func:`synthesis.kinds.comb_finger.check.rules_of` on CasADi symbols (exact AD); the clearance to the
other unit is sampled over the finger's turn."""

from __future__ import annotations

import math

import casadi as ca

from synthesis.core.declared import Declared, binding, named
from synthesis.core.kind import Setting
from synthesis.core.problem import ObjectiveParts, Operating, Problem
from synthesis.kinds.comb_finger.check import rules_of, trace
from synthesis.kinds.comb_finger.spec import NAMES
from synthesis.spec.common import design_box
from synthesis.spec.design_info import units_of

#: the objective is -theta / THETA_SCALE (deg): unit-sized gradients
THETA_SCALE = 10.0


def problem(setting: Setting) -> Declared:
    """The problem of one spec; the reported objective is theta (deg) at the spec's machine speed."""
    spec = setting.spec
    bounds, init = design_box(spec.variables(), NAMES)
    x = ca.SX.sym("x", len(NAMES))
    # the tolerance analysis's build only: both operating conditions symbols, so its report shows d rule /
    # d condition for them (0: the machine speed enters the combing angle, the objective, and the row spacing
    # only unit_within_row's limit, a number -- no rule's value reads either)
    op = spec.operation
    operating = ([Operating("machine_speed", ca.SX.sym("machine_speed"), op.machine_speed, "m/s"),
                  Operating("row_spacing", ca.SX.sym("row_spacing"), op.row_spacing, "mm")]
                 if setting.operating_symbols else [])
    tr = trace(spec, {n: x[i] for i, n in enumerate(NAMES)}, spec.solver.turn_samples,
               operating[0].symbol if operating else None)
    theta_deg = tr.theta * (180.0 / math.pi)
    # the reported combing angle at the spec's machine speed (free of the analysis's symbol)
    shown = ca.substitute(theta_deg, operating[0].symbol, ca.SX(op.machine_speed)) if operating else theta_deg
    theta = ca.Function("theta", [x], [shown])
    declared = Problem("comb_finger", x, bounds[:, 0], bounds[:, 1], [], rules_of(spec, tr),
                       ObjectiveParts(f=-theta_deg / THETA_SCALE), ipopt="tight", max_iter=spec.solver.max_iter,
                       x_units=units_of(spec, NAMES), objective_unit="deg", operating=operating)
    return Declared(declared, list(NAMES), bounds, init, design=named(NAMES),
                    objective=lambda out, design, elastic: float(theta(out.x[:len(NAMES)])),
                    details=lambda out, compiled: binding(out, compiled, NAMES, bounds, 1e-6))
