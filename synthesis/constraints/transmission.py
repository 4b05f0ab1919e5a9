"""Transmission angle (coupler AB to rocker O'B) over a full crank turn: min >= lo and max <= hi."""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated


def transmission_rules(mu_deg_samples, bounds: tuple, missing: str | None = None) -> list[Rule]:
    lo, hi = bounds
    if missing:
        return [not_evaluated("transmission_angle_min", lo, None, "deg", "over a turn", missing),
                not_evaluated("transmission_angle_max", None, hi, "deg", "over a turn", missing)]
    return [Rule("transmission_angle_min", mu_deg_samples, lo, None, "deg", 10.0, "over a turn"),
            Rule("transmission_angle_max", mu_deg_samples, None, hi, "deg", 10.0, "over a turn")]


def acute_transmission_rule(mu_deg_samples, minimum: float, where: str, name: str = "min_transmission_angle",
                            missing: str | None = None) -> Rule:
    """min over the samples of min(mu, 180 - mu) >= minimum: the transmission angle as an acute angle.

    Value: the worst acute angle.  NLP rows: minimum <= mu <= 180 - minimum at every sample (smooth).
    """
    if missing:
        return not_evaluated(name, minimum, None, "deg", where, missing)
    acute = ca.fmin(mu_deg_samples, 180.0 - mu_deg_samples)
    return Rule(name, acute, minimum, None, "deg", 10.0, where,
                nlp_rows=((mu_deg_samples, minimum, 180.0 - minimum),))
