"""Loop closure: the four-bar assembles at a crank angle when |r3 - r4| <= d <= r3 + r4, d = |O'A|.

Trace: d^2 = |O'A|^2 at each crank angle (the kind's kinematics computes it).
Value (records): the smallest of  d - |r3 - r4|  and  r3 + r4 - d  over the given crank angles, mm.
Optimiser rows: the equivalent polynomials  d^2 - (r3 - r4)^2 >= 0,  (r3 + r4)^2 - d^2 >= 0  (mm^2),
smooth everywhere.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule, stack


def assembly_rule(d2, r3, r4, where: str) -> Rule:
    """Closure at every crank angle whose squared diagonal |O'A|^2 is in ``d2`` (mm^2): a list of expressions, or
    on numbers (check, the fine-grid re-check: thousands of samples) a numpy vector, evaluated at once -- the same
    values in the same order, and one vector row per side."""
    if isinstance(d2, np.ndarray):
        d = np.sqrt(np.fmax(d2, 0.0))        # fmax as ca.fmax: a NaN sample reads 0, as in the list form
        margins = np.column_stack([d - abs(r3 - r4), r3 + r4 - d]).ravel()
        sides = ((d2 - (r3 - r4) ** 2, 0.0, None), ((r3 + r4) ** 2 - d2, 0.0, None))
        return Rule("assembly", margins, 0.0, None, "mm", 1.0, where, nlp_rows=sides, row_unit="mm^2")
    values, rows = [], []
    for q in d2:
        d = ca.sqrt(ca.fmax(q, 0.0))        # d^2 >= (r1 - r2)^2 >= 0; fmax only guards the last digit
        values += [d - ca.fabs(r3 - r4), r3 + r4 - d]
        rows += [(q - (r3 - r4) ** 2, 0.0, None), ((r3 + r4) ** 2 - q, 0.0, None)]
    return Rule("assembly", stack(values), 0.0, None, "mm", 1.0, where, nlp_rows=tuple(rows), row_unit="mm^2")


def assembly_extremes_rule(d2_shortest: list, d2_longest: list, r3, r4, where: str) -> Rule:
    """Closure over stretches of the crank's motion, each given by its shortest and its longest squared diagonal:
    the loop closes all along a stretch iff  d_shortest >= |r3 - r4|  and  d_longest <= r3 + r4, so each bound is
    a row only where it can bind (one row each, never the same row twice)."""
    values, rows = [], []
    for q in d2_shortest:
        values.append(ca.sqrt(ca.fmax(q, 0.0)) - ca.fabs(r3 - r4))
        rows.append((q - (r3 - r4) ** 2, 0.0, None))
    for q in d2_longest:
        values.append(r3 + r4 - ca.sqrt(ca.fmax(q, 0.0)))
        rows.append(((r3 + r4) ** 2 - q, 0.0, None))
    return Rule("assembly", stack(values), 0.0, None, "mm", 1.0, where, nlp_rows=tuple(rows), row_unit="mm^2")
