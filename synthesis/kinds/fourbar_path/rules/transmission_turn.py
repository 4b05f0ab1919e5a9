"""Transmission angle from cos mu, over a full crank turn (exactly) or at sampled crank angles.

cos mu = (r3^2 + r4^2 - d^2) / (2 r3 r4) falls as d^2 = r1^2 + r2^2 - 2 r1 r2 cos theta2 grows, so a
crank that turns fully sees mu_min at theta2 = 0 and mu_max at theta2 = pi: the trace of the full-turn
rules is cos mu at those two angles, nothing is sampled.  Records report mu in degrees.  The
optimiser gets polynomial rows, cos mu <= cos(lo) and cos mu >= cos(hi), written in degrees to first
order at the limit:  (cos(lo) - cos mu) / sin(lo) * 180/pi >= 0  (mu - lo near lo), and
(cos mu - cos(hi)) / sin(hi) * 180/pi >= 0  (hi - mu near hi).  So a row's margin, its back-off and an
elastic relaxation are in the rule's unit and scale, as the records are.  On floats, a cos mu outside
[-1, 1] means the loop does not close there: the rule is not evaluated, and says so.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule, not_evaluated, stack

DEG = 180.0 / math.pi
ROUNDING = 1e-12       # |cos mu| this far above 1 is the last digit of a closing loop, not an open one


def _mu_deg(cs):
    """mu (deg) at each cos mu (a list, or a numpy vector of numbers); None (numbers only) when the loop does not
    close at one of them."""
    if isinstance(cs, np.ndarray):
        if not np.all(np.abs(cs) <= 1.0 + ROUNDING):
            return None
        return np.asarray(ca.acos(np.clip(cs, -1.0, 1.0)), dtype=float).ravel() * DEG
    if not any(isinstance(c, (ca.SX, ca.MX)) for c in cs):
        if any(not abs(float(c)) <= 1.0 + ROUNDING for c in cs):
            return None
        cs = [min(1.0, max(-1.0, float(c))) for c in cs]
    return stack([ca.acos(c) * DEG for c in cs])


def _per_degree(limit_deg: float) -> float:
    """d(cos mu)/d(mu) in magnitude at the limit, per degree: rows in cos mu / this are in degrees there
    (1 at 0 and 180 deg, where cos mu is stationary and the rule is a bound on cos mu alone)."""
    slope = math.sin(math.radians(limit_deg)) / DEG
    return slope if slope > 1e-12 else 1.0


def _rows(cs, margin) -> tuple:
    """The rows ``margin(cos mu) >= 0``: one per cos mu of a list, one vector row for a numpy vector."""
    if isinstance(cs, np.ndarray):
        return ((margin(cs), 0.0, None),)
    return tuple((margin(c), 0.0, None) for c in cs)


def _min_rule(cs, lo: float, where: str, open_at: str) -> Rule:
    mu = _mu_deg(cs)
    if mu is None:
        return not_evaluated("transmission_angle_min", lo, None, "deg", where, f"the loop does not close {open_at}")
    c_lo, k = math.cos(math.radians(lo)), _per_degree(lo)
    return Rule("transmission_angle_min", mu, lo, None, "deg", 10.0, where,
                nlp_rows=_rows(cs, lambda c: (c_lo - c) / k))


def _max_rule(cs, hi: float, where: str, open_at: str) -> Rule:
    mu = _mu_deg(cs)
    if mu is None:
        return not_evaluated("transmission_angle_max", None, hi, "deg", where, f"the loop does not close {open_at}")
    c_hi, k = math.cos(math.radians(hi)), _per_degree(hi)
    return Rule("transmission_angle_max", mu, None, hi, "deg", 10.0, where,
                nlp_rows=_rows(cs, lambda c: (c - c_hi) / k))


def transmission_turn_rules(cos_at_0, cos_at_pi, bounds: tuple) -> list[Rule]:
    """Over a full turn: ``cos_at_0`` = cos mu at theta2 = 0 (mu_min), ``cos_at_pi`` at theta2 = pi (mu_max)."""
    lo, hi = bounds
    return [_min_rule([cos_at_0], lo, "over a turn (at theta2 = 0)", "at theta2 = 0"),
            _max_rule([cos_at_pi], hi, "over a turn (at theta2 = 180)", "at theta2 = 180 deg")]


def transmission_sampled_rules(cos_mu, bounds: tuple) -> list[Rule]:
    """When the crank does not turn fully: cos mu at every sampled crank angle of its motion (a list, or a numpy
    vector of numbers)."""
    return transmission_extremes_rules(cos_mu, cos_mu, bounds)


def transmission_extremes_rules(cos_largest: list, cos_smallest: list, bounds: tuple) -> list[Rule]:
    """Over stretches of the crank's motion, each given by cos mu where it is largest (mu smallest: the shortest
    diagonal) and where it is smallest (mu largest): mu_min binds only at the first, mu_max only at the second."""
    lo, hi = bounds
    where, open_at = "over the crank's motion", "everywhere on the crank's motion"
    as_given = lambda cs: cs if isinstance(cs, np.ndarray) else list(cs)       # noqa: E731
    return [_min_rule(as_given(cos_largest), lo, where, open_at), _max_rule(as_given(cos_smallest), hi, where, open_at)]
