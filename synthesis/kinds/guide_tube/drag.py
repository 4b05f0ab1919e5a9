"""Straight-line motion with quadratic drag, dv/dt = a - kappa v^2: time and speed over a distance.

Every phase of seed 001's drop model (eq 13, 16, 18) is this equation with its own constant
driving acceleration ``a`` (g in free fall, g (sin d - mu cos d) on the wall) and
``kappa = g / v_L^2``.  Covering a distance ``s`` from speed ``v0 >= 0``:

    E   = exp(-2 kappa s),   W = (1 - E) / kappa          (W = 2 s when kappa = 0)
    v^2 = v0^2 E + a W                                     (energy along the path, exact)
    D   = v + v0 E,          q = a kappa W^2 / D^2
    t   = (W / D) S(q),      S(q) = atanh(sqrt q)/sqrt q  (q > 0),  atan(sqrt -q)/sqrt -q  (q < 0)

S(q) = sum q^n / (2n + 1) is analytic in q, and q is a polynomial in ``a``: the time is one smooth
function of ``a`` through a = 0 (the near-sticking wall, tan d -> mu, where the printed eq 17
divides by A = sqrt(sin d - mu cos d)) and through a < 0 (the decelerating slide, where eq 17's
square root is imaginary; S then uses atan).  ``t`` never divides by A.  Near q = 1 (long falls
close to the terminal speed) atanh(sqrt q) loses its digits, so there the equivalent form

    t = [ln(1 + sqrt q) + kappa s + ln(D / (v + v0))] / sqrt(a kappa)

is used: it follows from 1 - q = E (v + v0)^2 / D^2, exact and free of cancellation, and it holds
kappa s itself instead of exp(2 kappa s), so no exponential can overflow.  Derivation and checks:
problems/guide_tube/GUIDE_TUBE.md.

The functions run on floats and on CasADi symbols alike (the CasADi math functions accept both);
branches become ``if_else`` on symbols.  Every argument of an inactive branch is kept finite, so a
branch switch never leaks a NaN into a value or a derivative.
"""

from __future__ import annotations

import casadi as ca

#: |q| below which S(q) is summed as its Taylor series (9 terms: truncation < 1e-19)
Q_SERIES = 1e-2
_SERIES_TERMS = 9
#: q above which the long-distance form is used (both forms are exact; this one keeps the digits)
Q_LONG = 0.5
#: 2 kappa s below which (1 - exp(-x)) / x is summed as its series (truncation < 1e-17)
X_SERIES = 1e-4
#: floor of denominators in inactive branches (never reached by an active branch)
_TINY = 1e-150


def where(condition, if_true, if_false):
    """``if_true`` where ``condition`` holds: a Python choice on floats, ``if_else`` on symbols."""
    if isinstance(condition, (ca.SX, ca.MX)):
        return ca.if_else(condition, if_true, if_false)
    return if_true if condition else if_false


def _horner(x, coefficients):
    out = coefficients[-1]
    for c in reversed(coefficients[:-1]):
        out = c + x * out
    return out


def atanh_ratio(q):
    """S(q) = sum_n q^n / (2n + 1): atanh(sqrt q)/sqrt q for 0 < q <= Q_LONG, atan(sqrt -q)/sqrt -q
    for q < 0, its series near 0.  Callers use it for q <= Q_LONG only."""
    series = _horner(q, [1.0 / (2 * n + 1) for n in range(_SERIES_TERMS)])
    root = ca.sqrt(ca.fmax(ca.fabs(q), Q_SERIES / 4))
    positive = ca.atanh(ca.fmin(root, Q_LONG ** 0.5)) / root
    negative = ca.atan(root) / root
    return where(ca.fabs(q) < Q_SERIES, series, where(q > 0, positive, negative))


def relaxation_length(kappa, s):
    """W = (1 - exp(-2 kappa s)) / kappa, exactly 2 s when kappa = 0 (no drag)."""
    x = 2 * kappa * s
    series = 1 - x / 2 + x * x / 6 - x * x * x / 24
    closed = -ca.expm1(-ca.fmax(x, X_SERIES)) / ca.fmax(x, X_SERIES)
    return 2 * s * where(x < X_SERIES, series, closed)


def exit_speed_sq(v0, a, kappa, s):
    """v^2 after covering s: v0^2 exp(-2 kappa s) + a W.  <= 0 means the motion stops before s
    (possible only when a < 0)."""
    return v0 * v0 * ca.exp(-2 * kappa * s) + a * relaxation_length(kappa, s)


def traverse(v0, a, kappa, s):
    """(t, v): time to cover distance ``s`` >= 0 from speed ``v0`` >= 0 under dv/dt = a - kappa v^2,
    and the speed there.  Valid while the motion does not stop (exit_speed_sq > 0); SI units."""
    E = ca.exp(-2 * kappa * s)
    W = relaxation_length(kappa, s)
    v = ca.sqrt(ca.fmax(v0 * v0 * E + a * W, _TINY * _TINY))   # > 0: no infinite slope when it stops
    D = ca.fmax(v + v0 * E, _TINY)
    q = a * kappa * W * W / (D * D)
    short = W / D * atanh_ratio(ca.fmin(q, Q_LONG))
    long = (ca.log1p(ca.sqrt(ca.fmax(q, Q_LONG))) + kappa * s + ca.log(D / ca.fmax(v + v0, _TINY))) \
        / ca.sqrt(ca.fmax(a * kappa, _TINY))
    return where(q > Q_LONG, long, short), v


def stopping_distance(v0: float, a: float, kappa: float) -> float:
    """Distance after which a decelerating motion (a < 0) from v0 comes to rest:
    ln(1 + kappa v0^2 / |a|) / (2 kappa), which is v0^2 / (2 |a|) without drag.  Floats only."""
    if a >= 0:
        return float("inf")
    y = kappa * v0 * v0 / -a
    ratio = 1.0 if y < 1e-12 else float(ca.log1p(y)) / y
    return v0 * v0 / (2 * -a) * ratio
