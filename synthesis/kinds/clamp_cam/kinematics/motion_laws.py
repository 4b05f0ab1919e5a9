"""Normalised cam motion laws: s(u) on u in [0, 1] with s(0) = 0, s(1) = 1, zero velocity at both ends.

A law is a list of pieces on consecutive u-intervals.  Each piece gives displacement, velocity,
acceleration and jerk (derivatives with respect to u) in closed form, written out by hand: the
tests differentiate ``s`` with CasADi AD and compare with these formulas.  Every function works
on floats / numpy arrays and on CasADi symbols alike (the backend follows the argument's type).

Physical follower motion over a segment of angle beta (rad) and stroke h:
    s(phi) = h s(u),  ds/dphi = h v(u) / beta,  d2s/dphi2 = h a(u) / beta^2,  u = (phi - phi0) / beta
and in time at crank speed omega (rad/s): velocity x omega, acceleration x omega^2.

Laws (coefficients C_v = max v, C_a = max |a|):
  cycloidal (sine acceleration, seed 001 eq 11): a = 2 pi sin(2 pi u)            C_v 2,     C_a 6.283
  poly345:    s = 10 u^3 - 15 u^4 + 6 u^5                                       C_v 1.875, C_a 5.774
  modified_trapezoid: sine ramps over u in [0,1/8], [3/8,5/8], [7/8,1]; flat between   C_v 2,     C_a 4.888
  modified_sine: quarter-wave 4 pi over [0,1/8] and [7/8,1], 4 pi/3 wave between  C_v 1.760, C_a 5.528
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

TWO_PI = 2.0 * math.pi


def _symbolic(u) -> bool:
    return isinstance(u, (ca.SX, ca.MX))


def _sin(u):
    return ca.sin(u) if _symbolic(u) else np.sin(u)


def _cos(u):
    return ca.cos(u) if _symbolic(u) else np.cos(u)


@dataclass(frozen=True)
class TrigPiece:
    """Acceleration c0 + c1 sin(w t) + c2 cos(w t), t = u - u0, integrated from (s0, v0) at u0."""

    u0: float
    u1: float
    c0: float
    c1: float
    c2: float
    w: float
    s0: float = 0.0
    v0: float = 0.0

    def jerk(self, t):
        return self.w * (self.c1 * _cos(self.w * t) - self.c2 * _sin(self.w * t))

    def acc(self, t):
        return self.c0 + self.c1 * _sin(self.w * t) + self.c2 * _cos(self.w * t)

    def vel(self, t):
        w = self.w
        return self.v0 + self.c0 * t + self.c1 * (1.0 - _cos(w * t)) / w + self.c2 * _sin(w * t) / w

    def pos(self, t):
        w = self.w
        return (self.s0 + self.v0 * t + 0.5 * self.c0 * t * t
                + self.c1 * (t / w - _sin(w * t) / w**2) + self.c2 * (1.0 - _cos(w * t)) / w**2)

    def scaled(self, k: float) -> "TrigPiece":
        return TrigPiece(self.u0, self.u1, k * self.c0, k * self.c1, k * self.c2, self.w, k * self.s0, k * self.v0)

    def started_at(self, s0: float, v0: float) -> "TrigPiece":
        return TrigPiece(self.u0, self.u1, self.c0, self.c1, self.c2, self.w, s0, v0)


@dataclass(frozen=True)
class PolyPiece:
    """Displacement sum_k c_k t^k, t = u - u0."""

    u0: float
    u1: float
    coeffs: tuple[float, ...]

    def _eval(self, t, order: int):
        out = 0.0 * t
        for k, c in enumerate(self.coeffs):
            if k < order:
                continue
            fall = math.prod(range(k - order + 1, k + 1))
            out = out + fall * c * t ** (k - order)
        return out

    def pos(self, t):
        return self._eval(t, 0)

    def vel(self, t):
        return self._eval(t, 1)

    def acc(self, t):
        return self._eval(t, 2)

    def jerk(self, t):
        return self._eval(t, 3)


Piece = TrigPiece | PolyPiece


def _chain(accelerations: list[TrigPiece]) -> tuple[TrigPiece, ...]:
    """Integrate acceleration pieces from rest at u = 0 and scale so that s(1) = 1."""
    pieces, s, v = [], 0.0, 0.0
    for p in accelerations:
        p = p.started_at(s, v)
        t = p.u1 - p.u0
        s, v = float(p.pos(t)), float(p.vel(t))
        pieces.append(p)
    return tuple(p.scaled(1.0 / s) for p in pieces)


@dataclass(frozen=True)
class MotionLaw:
    """A normalised rise law made of pieces covering [0, 1]; outside [0, 1] it is held at its ends."""

    name: str
    pieces: tuple[Piece, ...]

    def _select(self, u, method: str):
        if _symbolic(u):
            out = getattr(self.pieces[-1], method)(u - self.pieces[-1].u0)
            for p in reversed(self.pieces[:-1]):
                out = ca.if_else(u < p.u1, getattr(p, method)(u - p.u0), out)
            return out
        u = np.asarray(u, dtype=float)
        out = np.zeros_like(u)
        for p in self.pieces:
            inside = (u >= p.u0) & (u <= p.u1)
            out = np.where(inside, getattr(p, method)(u - p.u0), out)
        return out if out.ndim else float(out)

    def s(self, u):
        """Displacement (fraction of the stroke)."""
        return self._select(u, "pos")

    def v(self, u):
        """ds/du."""
        return self._select(u, "vel")

    def a(self, u):
        """d2s/du2."""
        return self._select(u, "acc")

    def j(self, u):
        """d3s/du3."""
        return self._select(u, "jerk")

    @cached_property
    def peaks(self) -> dict[str, float]:
        """C_v, C_a, C_j: the largest |v|, |a|, |j| over [0, 1] (dense sampling plus the piece ends)."""
        u = np.unique(np.concatenate([np.linspace(0.0, 1.0, 20001)] + [[p.u0, p.u1] for p in self.pieces]))
        return {"velocity": float(np.max(np.abs(self.v(u)))), "acceleration": float(np.max(np.abs(self.a(u)))),
                "jerk": float(np.max(np.abs(self.j(u))))}


def cycloidal() -> MotionLaw:
    """Sine-acceleration law of seed 001 eq (11): s = u - sin(2 pi u) / (2 pi)."""
    return MotionLaw("cycloidal", _chain([TrigPiece(0.0, 1.0, 0.0, TWO_PI, 0.0, TWO_PI)]))


def poly345() -> MotionLaw:
    """3-4-5 polynomial: s = 10 u^3 - 15 u^4 + 6 u^5 (zero velocity and acceleration at both ends)."""
    return MotionLaw("poly345", (PolyPiece(0.0, 1.0, (0.0, 0.0, 0.0, 10.0, -15.0, 6.0)),))


def modified_trapezoid() -> MotionLaw:
    """Modified trapezoid: constant acceleration with quarter-sine ramps (period 1/2) at its corners."""
    w = 4.0 * math.pi
    return MotionLaw("modified_trapezoid", _chain([
        TrigPiece(0.0, 0.125, 0.0, 1.0, 0.0, w),           # ramp up: sin(4 pi u)
        TrigPiece(0.125, 0.375, 1.0, 0.0, 0.0, w),         # flat
        TrigPiece(0.375, 0.625, 0.0, 0.0, 1.0, w),         # cos through zero at u = 1/2 down to -1
        TrigPiece(0.625, 0.875, -1.0, 0.0, 0.0, w),        # flat
        TrigPiece(0.875, 1.0, 0.0, 0.0, -1.0, w),          # back to zero
    ]))


def modified_sine() -> MotionLaw:
    """Modified sine: quarter waves of period 1/2 at the ends, one half wave of period 3/2 between."""
    w_end, w_mid = 4.0 * math.pi, 4.0 * math.pi / 3.0
    return MotionLaw("modified_sine", _chain([
        TrigPiece(0.0, 0.125, 0.0, 1.0, 0.0, w_end),
        TrigPiece(0.125, 0.875, 0.0, 0.0, 1.0, w_mid),
        TrigPiece(0.875, 1.0, 0.0, 0.0, -1.0, w_end),
    ]))


#: closed-form families a spec may name (the optimised B-spline law lives in synthesis.kinds.clamp_cam.bspline_law)
CLOSED_FORM = {"cycloidal": cycloidal, "poly345": poly345, "modified_trapezoid": modified_trapezoid,
               "modified_sine": modified_sine}


def law(name: str) -> MotionLaw:
    return CLOSED_FORM[name]()
