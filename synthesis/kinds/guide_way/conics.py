"""The paper's conic segments (seed 003 §1): eq (1), the fitting systems (3), (10), (13), the slope (9)
and a smooth parametrisation of each segment.

    F(x, y) = x^2 + a1 xy + a2 y^2 + a3 x + a4 y + a5 = 0                               (1)
    a point:    x y a1 + y^2 a2 + x a3 + y a4 + a5 = -x^2                                (3)
    a tangent:  (y + x y') a1 + 2 y y' a2 + a3 + y' a4 = -2x                             (8')
    y' = -(2x + a1 y + a3) / (a1 x + 2 a2 y + a4)                                         (9)

Every segment of the paper is a central conic (a1^2 != 4 a2): with centre c and principal axes Q,
F(c + Q w) = l1 w1^2 + l2 w2^2 + F(c), so an ellipse is c + Q (p cos t, q sin t) and a hyperbola
branch c + Q (s p cosh t, q sinh t): explicit in t, smooth, no square-root end points like the
paper's y(x) forms (2), which the check still compares against (``on_form``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

Point = tuple[float, float]


def value(a, x, y):
    """F(x, y) of eq (1)."""
    a1, a2, a3, a4, a5 = a
    return x * x + a1 * x * y + a2 * y * y + a3 * x + a4 * y + a5


def gradient(a, x, y) -> tuple[float, float]:
    a1, a2, a3, a4, _ = a
    return 2 * x + a1 * y + a3, a1 * x + 2 * a2 * y + a4


def slope(a, x, y) -> float:
    """y' of eq (9)."""
    gx, gy = gradient(a, x, y)
    return -gx / gy


def distance(a, x, y) -> float:
    """First-order distance of (x, y) from the conic: |F| / |grad F| (mm)."""
    gx, gy = gradient(a, x, y)
    return abs(value(a, x, y)) / math.hypot(gx, gy)


def point_row(p: Point) -> tuple[list[float], float]:
    x, y = p
    return [x * y, y * y, x, y, 1.0], -x * x


def tangent_row(p: Point, yp: float) -> tuple[list[float], float]:
    x, y = p
    return [y + x * yp, 2 * y * yp, 1.0, yp, 0.0], -2.0 * x


def solve_rows(rows: list[tuple[list[float], float]]) -> np.ndarray:
    """a1..a5 from five rows (3) / (8'): the paper's systems (10) and (13)."""
    m = np.array([r for r, _ in rows], dtype=float)
    b = np.array([v for _, v in rows], dtype=float)
    return np.linalg.solve(m, b)


def explicit(a, form: str, s):
    """The paper's explicit forms (2) / §3(2): y(x) for "y+"/"y-", x(y) for "x+"/"x-" (NaN where there is none)."""
    a1, a2, a3, a4, a5 = a
    s = np.asarray(s, dtype=float)
    sign = 1.0 if form.endswith("+") else -1.0
    with np.errstate(invalid="ignore"):
        if form.startswith("y"):
            b, c = a1 * s + a4, s * s + a3 * s + a5
            return (-b + sign * np.sqrt(b * b - 4 * a2 * c)) / (2 * a2)
        b, c = a1 * s + a3, a2 * s * s + a4 * s + a5
        return (-b + sign * np.sqrt(b * b - 4 * c)) / 2


@dataclass(frozen=True)
class CentralConic:
    """c + Q diag(p, q) (cos t, sin t) (ellipse) or c + Q diag(p, q) (s cosh t, sinh t) (hyperbola, branch s)."""

    coefficients: tuple[float, ...]
    centre: tuple[float, float]
    axes: tuple[tuple[float, float], tuple[float, float]]   # columns of Q
    p: float
    q: float
    hyperbola: bool
    branch: float = 1.0

    @classmethod
    def of(cls, a) -> "CentralConic":
        a1, a2, a3, a4, a5 = a
        A = np.array([[1.0, a1 / 2], [a1 / 2, a2]])
        b = np.array([a3, a4])
        if abs(np.linalg.det(A)) < 1e-12:
            raise ValueError("a parabola (a1^2 = 4 a2): not a central conic")
        c = -np.linalg.solve(A, b) / 2
        k = -(a5 + b @ c / 2)                    # l1 w1^2 + l2 w2^2 = k
        lam, Q = np.linalg.eigh(A)
        if np.sign(lam[0]) == np.sign(lam[1]):
            if k / lam[0] <= 0:
                raise ValueError("an empty or degenerate ellipse")
            return cls(tuple(a), tuple(c), (tuple(Q[:, 0]), tuple(Q[:, 1])), math.sqrt(k / lam[0]),
                       math.sqrt(k / lam[1]), False)
        if k == 0:
            raise ValueError("a degenerate hyperbola (two lines)")
        i, j = (0, 1) if k / lam[0] > 0 else (1, 0)         # w_i is the transverse axis
        return cls(tuple(a), tuple(c), (tuple(Q[:, i]), tuple(Q[:, j])), math.sqrt(k / lam[i]),
                   math.sqrt(-k / lam[j]), True)

    def with_branch(self, s: float) -> "CentralConic":
        return CentralConic(self.coefficients, self.centre, self.axes, self.p, self.q, self.hyperbola, s)

    def local(self, x, y) -> tuple[float, float]:
        dx, dy = x - self.centre[0], y - self.centre[1]
        (e1x, e1y), (e2x, e2y) = self.axes
        return dx * e1x + dy * e1y, dx * e2x + dy * e2y

    def at(self, t, order: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """The point (order 0) or its t-derivative of order 1, 2."""
        t = np.asarray(t, dtype=float)
        if self.hyperbola:
            u = [np.cosh, np.sinh][order % 2](t) * self.branch
            v = [np.sinh, np.cosh][order % 2](t)
        else:
            # cos t and sin t, then their first and second derivatives
            cos_derivatives: list[Callable[[np.ndarray], np.ndarray]] = [np.cos, lambda z: -np.sin(z),
                                                                          lambda z: -np.cos(z)]
            sin_derivatives: list[Callable[[np.ndarray], np.ndarray]] = [np.sin, np.cos, lambda z: -np.sin(z)]
            u = cos_derivatives[order](t)
            v = sin_derivatives[order](t)
        (e1x, e1y), (e2x, e2y) = self.axes
        u, v = self.p * u, self.q * v
        x0, y0 = (self.centre if order == 0 else (0.0, 0.0))
        return x0 + e1x * u + e2x * v, y0 + e1y * u + e2y * v

    def parameter(self, x: float, y: float) -> tuple[float, float]:
        """(t, distance): the parameter of the conic point nearest (x, y) (a hyperbola: on this branch)."""
        w1, w2 = self.local(x, y)
        t0 = math.asinh(w2 / self.q) if self.hyperbola else math.atan2(w2 / self.q, w1 / self.p)
        f = lambda t: float(np.hypot(*(np.subtract(self.at(t), (x, y)))))  # noqa: E731
        res = minimize_scalar(f, bounds=(t0 - 0.2, t0 + 0.2), method="bounded", options={"xatol": 1e-13})
        t = float(res.x) if res.fun < f(t0) else t0
        return t, f(t)

    def branch_of(self, x: float, y: float) -> float:
        return 1.0 if self.local(x, y)[0] >= 0 else -1.0


def span(conic: CentralConic, start: Point, end: Point, via: Point | None = None) -> tuple[float, float]:
    """(t0, t1) of the arc from ``start`` to ``end``: on an ellipse the arc through ``via`` (default the shorter)."""
    t0, _ = conic.parameter(*start)
    t1, _ = conic.parameter(*end)
    if conic.hyperbola:
        return t0, t1
    two_pi = 2 * math.pi
    forward = (t1 - t0) % two_pi                     # counter-clockwise in t
    if via is None:
        return (t0, t0 + forward) if forward <= math.pi else (t0, t0 + forward - two_pi)
    tv, _ = conic.parameter(*via)
    on_forward = (tv - t0) % two_pi <= forward
    return (t0, t0 + forward) if on_forward else (t0, t0 + forward - two_pi)
