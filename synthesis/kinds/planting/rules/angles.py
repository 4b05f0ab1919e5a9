"""Entry angle (seed 000 §6.2 (7)): direction of the claw's ground-frame velocity at soil entry P4.

Value: the angle of (vx_g, vy) to the horizontal, atan2(|vy|, |vx_g|) in [0, 90] deg; >= 80 deg
means the claw enters within 10 deg of vertical.  That is not smooth where vx_g = 0 (exactly the
ideal), so the optimiser gets the equivalent smooth row  min <= atan2(-vy, vx_g) <= 180 - min
(the direction measured from +X; vy < 0 at entry), in degrees like the rule itself.
"""

from __future__ import annotations

import math

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated


def entry_angle_rule(vx_ground, vy, minimum_deg: float, missing: str | None = None) -> Rule:
    if missing:
        return not_evaluated("entry_angle", minimum_deg, None, "deg", "at P4, ground frame", missing)
    angle = ca.atan2(ca.fabs(vy), ca.fabs(vx_ground)) * (180.0 / math.pi)
    rows = ((ca.atan2(-vy, vx_ground) * (180.0 / math.pi), minimum_deg, 180.0 - minimum_deg),)
    return Rule("entry_angle", angle, minimum_deg, None, "deg", 10.0, "at P4, ground frame", nlp_rows=rows)
