"""Analytic derivative dt_z/d(delta) of the closed-form drop, written out by hand.

It is independent of the closed form's code (it uses the integral t = int dv / (a - kappa v^2) and
the energy balance v^2 = v0^2 E + a W, not the formula drag.traverse evaluates) and of CasADi, so
it checks the AD derivatives the optimiser uses.  Partials of one phase (t, v) = T(v0, a, s), with
E = exp(-2 kappa s), W = (1 - E) / kappa and P = a - kappa v0^2 (the acceleration at the start):

    dt/ds  = 1 / v                     dv/ds  = (a - kappa v^2) / v = E P / v
    dt/dv0 = (v0 - v) / (v P)          dv/dv0 = v0 E / v
    dt/da  = W / (2 v E P) - [v / (E P) - v0 / P + t] / (2 a)          dv/da = W / (2 v)

dt/da follows from int dw / (a - kappa w^2)^2 = [w / (a - kappa w^2) + int dw / (a - kappa w^2)] / (2a).
These are singular where P = 0 (v0 at the terminal speed) or a = 0 (the sticking limit): that is
the formula's limit, not the closed form's, which stays smooth there; use it away from them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from synthesis.kinds.guide_tube.drag import relaxation_length
from synthesis.kinds.guide_tube.drop import Physics, Tube, landing


@dataclass(frozen=True)
class PhaseSlopes:
    """Partials of (t, v) of one phase with respect to (v0, a, s)."""

    t_v0: float
    t_a: float
    t_s: float
    v_v0: float
    v_a: float
    v_s: float


def phase_slopes(v0: float, a: float, kappa: float, s: float, t: float, v: float) -> PhaseSlopes:
    E = math.exp(-2 * kappa * s)
    W = float(relaxation_length(kappa, s))
    P = a - kappa * v0 * v0
    return PhaseSlopes(
        t_v0=(v0 - v) / (v * P),
        t_a=W / (2 * v * E * P) - (v / (E * P) - v0 / P + t) / (2 * a),
        t_s=1.0 / v,
        v_v0=v0 * E / v,
        v_a=W / (2 * v),
        v_s=E * P / v,
    )


def landing_time_slope(delta_deg: float, tube: Tube, physics: Physics) -> float:
    """dt_z / d(delta) in s per radian at wall angle ``delta_deg`` (tube with a wall, L3 > 0)."""
    d = math.radians(delta_deg)
    sin, cos = math.sin(d), math.cos(d)
    g, kappa, mu = physics.gravity, physics.kappa, physics.mu
    ph = landing(delta_deg, tube, physics)
    # geometry (eq 23): h1 = H - h5 - h6 - L3 tan d, s1 = L3 / cos d
    dh1 = -tube.l3 / cos ** 2
    ds1 = tube.l3 * sin / cos ** 2
    # phase 1: free fall from rest over h1
    fall = phase_slopes(0.0, g, kappa, ph.h1, ph.t_fall, ph.v_impact)
    dt1, dv1 = fall.t_s * dh1, fall.v_s * dh1
    # impact (eq 15) and the slide's driving acceleration
    dv2 = dv1 * sin + ph.v_impact * cos
    accel = g * (sin - mu * cos)
    daccel = g * (cos + mu * sin)
    slide = phase_slopes(ph.v_wall, accel, kappa, ph.s1, ph.t_slide, ph.v_exit)
    dt2 = slide.t_v0 * dv2 + slide.t_a * daccel + slide.t_s * ds1
    dv3 = slide.v_v0 * dv2 + slide.v_a * daccel + slide.v_s * ds1
    # phases 4-6: vertical fall of h5 + h6 from v3a sin d
    u = ph.v_exit * sin
    du = dv3 * sin + ph.v_exit * cos
    after = phase_slopes(u, g, kappa, tube.below_wall, ph.t_after, ph.v_land)
    return dt1 + dt2 + after.t_v0 * du
