"""Distorted rotary tillage linkage of seed 002 (§四.2, eq 3-11, Figs. 18-20), floats and CasADi alike.

Geometry as we derive it (the figures are missing; the frame is the one in which eq 7 holds):
the roller pair C is the origin, x to the right, y up.  The flywheel centre A lies at distance b
from C, so that C is seen from A at the depression angle theta (A is up and to the right of C):

    A = b (cos theta, sin theta)
    B = A + a (cos omega, sin omega)          crank AB, omega from +x, counter-clockwise
    D = B + c (C - B) / |C - B|               the bar BD (length c) slides through the rollers at C

With U, V = B - C and S = |B - C| = sqrt(a^2 + b^2 + 2 a b cos(omega - theta)), W = c / S:

    x_D = U (1 - W),   y_D = V (1 - W)                                       (eq 7)

D lies beyond C (W > 1) as long as the bar is longer than CB, i.e. c > a + b at every omega, and
is defined while S > 0, i.e. a < b (the crank circle does not reach C).  The angle ACB (eq 3) is
phi = atan2(a sin(omega - theta), b + a cos(omega - theta)), positive with B above line AC.

D runs round its loop clockwise: at the bottom it moves towards -x.  With the machine travelling
towards +x at speed v, the tool moves backwards relative to the soil (it lifts; it does not push)
where omega_dot dx/domega + v < 0.  Derivatives with respect to omega (eq 9-11) are CasADi AD.
"""

from __future__ import annotations

import functools
import math

import casadi as ca


def bar_vector(omega, a, b, theta) -> tuple:
    """(U, V) = B - C and S = |B - C| (mm); theta, omega in rad."""
    u = a * ca.cos(omega) + b * ca.cos(theta)
    v = a * ca.sin(omega) + b * ca.sin(theta)
    s = ca.sqrt(a * a + b * b + 2.0 * a * b * ca.cos(omega - theta))
    return u, v, s


def tool_point(omega, a, b, c, theta) -> tuple:
    """D = (U (1 - W), V (1 - W)) with W = c / S: eq 7 (mm, C at the origin)."""
    u, v, s = bar_vector(omega, a, b, theta)
    w = c / s
    return u * (1.0 - w), v * (1.0 - w)


def bar_angle(omega, a, b, theta):
    """phi = angle ACB (rad), positive with B above AC: eq 3 as atan2 of its numerator and denominator."""
    return ca.atan2(a * ca.sin(omega - theta), b + a * ca.cos(omega - theta))


def joints(omega: float, a: float, b: float, c: float, theta: float) -> dict[str, tuple[float, float]]:
    """A, B, C, D (mm) by construction (floats): B on the crank circle, D on ray B -> C at distance c."""
    ax, ay = b * math.cos(theta), b * math.sin(theta)
    bx, by = ax + a * math.cos(omega), ay + a * math.sin(omega)
    s = math.hypot(bx, by)
    dx, dy = bx + c * (0.0 - bx) / s, by + c * (0.0 - by) / s
    return {"A": (ax, ay), "B": (bx, by), "C": (0.0, 0.0), "D": (dx, dy)}


@functools.lru_cache(maxsize=1)
def path_function() -> ca.Function:
    """(omega, [a, b, c, theta]) -> x, y, dx/domega, dy/domega, d2x/domega2, d2y/domega2 (mm, mm/rad, mm/rad^2),
    every derivative by CasADi AD of eq 7.  Works on floats, DM grids (``.map``) and symbols."""
    omega = ca.SX.sym("omega")
    p = ca.SX.sym("p", 4)
    x, y = tool_point(omega, p[0], p[1], p[2], p[3])
    dx, dy = ca.jacobian(x, omega), ca.jacobian(y, omega)
    ddx, ddy = ca.jacobian(dx, omega), ca.jacobian(dy, omega)
    return ca.Function("tillage_path", [omega, p], [x, y, dx, dy, ddx, ddy],
                       ["omega", "p"], ["x", "y", "dx", "dy", "ddx", "ddy"])


def speed(dx, dy):
    """Eq 9: v = sqrt(x'^2 + y'^2) (per unit crank angle)."""
    return ca.sqrt(dx * dx + dy * dy)


def direction(dx, dy):
    """Eq 10: delta = atan(y' / x'), here as atan2 (the quadrant kept)."""
    return ca.atan2(dy, dx)


def acceleration(ddx, ddy):
    """Eq 11: sqrt(x''^2 + y''^2) (per unit crank angle squared; x ``omega_dot^2`` at constant crank speed)."""
    return ca.sqrt(ddx * ddx + ddy * ddy)
