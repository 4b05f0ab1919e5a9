"""Seed 001 eq 14, 17, 19, 21 exactly as printed: the "superposition" reading of the drop.

Each printed phase adds the phase's initial speed to the from-rest solution:

    v(t) = A v_L tanh(g A t / v_L) + v0,     x(t) = v0 t + (v_L^2 / g) ln cosh(g A t / v_L)

(eq 17 with A = sqrt(sin d - mu cos d), v0 = v2a; eq 19 and 21 with A = 1, v0 = v3a sin d and v5a).
For v0 > 0 this is not a solution of the printed differential equations 16 and 18 (the drag on
v0 is left out: dv/dt = g A^2 sech^2(...) instead of g (A^2 - v^2 / v_L^2)); for v0 = 0 it is the
exact eq 14.  It is undefined when tan d < mu (A imaginary), and with it the split of h5 + h6
into h3 (projectile) and h4 (fall after the vertical wall) changes the drop time, so it takes
``h3`` as an argument.  Used only to compare readings of the paper (GUIDE_TUBE.md), never by a run.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from synthesis.kinds.guide_tube.drop import Physics, Tube


def _log_cosh(x: float) -> float:
    return x + math.log1p(math.exp(-2 * x)) - math.log(2.0)


def printed_phase(v0: float, A: float, physics: Physics, distance: float) -> tuple[float, float]:
    """(t, v) of one printed phase over ``distance`` (m): root of x(t) = distance."""
    g, vl = physics.gravity, physics.terminal_speed
    if distance == 0:
        return 0.0, v0

    def x(t: float) -> float:
        return v0 * t + vl * vl / g * _log_cosh(g * A * t / vl) - distance

    hi = 1e-3
    while x(hi) < 0:
        hi *= 2
    t = brentq(x, 0.0, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return t, A * vl * math.tanh(g * A * t / vl) + v0


def printed_landing_time(delta_deg: float, tube: Tube, physics: Physics, h3: float | None = None) -> float:
    """t_z from eq 14, 15, 17, 19-23 as printed; ``h3`` (m) is the projectile's drop before the
    vertical wall (default: all of h5 + h6, no vertical-wall impact)."""
    d = math.radians(delta_deg)
    a_sq = math.sin(d) - physics.mu * math.cos(d)
    if a_sq < 0:
        raise ValueError(f"eq 17 is undefined for tan d < mu (A^2 = {a_sq:.4g} < 0)")
    h1 = physics.height - tube.below_wall - tube.l3 * math.tan(d)
    h3 = tube.below_wall if h3 is None else h3
    t1, v1 = printed_phase(0.0, 1.0, physics, h1)                                       # eq 14
    t2, v3 = printed_phase(v1 * math.sin(d), math.sqrt(a_sq), physics, tube.l3 / math.cos(d))  # eq 15, 17
    t3, v4 = printed_phase(v3 * math.sin(d), 1.0, physics, h3)                           # eq 19
    t4, _ = printed_phase(v4, 1.0, physics, tube.below_wall - h3)                        # eq 20, 21
    return t1 + t2 + t3 + t4
