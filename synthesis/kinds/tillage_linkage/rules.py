"""Tillage-linkage rules (seed 002 §四.2): working depth, plant lift, rearward motion in the soil, the bar's
angle to the roller slot and its engagement in the rollers."""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated


def working_depth_rule(depth_mm, bounds: tuple) -> Rule:
    """lo <= depth of the tool tip's lowest point below the ground <= hi (mm): deep enough to cut under the
    pods (5-8 cm in sandy soil), not past 12 cm where the wheels' slip grows sharply (seed 002 §四.2)."""
    return Rule("working_depth", depth_mm, bounds[0], bounds[1], "mm", 10.0, "lowest point of D")


def lift_height_rule(lift_mm, minimum: float) -> Rule:
    """The highest point of D above the ground >= minimum (mm): the tool carries the plants up that far."""
    return Rule("lift_height", lift_mm, minimum, None, "mm", 10.0, "highest point of D")


def rearward_in_soil_rule(vx_ground_m_s, min_rearward: float, missing: str | None = None) -> Rule:
    """The tool's ground-frame speed in the travel direction <= -min_rearward (m/s) at every sampled crank
    angle while D is below the ground: it moves backwards relative to the soil (it lifts, it does not push)."""
    where = "while D is in the soil, ground frame"
    if missing:
        return not_evaluated("rearward_in_soil", None, -min_rearward, "m/s", where, missing)
    return Rule("rearward_in_soil", vx_ground_m_s, None, -min_rearward, "m/s", 0.1, where)


def bar_slot_angle_rule(a, b, maximum_deg: float) -> Rule:
    """The bar's largest angle to the roller slot (aligned with AC), asin(a / b) in deg, <= maximum: beyond it
    the bar jams between the rollers.  Needs a < b (the spec guarantees it)."""
    return Rule("bar_slot_angle", ca.asin(a / b) * (180.0 / ca.pi), None, maximum_deg, "deg", 5.0, "over a turn")


def bar_engagement_rule(a, b, c, minimum: float) -> Rule:
    """c - (a + b) >= minimum (mm): the bar still reaches past the rollers when B is farthest from C
    (|CB| = a + b), so it never leaves the roller pair and D stays beyond C."""
    return Rule("bar_engagement", c - (a + b), minimum, None, "mm", 10.0, "B farthest from C")
