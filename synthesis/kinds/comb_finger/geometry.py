"""The eccentric rotating comb fingers of seed 002 §四.3 (eq 14-22, Fig. 26-28), on floats or CasADi symbols.

Front view (Fig. 28b, reconstructed; problems/comb_finger/FINGER.md): x across the row from its centre
line (toward the right unit), y up from the ground line MN, the plant's root D at the origin.  The left
unit (the right one is its mirror image in x = 0):

    drum (cone) axis S = (-(r + e) cos(alpha), b)          (the drums' axes run along the travel direction)
    finger hub       R = S + e (cos(alpha), -sin(alpha))  = (-r cos(alpha), b - e sin(alpha))
    finger tip       T(phi) = R + r (sin(phi), -cos(phi)),  phi from straight down, turning toward the row

S, R, E collinear with E on the centre line (the paper's simplification) puts R at r cos(alpha) from the
centre line; the two tip circles meet the centre line at E (phi = 90 - alpha) and F (phi = 90 + alpha).
With the tip circle touching the ground (b = r + e sin(alpha), the paper's second simplification):

    PD = |RD| - r = r (csc(beta) - 1),  beta = angle of DR above the ground      eq (17)
    the tip rises r (1 - cos(omega t)) after turning omega t from the bottom       eq (18, 19)
    it reaches F after omega t = 90 deg + alpha                                    eq (20, 22)
    so the lift is l = r (1 + sin(alpha)) and tan(theta) = l / (V_s t)            eq (16, 21)

Lengths mm, angles rad inside this module, omega rad/s, V_s mm/s.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


def _plain(r):
    return float(r) if np.ndim(r) == 0 else r


def _f(name: str):
    cas, num = {"sin": (ca.sin, np.sin), "cos": (ca.cos, np.cos), "sqrt": (ca.sqrt, np.sqrt),
                "atan": (ca.atan, np.arctan)}[name]
    return lambda x: cas(x) if _symbolic(x) else _plain(num(x))


sin, cos, sqrt, atan = _f("sin"), _f("cos"), _f("sqrt"), _f("atan")


def atan2(y, x):
    return ca.atan2(y, x) if _symbolic(y, x) else _plain(np.arctan2(y, x))


def drum_axis(r, e, alpha, b):
    """S of the left unit."""
    return -(r + e) * cos(alpha), b


def hub(r, e, alpha, b):
    """R of the left unit: S offset by e at the depression angle alpha toward the row."""
    return -r * cos(alpha), b - e * sin(alpha)


def tip(r, e, alpha, b, phi):
    """The left finger's tip at turn angle phi (from straight down, toward the row)."""
    rx, ry = hub(r, e, alpha, b)
    return rx + r * sin(phi), ry - r * cos(phi)


def centre_line_points(r, e, alpha, b):
    """E (lower) and F (upper): where the tip circle meets the row's centre line x = 0."""
    _, ry = hub(r, e, alpha, b)
    return (0.0, ry - r * sin(alpha)), (0.0, ry + r * sin(alpha))


def cone_distance(r, e, alpha):
    """a: the distance between the two drums' axes (our reading of eq 14)."""
    return 2.0 * (r + e) * cos(alpha)


def tangent_drum_height(r, e, alpha):
    """b with the tip circle touching the ground line (our reading of eq 15)."""
    return r + e * sin(alpha)


def lowest_tip(r, e, alpha, b):
    """Height of the tip's lowest point above the ground line (0: it touches the ground)."""
    return b - e * sin(alpha) - r


def root_angle(r, e, alpha, b):
    """beta: the angle of D -> R above the ground line (eq 17's beta)."""
    rx, ry = hub(r, e, alpha, b)
    return atan2(ry, -rx)


def root_clearance(r, e, alpha, b):
    """PD: from the root D along D -> R to the tip circle (P), mm."""
    rx, ry = hub(r, e, alpha, b)
    return sqrt(rx * rx + ry * ry) - r


def combing_turn(r, e, alpha, b):
    """The turn from the tip's lowest point (phi = 0) to F, from the geometry: the angle of R -> F measured
    from straight down toward the row (eq 20 says 90 deg + alpha)."""
    _, f = centre_line_points(r, e, alpha, b)
    rx, ry = hub(r, e, alpha, b)
    return atan2(f[0] - rx, -(f[1] - ry))


def rise(r, e, alpha, b, phi):
    """How far the tip has risen above its lowest point after turning phi from it (eq 18/19: r (1 - cos phi))."""
    return tip(r, e, alpha, b, phi)[1] - tip(r, e, alpha, b, 0.0)[1]


def combing_lift(r, e, alpha, b):
    """l: the rise from the lowest point to F (eq 16/21: r (1 + sin alpha))."""
    return rise(r, e, alpha, b, combing_turn(r, e, alpha, b))


def combing_time(r, e, alpha, b, omega):
    """t: the time of the combing turn at omega rad/s (eq 22: (alpha + pi/2) / omega), s."""
    return combing_turn(r, e, alpha, b) / omega


def combing_angle(r, e, alpha, b, omega, machine_speed_mm_s):
    """theta: the stem's angle after combing, the straight line from where the tip picks it up to F
    (eq 21: tan theta = l / (V_s t)), rad."""
    return atan2(combing_lift(r, e, alpha, b), machine_speed_mm_s * combing_time(r, e, alpha, b, omega))


# ---- as printed ---------------------------------------------------------------------------------------------

def pd_printed(r, beta):
    """Eq (17): PD = r (csc beta - 1)."""
    return r * (1.0 / sin(beta) - 1.0)


def tan_theta_eq19(r, omega_t, machine_speed_mm_s, t):
    """Eq (19) (OCR 'V_0 + epsilon' read V_s t): tan theta = r (1 - cos omega t) / (V_s t)."""
    return r * (1.0 - cos(omega_t)) / (machine_speed_mm_s * t)


def tan_theta_eq21(r, alpha, machine_speed_mm_s, t):
    """Eq (21) (OCR 'V_a t' read V_s t): tan theta = r (1 + sin alpha) / (V_s t)."""
    return r * (1.0 + sin(alpha)) / (machine_speed_mm_s * t)


def time_eq22(alpha, omega):
    """Eq (22): t = (alpha + pi/2) / omega."""
    return (alpha + math.pi / 2.0) / omega


def best_alpha_at_fixed_omega() -> float:
    """The alpha (rad) that maximises tan theta = r omega (1 + sin alpha) / (V_s (alpha + pi/2)) at fixed r, omega:
    with u = alpha + pi/2 the derivative vanishes at u = tan(u / 2) (about 43.6 deg)."""
    u = 2.33
    for _ in range(60):                      # Newton on u - tan(u/2) = 0
        t = math.tan(u / 2.0)
        u -= (u - t) / (1.0 - 0.5 * (1.0 + t * t))
    return u - math.pi / 2.0
