"""Ackermann steering trapezoid (seed 002 Table 12): closed-form position analysis, floats and CasADi alike.

Frame (plan view): origin at the middle of the front axle between the kingpins, x to the right
kingpin, y forward.  Kingpins K_L = (-w/2, 0), K_R = (w/2, 0) (w = kingpin spacing).  The steering
arms (length r) point rearward and inward at the *base angle* gamma to the axle line, so the
straight-ahead linkage is an isosceles trapezoid K_L T_L T_R K_R with the tie rod T_L T_R behind
the axle, of length

    l = w - 2 r cos(gamma)                          (the wheels are parallel straight ahead)

A left turn (the right one is its mirror image) steers both wheels counter-clockwise: the inner
(left) wheel by beta, the outer (right) wheel by alpha,

    T_L(beta)  = K_L + r (cos(beta - gamma), sin(beta - gamma))
    T_R(alpha) = K_R - r (cos(gamma + alpha), sin(gamma + alpha))

and alpha closes the loop |T_R - T_L| = l.  With d = T_L - K_R, D = |d| and psi the direction of -d,

    alpha = psi + acos((r^2 + D^2 - l^2) / (2 r D)) - gamma

(the + root is the assembly that is straight ahead at beta = 0).  The argument of acos is the
cosine of the angle at K_R in the triangle K_R T_L T_R; it reaches +-1 where the outer arm and the
tie rod align: the dead centre beyond which the trapezoid cannot follow the inner wheel.

Ackermann (every wheel square to a radius from one centre on the rear-axle line, wheelbase L):

    cot(alpha) - cot(beta) = w / L   <=>   alpha = atan2(sin beta, cos beta + (w/L) sin beta)
"""

from __future__ import annotations

import math

import casadi as ca


def tie_rod_length(w, r, gamma):
    """l = w - 2 r cos(gamma): the tie rod of the straight-ahead trapezoid (gamma in rad)."""
    return w - 2.0 * r * ca.cos(gamma)


def kingpins(w) -> tuple[tuple, tuple]:
    return (-0.5 * w, 0.0), (0.5 * w, 0.0)


def inner_tip(beta, w, r, gamma) -> tuple:
    """T_L: the inner (left) arm's tip at inner lock beta (rad)."""
    return (-0.5 * w + r * ca.cos(beta - gamma), r * ca.sin(beta - gamma))


def outer_tip(alpha, w, r, gamma) -> tuple:
    """T_R: the outer (right) arm's tip at outer lock alpha (rad)."""
    return (0.5 * w - r * ca.cos(gamma + alpha), -r * ca.sin(gamma + alpha))


def dead_centre_cosine(beta, w, r, gamma):
    """cos of the angle at K_R in the triangle K_R T_L T_R: (r^2 + D^2 - l^2) / (2 r D).

    Defined for every beta (it needs only T_L); the trapezoid assembles at beta iff it lies in [-1, 1]."""
    tx, ty = inner_tip(beta, w, r, gamma)
    dx, dy = tx - 0.5 * w, ty
    d2 = dx * dx + dy * dy
    l = tie_rod_length(w, r, gamma)
    return (r * r + d2 - l * l) / (2.0 * r * ca.sqrt(d2))


def outer_lock(beta, w, r, gamma):
    """alpha(beta) in closed form (rad); NaN on floats beyond the dead centre."""
    tx, ty = inner_tip(beta, w, r, gamma)
    dx, dy = tx - 0.5 * w, ty
    psi = ca.atan2(-dy, -dx)
    return psi + ca.acos(dead_centre_cosine(beta, w, r, gamma)) - gamma


def loop_residual(beta, alpha, w, r, gamma):
    """(|T_R - T_L|^2 - l^2) / w^2: zero where (beta, alpha) closes the loop (NLP structural row)."""
    lx, ly = inner_tip(beta, w, r, gamma)
    rx, ry = outer_tip(alpha, w, r, gamma)
    l = tie_rod_length(w, r, gamma)
    return ((rx - lx) ** 2 + (ry - ly) ** 2 - l * l) / (w * w)


def _signed_angle(u: tuple, v: tuple):
    """The angle from u to v, counter-clockwise positive, in (-pi, pi]: atan2(u x v, u . v)."""
    return ca.atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])


def transmission_angles(beta, alpha, w, r, gamma) -> tuple:
    """(mu_outer, mu_inner), rad: the angles between the tie rod and each steering arm, signed so that the
    straight-ahead assembly has both in (0, pi) (the other assembly of the outer side is negative).

    mu_outer: at T_R from T_R->K_R to T_R->T_L; mu_inner: at T_L from T_L->T_R to T_L->K_L."""
    (klx, kly), (krx, kry) = kingpins(w)
    lx, ly = inner_tip(beta, w, r, gamma)
    rx, ry = outer_tip(alpha, w, r, gamma)
    mu_outer = _signed_angle((krx - rx, kry - ry), (lx - rx, ly - ry))
    mu_inner = _signed_angle((rx - lx, ry - ly), (klx - lx, kly - ly))
    return mu_outer, mu_inner


def ackermann_outer(beta, w_over_l):
    """The Ackermann outer lock for inner lock beta (rad): cot(alpha) - cot(beta) = w / L, smooth at 0."""
    return ca.atan2(ca.sin(beta), ca.cos(beta) + w_over_l * ca.sin(beta))


def ackermann_kingpin_spacing(beta_deg: float, alpha_deg: float, wheelbase: float) -> float:
    """w = L (cot(alpha) - cot(beta)): the kingpin spacing that makes (beta, alpha) an Ackermann pair."""
    return wheelbase * (1.0 / math.tan(math.radians(alpha_deg)) - 1.0 / math.tan(math.radians(beta_deg)))


def turning_radii(beta_deg: float, wheelbase: float, kingpin_spacing: float, track: float) -> dict[str, float]:
    """Path radii (mm) at inner lock beta about the Ackermann centre O on the rear-axle line, which lies
    L cot(beta) inboard of the inner kingpin; the wheels' contact points lie (track - w)/2 outboard of
    their kingpins."""
    L, w = wheelbase, kingpin_spacing
    s = 0.5 * (track - w)
    x = L / math.tan(math.radians(beta_deg))      # inner kingpin's lateral distance from O
    return {
        "inner_rear_wheel": x - s,
        "rear_axle_midpoint": x + 0.5 * w,
        "outer_rear_wheel": x + w + s,
        "inner_front_wheel": math.hypot(x - s, L),
        "inner_front_kingpin": math.hypot(x, L),          # = L / sin(beta)
        "front_axle_midpoint": math.hypot(x + 0.5 * w, L),
        "outer_front_kingpin": math.hypot(x + w, L),       # = L / sin(alpha_Ackermann)
        "outer_front_wheel": math.hypot(x + w + s, L),
    }
