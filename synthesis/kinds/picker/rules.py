"""Where a frame pivot may sit (seed 001 eq 7): the picker's crank pivot A lies between the machine
frame and the seedling tray, x_A > 0 in the paper's axes."""

from __future__ import annotations

from constraints.base import Rule


def frame_point_rule(x_a, minimum: float) -> Rule:
    return Rule("frame_point_x_a", x_a, minimum, None, "mm", 10.0, "eq (7): pivot A between frame and tray")
