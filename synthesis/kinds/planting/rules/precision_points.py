"""Precision-point rules of the planting claw (seed 000 §6.2 (1)-(2)).

P1, P2, P3: where the claw tip crosses the seedling top, the seedbed top and the seedbed bottom
(machine frame: the tray moves with the machine).  P4, P6: soil entry and exit, on one soil line.
"""

from __future__ import annotations

import math

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated


def distance(p, q):
    """|pq| for points given as (x, y) pairs of floats or symbols."""
    return ca.sqrt((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2)


def turn_angle_deg(p1, p2, p3):
    """Angle between the directions P1->P2 and P2->P3 (deg): 0 when the three are collinear."""
    ax, ay = p2[0] - p1[0], p2[1] - p1[1]
    bx, by = p3[0] - p2[0], p3[1] - p2[1]
    return ca.atan2(ca.fabs(ax * by - ay * bx), ax * bx + ay * by) * (180.0 / math.pi)


def seedbed_rules(p1, p2, p3, p1p3: tuple, p2p3: tuple, collinearity: float, missing: str | None = None):
    """P1P3 in [lo, hi], P2P3 in [lo, hi], the path turns by at most ``collinearity`` deg at P2."""
    specs = [("p1p3_distance", *p1p3, "mm", 5.0), ("p2p3_distance", *p2p3, "mm", 1.0),
             ("p1p2p3_collinearity", None, collinearity, "deg", collinearity)]
    if missing:
        return [not_evaluated(n, lo, hi, u, "machine frame", missing) for n, lo, hi, u, _ in specs]
    exprs = [distance(p1, p3), distance(p2, p3), turn_angle_deg(p1, p2, p3)]
    return [Rule(n, e, lo, hi, u, s, "machine frame") for (n, lo, hi, u, s), e in zip(specs, exprs)]


def p4p6_rule(p4_ground, p6_ground, minimum: float, missing: str | None = None):
    """Ground-frame distance P4-P6 >= minimum, so the rising claw clears the planted seedling."""
    if missing:
        return not_evaluated("p4p6_distance", minimum, None, "mm", "ground frame", missing)
    return Rule("p4p6_distance", distance(p4_ground, p6_ground), minimum, None, "mm", 10.0, "ground frame")
