"""Quick-return rules of a crank-rocker (seed 001 §2.1.3): time ratio K and rocker swing psi.

Both are read off the two extreme positions of the simulated rocker (crank angles phi_a, phi_b where
d beta / d phi = 0), never the textbook dead-centre formulas.  Given designs are checked within a
tolerance (printed lengths are rounded); the optimiser gets the exact requirement as an equality.
"""

from __future__ import annotations

import math

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated


def time_ratio_rule(stroke, required: float, tolerance: float, missing: str | None = None) -> Rule:
    """K = (2 pi - stroke) / stroke for the crank angle ``stroke`` (rad) of the quick stroke.

    The NLP row is the same expression set equal to the required K (the quick stroke is then
    2 pi / (1 + K)), in the rule's own unit so an elastic slack means the same thing in every row.
    """
    limit = (required - tolerance, required + tolerance)
    where = "rocker extremes, crank at constant speed"
    if missing:
        return not_evaluated("time_ratio", *limit, "-", where, missing)
    value = (2.0 * math.pi - stroke) / stroke
    return Rule("time_ratio", value, *limit, "-", 0.05, where, nlp_rows=((value, required, required),))


def rocker_swing_rule(u, w, rocker_length, required_deg: float, tolerance_deg: float,
                      missing: str | None = None) -> Rule:
    """Swing = angle between the rocker vectors u, w (A -> E) at the two extremes, deg.

    NLP row: 2 atan2(|u - w|, |u + w|) = psi in degrees (|u| = |w| = l9: the half-angle's sine and
    cosine, times 2 l9).  Smooth for swings inside (0, 180) deg and defined at every iterate, unlike
    acos(u.w / l9^2), whose argument leaves [-1, 1] by rounding near 180 deg (NaN) and whose
    derivative is infinite there.
    """
    limit = (required_deg - tolerance_deg, required_deg + tolerance_deg)
    if missing:
        return not_evaluated("rocker_swing", *limit, "deg", "between the rocker extremes", missing)
    dot = u[0] * w[0] + u[1] * w[1]
    cross = u[0] * w[1] - u[1] * w[0]
    value = ca.atan2(ca.fabs(cross), dot) * (180.0 / math.pi)
    chord = ca.sqrt((u[0] - w[0]) ** 2 + (u[1] - w[1]) ** 2)          # 2 l9 sin(psi / 2)
    span = ca.sqrt((u[0] + w[0]) ** 2 + (u[1] + w[1]) ** 2)           # 2 l9 cos(psi / 2)
    row = (2.0 * ca.atan2(chord, span) * (180.0 / math.pi), required_deg, required_deg)
    return Rule("rocker_swing", value, *limit, "deg", 5.0, "between the rocker extremes", nlp_rows=(row,))
