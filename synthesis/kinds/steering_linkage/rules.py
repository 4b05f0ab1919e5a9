"""Steering-trapezoid rules (seed 002 Table 12): tie-rod transmission angles and steering-arm length."""

from __future__ import annotations

import numpy as np

from synthesis.constraints.base import Rule, not_evaluated, symbolic

WHERE_TRANSMISSION = "tie rod to both steering arms, inside lock 0-{:g} deg"


def tie_rod_transmission_rule(mu_deg_samples, minimum: float, max_lock: float, missing: str | None = None) -> Rule:
    """minimum <= mu <= 180 - minimum at every sampled lock, for the angle between the tie rod and each arm
    (the straight-ahead assembly has mu in (0, 180); on numbers the samples follow each arm continuously from
    lock 0, so an arm swung through its line with the tie rod reads beyond 180 or below 0 and fails)."""
    where = WHERE_TRANSMISSION.format(max_lock)
    if missing:
        return not_evaluated("tie_rod_transmission_angle", minimum, 180.0 - minimum, "deg", where, missing)
    return Rule("tie_rod_transmission_angle", mu_deg_samples, minimum, 180.0 - minimum, "deg", 10.0, where,
                note=_through_the_line(mu_deg_samples))


def _through_the_line(mu_deg_samples) -> str | None:
    """On numbers, a caveat for samples outside 0-180 deg (a trace followed continuously from lock 0): there the tie
    rod has swung through its line with that arm, which a bare 184.96 deg does not say."""
    if symbolic([mu_deg_samples]):
        return None
    mu = np.atleast_1d(np.asarray(mu_deg_samples, dtype=float)).ravel()
    past = (mu < 0.0) | (mu > 180.0)
    if not past.any():
        return None
    return (f"{int(past.sum())} of {mu.size} samples lie outside 0-180 deg: there the tie rod has swung through "
            f"its line with the arm (a dead centre of that arm)")


def arm_length_rule(r, bounds: tuple) -> Rule:
    """lo <= r <= hi: short arms need large steering forces, long ones do not fit inside the wheel."""
    return Rule("steering_arm_length", r, bounds[0], bounds[1], "mm", 10.0, "both arms")
