"""Transmission angle (coupler AB to rocker O'B) over a full crank turn: min >= lo and max <= hi."""

from __future__ import annotations

from constraints.base import Rule, not_evaluated


def transmission_rules(mu_deg_samples, bounds: tuple, missing: str | None = None) -> list[Rule]:
    lo, hi = bounds
    if missing:
        return [not_evaluated("transmission_angle_min", lo, None, "deg", "over a turn", missing),
                not_evaluated("transmission_angle_max", None, hi, "deg", "over a turn", missing)]
    return [Rule("transmission_angle_min", mu_deg_samples, lo, None, "deg", 10.0, "over a turn"),
            Rule("transmission_angle_max", mu_deg_samples, None, hi, "deg", 10.0, "over a turn")]
