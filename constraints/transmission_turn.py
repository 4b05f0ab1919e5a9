"""Transmission angle over a full crank turn, exactly: its extremes are at theta2 = 0 and pi.

cos mu = (r3^2 + r4^2 - d^2) / (2 r3 r4) falls as d^2 = r1^2 + r2^2 - 2 r1 r2 cos theta2 grows, so a
crank that turns fully sees mu_min at theta2 = 0 and mu_max at theta2 = pi.  The optimiser gets the
two polynomial rows  cos mu(0) <= cos(lo)  and  cos mu(pi) >= cos(hi); nothing is sampled, so no
backoff is needed.  Records report mu in degrees (``check`` re-samples the whole turn on its own).
"""

from __future__ import annotations

import math

import casadi as ca

from constraints.base import Rule
from synthesis.kinematics.coupler_point import cos_transmission


def transmission_turn_rules(r1, r2, r3, r4, bounds: tuple) -> list[Rule]:
    lo, hi = bounds
    c_min = cos_transmission(0.0, r1, r2, r3, r4)          # at mu_min
    c_max = cos_transmission(math.pi, r1, r2, r3, r4)      # at mu_max
    deg = 180.0 / math.pi
    return [Rule("transmission_angle_min", ca.acos(c_min) * deg, lo, None, "deg", 10.0, "over a turn (at theta2 = 0)",
                 nlp_rows=((c_min, None, math.cos(math.radians(lo))),)),
            Rule("transmission_angle_max", ca.acos(c_max) * deg, None, hi, "deg", 10.0, "over a turn (at theta2 = 180)",
                 nlp_rows=((c_max, math.cos(math.radians(hi)), None),))]


def transmission_sampled_rules(thetas: list, r1, r2, r3, r4, bounds: tuple) -> list[Rule]:
    """The same two rules when the crank does not turn fully: cos mu at every sampled crank angle."""
    lo, hi = bounds
    cs = [cos_transmission(th, r1, r2, r3, r4) for th in thetas]
    deg = 180.0 / math.pi
    mu = ca.vertcat(*[ca.acos(c) * deg for c in cs])
    return [Rule("transmission_angle_min", mu, lo, None, "deg", 10.0, "over the crank's motion",
                 nlp_rows=tuple((c, None, math.cos(math.radians(lo))) for c in cs)),
            Rule("transmission_angle_max", mu, None, hi, "deg", 10.0, "over the crank's motion",
                 nlp_rows=tuple((c, math.cos(math.radians(hi)), None) for c in cs))]
