"""Key-pose rules: a named pose the claw must pass through -- its tip within a distance of a target point and, if
the pose asks one, its attitude (the claw's direction) within an angle of a target direction.

Shared by the kinds whose spec has a ``[key_poses]`` table (the rotary planetary transplanter, the four-bar planting
arm); each kind says where a pose is read (a crank or carrier angle, found or prescribed) and which line on its
mechanism the claw's attitude is.  Rules ``pose_<name>`` (tip miss, mm) and ``pose_<name>_attitude`` (wrapped
attitude miss, deg), on floats (check, re-check) or CasADi symbols (the NLP).
"""

from __future__ import annotations

import math

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated

RAD = math.pi / 180.0
DEG = 180.0 / math.pi


def attitude_miss_deg(attitude_deg, target_deg: float):
    """attitude - target wrapped into (-180, 180], deg: a miss of 350 deg is one of -10 (smooth but where the miss
    is half a turn)."""
    d = attitude_deg - target_deg
    return ca.atan2(ca.sin(d * RAD), ca.cos(d * RAD)) * DEG


def nearest_row(dx, dy, rate_x, rate_y):
    """(tip - target) . d tip / d angle: zero where the tip is nearest its target along the path, the row that pins
    a free pose's angle (the check reads the pose there too), mm^2/rad."""
    return dx * rate_x + dy * rate_y


def pose_tip_rule(name: str, dx, dy, tolerance: float, where: str | None = None, missing: str | None = None) -> Rule:
    """Tip within ``tolerance`` of the pose's point: (dx, dy) the tip minus the target, mm; the NLP row is the squared
    distance (smooth where the tip is on its target)."""
    where = f"key pose {name}" if where is None else where
    if missing:
        return not_evaluated(f"pose_{name}", None, tolerance, "mm", where, missing)
    return Rule(f"pose_{name}", ca.sqrt(dx * dx + dy * dy), None, tolerance, "mm", 1.0, where,
                nlp_rows=((dx * dx + dy * dy, None, tolerance * tolerance),), row_unit="mm^2")


def pose_attitude_rule(name: str, attitude_miss, tolerance: float, where: str | None = None,
                       missing: str | None = None) -> Rule:
    """The claw's attitude within ``tolerance`` of the pose's (``attitude_miss`` already wrapped into (-180, 180],
    :func:`attitude_miss_deg`), deg."""
    where = f"key pose {name}" if where is None else where
    if missing:
        return not_evaluated(f"pose_{name}_attitude", -tolerance, tolerance, "deg", where, missing)
    return Rule(f"pose_{name}_attitude", attitude_miss, -tolerance, tolerance, "deg", 1.0, where)


def pose_rules(name: str, dx, dy, tolerance: float, attitude_miss=None, attitude_tolerance: float = 0.0
               ) -> list[Rule]:
    """Tip within ``tolerance`` of the pose (the NLP row: squared distance) and, if the pose gives one, the claw's
    attitude within ``attitude_tolerance`` (``attitude_miss`` already wrapped into (-180, 180])."""
    rules = [pose_tip_rule(name, dx, dy, tolerance)]
    if attitude_miss is not None:
        rules.append(pose_attitude_rule(name, attitude_miss, attitude_tolerance))
    return rules
