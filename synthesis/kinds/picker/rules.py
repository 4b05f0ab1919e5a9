"""The picker double crank's own rules: where a frame pivot may sit (seed 001 eq 7: the crank pivot A lies between
the machine frame and the seedling tray, x_A > 0 in the paper's axes), and how far the clamp may miss the target
points (ours, for objectives other than the miss itself)."""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule


def frame_point_rule(x_a, minimum: float) -> Rule:
    return Rule("frame_point_x_a", x_a, minimum, None, "mm", 10.0, "eq (7): pivot A between frame and tray")


def arc_error_rule(dx, dy, limit: float) -> Rule:
    """The clamp point within ``limit`` (mm) of every target point at its crank angle; ``dx``, ``dy``: the misses
    (clamp point - target, mm) at the target points.  Value: the largest distance; NLP rows: dx^2 + dy^2 <= limit^2
    at each point (smooth where a miss vanishes, as eq (4)'s optimum has it, unlike the distance)."""
    squared = dx * dx + dy * dy
    return Rule("max_arc_error", ca.sqrt(squared), None, limit, "mm", limit, "at the target points",
                nlp_rows=((squared, None, limit * limit),), row_unit="mm^2")
