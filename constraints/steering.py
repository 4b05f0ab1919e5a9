"""Steering-trapezoid rules (seed 002 Table 12): tie-rod transmission angles and steering-arm length."""

from __future__ import annotations

from constraints.base import Rule, not_evaluated

WHERE_TRANSMISSION = "tie rod to both steering arms, inside lock 0-{:g} deg"


def tie_rod_transmission_rule(mu_deg_samples, minimum: float, max_lock: float, missing: str | None = None) -> Rule:
    """minimum <= mu <= 180 - minimum at every sampled lock, for the angle between the tie rod and each arm
    (signed: the straight-ahead assembly has mu in (0, 180); a negative mu is the other assembly)."""
    where = WHERE_TRANSMISSION.format(max_lock)
    if missing:
        return not_evaluated("tie_rod_transmission_angle", minimum, 180.0 - minimum, "deg", where, missing)
    return Rule("tie_rod_transmission_angle", mu_deg_samples, minimum, 180.0 - minimum, "deg", 10.0, where)


def arm_length_rule(r, bounds: tuple) -> Rule:
    """lo <= r <= hi: short arms need large steering forces, long ones do not fit inside the wheel."""
    return Rule("steering_arm_length", r, bounds[0], bounds[1], "mm", 10.0, "both arms")
