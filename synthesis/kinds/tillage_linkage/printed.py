"""Seed 002 eq 3-11 as printed (our reading of the OCR), kept apart from the model so tests and the
result can hold each printed relation against the constructed geometry and against CasADi's AD.

Floats only.  Angles in rad, lengths in mm.  The OCR breaks eq 5 and 6 over lines (the products
c cos(theta) x (b + a cos(omega - theta)) / S lose their multiplication) and prints "±" in eq 3's
intermediate step; read as products and "+", they hold.  Eq 8's expanded form is printed with "+"
between its terms and does *not* hold (see :func:`eq8_expanded_as_printed`).
"""

from __future__ import annotations

import math


def _s(omega, a, b, theta) -> float:
    return math.sqrt(a * a + b * b + 2.0 * a * b * math.cos(omega - theta))


def eq3_tan(omega, a, b, theta) -> float:
    """tan(phi) = a sin(omega - theta) / (b + a cos(omega - theta))."""
    return a * math.sin(omega - theta) / (b + a * math.cos(omega - theta))


def eq3_tan_expanded(omega, a, b, theta) -> float:
    """= (a sin(omega) cos(theta) - a cos(omega) sin(theta)) / (b + a cos(omega) cos(theta) + a sin(omega) sin(theta)) = Q/P."""
    q = a * math.sin(omega) * math.cos(theta) - a * math.cos(omega) * math.sin(theta)
    p = b + a * math.cos(omega) * math.cos(theta) + a * math.sin(omega) * math.sin(theta)
    return q / p


def eq3_denominator_squared(omega, a, b, theta) -> float:
    """P^2 + Q^2 as the intermediate step prints it, "±" read as "+": a^2 sin^2(omega) + a^2 cos^2(omega) + b^2
    + 2 a b cos(omega - theta) (the a^2 terms of P^2 + Q^2 sum to a^2 whatever theta is)."""
    return (a * a * math.sin(omega) ** 2 + a * a * math.cos(omega) ** 2 + b * b
            + 2.0 * a * b * math.cos(omega - theta))


def eq3_sin(omega, a, b, theta) -> float:
    """sin(phi) = a sin(omega - theta) / sqrt(a^2 + b^2 + 2 a b cos(omega - theta))."""
    return a * math.sin(omega - theta) / _s(omega, a, b, theta)


def eq4_cos(omega, a, b, theta) -> float:
    """cos(phi) = (b + a cos(omega - theta)) / sqrt(a^2 + b^2 + 2 a b cos(omega - theta))."""
    return (b + a * math.cos(omega - theta)) / _s(omega, a, b, theta)


def eq5_first_line(omega, a, b, c, theta) -> float:
    """x = b cos(theta) + a cos(omega) - c cos(theta) cos(phi) + c sin(theta) sin(phi), phi from eq 3, 4
    (= U - c cos(theta + phi): D lies on the ray from B through C, at distance c from B)."""
    return (b * math.cos(theta) + a * math.cos(omega) - c * math.cos(theta) * eq4_cos(omega, a, b, theta)
            + c * math.sin(theta) * eq3_sin(omega, a, b, theta))


def eq5(omega, a, b, c, theta) -> float:
    """x = a cos(omega) + b cos(theta) - c (a cos(omega) + b cos(theta)) / sqrt(a^2 + b^2 + 2ab cos(omega - theta))."""
    u = a * math.cos(omega) + b * math.cos(theta)
    return u - c * u / _s(omega, a, b, theta)


def eq6_first_line(omega, a, b, c, theta) -> float:
    """y = b sin(theta) + a sin(omega) - c sin(theta) cos(phi) - c cos(theta) sin(phi) (= V - c sin(theta + phi));
    the OCR gives only "likewise" for this line."""
    return (b * math.sin(theta) + a * math.sin(omega) - c * math.sin(theta) * eq4_cos(omega, a, b, theta)
            - c * math.cos(theta) * eq3_sin(omega, a, b, theta))


def eq6(omega, a, b, c, theta) -> float:
    """y = a sin(omega) + b sin(theta) - c (a sin(omega) + b sin(theta)) / sqrt(...)."""
    v = a * math.sin(omega) + b * math.sin(theta)
    return v - c * v / _s(omega, a, b, theta)


def eq7(omega, a, b, c, theta) -> tuple[float, float]:
    """U = a cos(omega) + b cos(theta), V = a sin(omega) + b sin(theta), W = c / sqrt(...): (U (1 - W), V (1 - W))."""
    u = a * math.cos(omega) + b * math.cos(theta)
    v = a * math.sin(omega) + b * math.sin(theta)
    w = c / _s(omega, a, b, theta)
    return u * (1.0 - w), v * (1.0 - w)


def eq8(omega, a, b, c, theta) -> float:
    """V x - U y at D: zero (D lies on the line through C and B)."""
    x, y = eq7(omega, a, b, c, theta)
    u = a * math.cos(omega) + b * math.cos(theta)
    v = a * math.sin(omega) + b * math.sin(theta)
    return v * x - u * y


def eq8_expanded_as_printed(omega, a, b, c, theta) -> float:
    """(a sin(omega) + b sin(theta)) x + (a cos(omega) + b cos(theta)) y at D, as printed ("+").  Not zero:
    with x = U (1 - W), y = V (1 - W) it equals 2 U V (1 - W), zero only where CB is horizontal or vertical
    (U V = 0); the printed line is the mirror image of CB in the x axis.  The "+" must be "-" (eq 8's
    own first form, V x - U y = 0)."""
    x, y = eq7(omega, a, b, c, theta)
    u = a * math.cos(omega) + b * math.cos(theta)
    v = a * math.sin(omega) + b * math.sin(theta)
    return v * x + u * y


def derivatives(omega, a, b, c, theta) -> tuple[float, float, float, float]:
    """x', y', x'', y'' of eq 7 (d/domega), derived by hand, for eq 9-11 and to hold against AD:

    U' = -a sin(omega), V' = a cos(omega), U'' = -a cos(omega), V'' = -a sin(omega)
    S' = -a b sin(omega - theta) / S,  W = c / S,  W' = c a b sin(omega - theta) / S^3
    W'' = c a b (cos(omega - theta) / S^3 - 3 sin(omega - theta) S' / S^4)
    x' = U' (1 - W) - U W',  x'' = U'' (1 - W) - 2 U' W' - U W''   (and y with V)"""
    d = omega - theta
    u = a * math.cos(omega) + b * math.cos(theta)
    v = a * math.sin(omega) + b * math.sin(theta)
    s = _s(omega, a, b, theta)
    w = c / s
    s1 = -a * b * math.sin(d) / s
    w1 = c * a * b * math.sin(d) / s**3
    w2 = c * a * b * (math.cos(d) / s**3 - 3.0 * math.sin(d) * s1 / s**4)
    u1, v1, u2, v2 = -a * math.sin(omega), a * math.cos(omega), -a * math.cos(omega), -a * math.sin(omega)
    x1 = u1 * (1.0 - w) - u * w1
    y1 = v1 * (1.0 - w) - v * w1
    x2 = u2 * (1.0 - w) - 2.0 * u1 * w1 - u * w2
    y2 = v2 * (1.0 - w) - 2.0 * v1 * w1 - v * w2
    return x1, y1, x2, y2


def eq9(x1: float, y1: float) -> float:
    return math.hypot(x1, y1)


def eq10(x1: float, y1: float) -> float:
    """delta = tan^-1(y' / x'), printed as an arctangent of the ratio: the quadrant is lost; atan2 keeps it."""
    return math.atan2(y1, x1)


def eq11(x2: float, y2: float) -> float:
    return math.hypot(x2, y2)
