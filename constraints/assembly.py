"""Loop closure: the four-bar assembles at a crank angle when |r3 - r4| <= d <= r3 + r4, d = |O'A|.

Value (records): the smallest of  d - |r3 - r4|  and  r3 + r4 - d  over the given crank angles, mm.
Optimiser rows: the equivalent polynomials  d^2 - (r3 - r4)^2 >= 0,  (r3 + r4)^2 - d^2 >= 0  (mm^2),
smooth everywhere, with d^2 = r1^2 + r2^2 - 2 r1 r2 cos theta2.
"""

from __future__ import annotations

import casadi as ca

from constraints.base import Rule
from synthesis.kinematics.coupler_point import closure_slacks
from synthesis.kinematics.fourbar import diagonal_sq


def assembly_rule(thetas: list, r1, r2, r3, r4, where: str) -> Rule:
    """Closure at every crank angle of ``thetas`` (rad)."""
    values, rows = [], []
    for th in thetas:
        d = ca.sqrt(diagonal_sq(th, r1, r2))
        values += [d - ca.fabs(r3 - r4), r3 + r4 - d]
        rows += [(s, 0.0, None) for s in closure_slacks(th, r1, r2, r3, r4)]
    return Rule("assembly", ca.vertcat(*values), 0.0, None, "mm", 1.0, where, nlp_rows=tuple(rows))
