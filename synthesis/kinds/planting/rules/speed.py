"""Claw speed at P2 (seed 000 §6.2 (3)): the claw cuts the seedbed, so |v(P2)| >= 1 m/s.

Relative to the seedbed, i.e. the machine-frame velocity (the tray travels with the machine).
"""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated


def p2_speed_rule(vx, vy, minimum_m_s: float, missing: str | None = None) -> Rule:
    """vx, vy in mm/s; the rule reads in m/s."""
    if missing:
        return not_evaluated("p2_speed", minimum_m_s, None, "m/s", "at P2, machine frame", missing)
    speed = ca.sqrt(vx * vx + vy * vy) / 1000.0
    return Rule("p2_speed", speed, minimum_m_s, None, "m/s", 1.0, "at P2, machine frame")
