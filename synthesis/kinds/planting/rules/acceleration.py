"""Acceleration-sign rules of the planting claw (seed 000 §6.2 (4)-(6)).

hold   : from the seedling taken (P3) to soil entry (P4)
throw  : from soil entry (P4) to the lowest point (P5)
release: from the lowest point (P5) to soil exit (P6)
Each requires sign * a_y >= 0 at every sample of its phase (semi-infinite, sampled).
"""

from __future__ import annotations

from synthesis.constraints.base import Rule, not_evaluated

PHASES = {"hold": "P3 to P4", "throw": "P4 to P5", "release": "P5 to P6"}


def acceleration_sign_rule(phase: str, ay_samples, sign: int, scale: float, missing: str | None = None) -> Rule:
    """sign * a_y >= 0 over the phase; ``ay_samples`` in mm/s^2, ``scale`` a typical |a_y|."""
    name = f"accel_{phase}"
    where = f"{PHASES[phase]}, a_y {'>' if sign > 0 else '<'} 0"
    if missing:
        return not_evaluated(name, 0.0, None, "mm/s^2", where, missing)
    return Rule(name, sign * ay_samples, 0.0, None, "mm/s^2", scale, where)
