"""A closed claw path as a periodic uniform cubic B-spline, and its key points along the loop.

M(u), u in [0, 1) once round the loop, n control points P_0..P_{n-1} (indices mod n), knot spacing 1/n.
On span j (s = n u - j in [0, 1)):

    M = b0(s) P_j + b1(s) P_{j+1} + b2(s) P_{j+2} + b3(s) P_{j+3}
    b0 = (1 - s)^3 / 6, b1 = (3 s^3 - 6 s^2 + 4) / 6, b2 = (-3 s^3 + 3 s^2 + 3 s + 1) / 6, b3 = s^3 / 6

C2 everywhere (so the claw path has no curvature jump anywhere); M''' on span j is
n^3 (-P_j + 3 P_{j+1} - 3 P_{j+2} + P_{j+3}), so the smoothness energy sum_j |M'''_j|^2 / n is a
quadratic form in the control points.  Every sample is linear in the control points: M = B P.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from synthesis.errors import SpecError

_BASIS = (
    (lambda s: (1 - s) ** 3 / 6, lambda s: -(1 - s) ** 2 / 2, lambda s: 1 - s),
    (lambda s: (3 * s**3 - 6 * s**2 + 4) / 6, lambda s: (9 * s**2 - 12 * s) / 6, lambda s: 3 * s - 2),
    (lambda s: (-3 * s**3 + 3 * s**2 + 3 * s + 1) / 6, lambda s: (-9 * s**2 + 6 * s + 3) / 6, lambda s: -3 * s + 1),
    (lambda s: s**3 / 6, lambda s: s**2 / 2, lambda s: s),
)


def basis(n: int, u, order: int = 0) -> np.ndarray:
    """(len(u), n): row i holds the weights of the control points in d^order M / du^order at u_i."""
    u = np.atleast_1d(np.asarray(u, dtype=float)) % 1.0
    x = u * n
    j = np.minimum(np.floor(x).astype(int), n - 1)
    s = x - j
    out = np.zeros((u.size, n))
    for k in range(4):
        out[np.arange(u.size), (j + k) % n] += _BASIS[k][order](s) * n**order
    return out


def basis_at(n: int, u, order: int, spans):
    """(1, n) CasADi row: the weights of the control points in d^order M / du^order at a symbolic ``u`` that lies
    in one of the knot ``spans`` (j: u in [j/n, (j+1)/n)), chosen by ``if_else`` (the spline is C2, so the
    weights meet smoothly from span to span up to order 2)."""
    import casadi as ca

    x = u * n
    expr = None
    for j in sorted(spans, reverse=True):
        row = ca.SX.zeros(1, n)
        for k in range(4):
            row[(j + k) % n] += _BASIS[k][order](x - j) * n**order
        expr = row if expr is None else ca.if_else(x < j + 1, row, expr)
    return expr


def third_differences(n: int) -> np.ndarray:
    """(n, n): row j gives M''' on span j divided by n^3."""
    d = np.zeros((n, n))
    for j in range(n):
        for k, c in enumerate((-1.0, 3.0, -3.0, 1.0)):
            d[j, (j + k) % n] += c
    return d


def energy_matrix(n: int) -> np.ndarray:
    """H with sum_j |M'''_j|^2 / n = sum over x and y of c^T H c (c: one coordinate of the control points)."""
    d = third_differences(n) * n**3
    return d.T @ d / n


@dataclass(frozen=True)
class Keys:
    """Key points in time order with their parameters u (u of the first = 0), the fold and tangents."""

    names: tuple[str, ...]
    points: tuple[tuple[float, float], ...]
    u: tuple[float, ...]
    tangents: dict          # name -> unit direction (tx, ty)
    fold: str
    length: float           # chord length of the loop through the keys, mm

    def index(self, name: str) -> int:
        return self.names.index(name)


def keys_of(names, points: dict, tangents_deg: dict, fold: str, R: float, d: float) -> Keys:
    """Key points (the fold moved along OM onto |OM| = R - d, its tangent perpendicular to OM, on the
    side of the given direction) and chord-length parameters round the loop."""
    pts = []
    for name in names:
        x, y = points[name]
        if name == fold:
            rho = math.hypot(x, y)
            if rho == 0.0:          # no direction to move it along
                raise SpecError(f"points.{name} = [{x:g}, {y:g}]: the fold point lies on the arm's centre O, so it "
                                f"has no direction OM to be moved along onto |OM| = R - d; give it one")
            x, y = x * (R - d) / rho, y * (R - d) / rho
        pts.append((float(x), float(y)))
    tangents = {}
    for name, deg in tangents_deg.items():
        t = (math.cos(math.radians(deg)), math.sin(math.radians(deg)))
        if name == fold:
            x, y = pts[list(names).index(name)]
            nx, ny = -y, x                            # OM turned +90 deg
            sign = 1.0 if nx * t[0] + ny * t[1] >= 0 else -1.0
            norm = math.hypot(nx, ny)
            t = (sign * nx / norm, sign * ny / norm)
        tangents[name] = t
    chords = [math.dist(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    total = sum(chords)
    u = tuple(float(v) for v in np.concatenate([[0.0], np.cumsum(chords)[:-1] / total]))
    return Keys(tuple(names), tuple(pts), u, tangents, fold, total)
