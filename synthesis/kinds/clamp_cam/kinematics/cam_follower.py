"""Disc cam with a roller follower: pitch curve, working profile, pressure angle, curvature.

Pure functions of the follower displacement s(phi) and its phi-derivatives; they run on floats /
numpy arrays and on CasADi symbols alike.  Derivation (problems/clamp_cam/CAMS.md):

* Ground frame: cam centre at the origin, the cam turns counter-clockwise by phi (seed 001 eq 12
  has the same sense: its profile points are (r cos phi, -r sin phi)).  C(phi) is the roller
  centre in the ground frame, moved by the follower only.
* Inversion: in the cam frame the roller centre traces the pitch curve P(phi) = R(-phi) C(phi).
  With J the +90 deg rotation, P' = R(-phi) T and P'' = R(-phi) A where
      T = C' - J C,     A = C'' - 2 J C' - C.
* The pitch curve runs clockwise in the cam frame, so J T / |T| is its outward normal.  The
  roller circles' envelope is P -/+ r_roller J T/|T| (inner = the working profile of a disc cam
  under a spring, outer = the other flank of a groove).
* Signed curvature of the pitch curve, > 0 where it is convex: kappa = -(T x A) / |T|^3.
  Radius of curvature of the working profile: 1/kappa - r_roller (inner), 1/kappa + r_roller
  (outer); the inner envelope has a cusp (undercut) where 0 < 1/kappa < r_roller.
* Pressure angle: between the contact normal N = J T (the force line, friction neglected) and
  the velocity direction d of the roller centre as a point of the follower:
      alpha = atan2(d x N, d . N).
  For a translating follower this is tan(alpha) = (s' - e) / (s0 + s); for an oscillating one
  tan(alpha) = (l psi' - sigma (a cos(psi0 + psi) - l)) / (a sin(psi0 + psi)) (tests compare both).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import casadi as ca
import numpy as np


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


class _Ops:
    """The math functions of the backend the arguments live in."""

    sin: Callable[..., Any]
    cos: Callable[..., Any]
    sqrt: Callable[..., Any]
    acos: Callable[..., Any]
    atan2: Callable[..., Any]

    def __init__(self, symbolic: bool):
        self.sin, self.cos, self.sqrt = (ca.sin, ca.cos, ca.sqrt) if symbolic else (np.sin, np.cos, np.sqrt)
        self.acos = ca.acos if symbolic else np.arccos
        self.atan2 = ca.atan2 if symbolic else np.arctan2


def _ops(*xs) -> _Ops:
    return _Ops(_symbolic(*xs))


@dataclass(frozen=True)
class Translating:
    """Translating roller follower moving along +X, its line offset by ``offset`` to -Y.

    base_radius: smallest distance of the roller centre from the cam centre (pitch base circle).
    offset > 0 lowers the pressure angle on the rise of a counter-clockwise cam (tan a = (s' - e)/(s0 + s)).
    Displacement s in mm.
    """

    base_radius: Any
    offset: Any = 0.0

    def rest_distance(self):
        """s0 = sqrt(r0^2 - e^2): the roller centre's X at zero displacement."""
        return _ops(self.base_radius, self.offset).sqrt(self.base_radius**2 - self.offset**2)


@dataclass(frozen=True)
class Oscillating:
    """Oscillating roller follower: arm of length l pivoting at (a, 0); displacement s = arm angle in rad.

    The roller centre is C = (a - l cos g, sigma l sin g), g = psi0 + s, where psi0 puts it on the
    pitch base circle at s = 0: cos psi0 = (a^2 + l^2 - r0^2) / (2 a l).  ``side`` is sigma: +1 puts
    the roller on the +Y side of the line from the cam centre to the pivot.
    """

    base_radius: Any
    pivot_distance: Any
    arm_length: Any
    side: int = 1

    def rest_angle(self):
        a, l, r0 = self.pivot_distance, self.arm_length, self.base_radius
        return _ops(a, l, r0).acos((a**2 + l**2 - r0**2) / (2.0 * a * l))


Follower = Translating | Oscillating


@dataclass(frozen=True)
class RollerCentre:
    """Roller centre in the ground frame and its phi-derivatives; ``d`` = unit direction it moves in."""

    x: Any
    y: Any
    dx: Any
    dy: Any
    ddx: Any
    ddy: Any
    d: tuple


def roller_centre(f: Follower, s, ds, dds) -> RollerCentre:
    """C(phi), C'(phi), C''(phi) from the displacement s and its derivatives ds/dphi, d2s/dphi2."""
    if isinstance(f, Translating):
        zero = 0.0 * s
        x = f.rest_distance() + s
        return RollerCentre(x, zero - f.offset, ds, zero, dds, zero, (1.0 + zero, zero))
    o = _ops(s, f.base_radius, f.pivot_distance, f.arm_length)
    a, l, sig = f.pivot_distance, f.arm_length, f.side
    g = f.rest_angle() + s
    sg, cg = o.sin(g), o.cos(g)
    x, y = a - l * cg, sig * l * sg
    dx, dy = ds * l * sg, ds * sig * l * cg
    ddx = dds * l * sg + ds**2 * l * cg
    ddy = dds * sig * l * cg - ds**2 * sig * l * sg
    return RollerCentre(x, y, dx, dy, ddx, ddy, (sg, sig * cg))


def tangent(c: RollerCentre) -> tuple:
    """T = C' - J C (ground frame): the pitch curve's phi-derivative, rotated back by phi."""
    return c.dx + c.y, c.dy - c.x


def _second(c: RollerCentre) -> tuple:
    """A = C'' - 2 J C' - C: the pitch curve's second phi-derivative, rotated back by phi."""
    return c.ddx + 2.0 * c.dy - c.x, c.ddy - 2.0 * c.dx - c.y


def pressure_angle(c: RollerCentre):
    """Signed pressure angle, rad: positive when the contact normal leans ahead of the follower's motion."""
    tx, ty = tangent(c)
    nx, ny = -ty, tx                                  # N = J T, the contact normal
    dx, dy = c.d
    return _ops(c.x).atan2(dx * ny - dy * nx, dx * nx + dy * ny)


def pitch_curvature(c: RollerCentre):
    """Signed curvature of the pitch curve, 1/mm, > 0 where convex (seen from outside the cam)."""
    tx, ty = tangent(c)
    ax, ay = _second(c)
    speed = _ops(c.x).sqrt(tx**2 + ty**2)
    return -(tx * ay - ty * ax) / speed**3


def to_cam_frame(x, y, phi) -> tuple:
    """R(-phi) (x, y): a ground-frame point seen from the cam after it has turned by phi."""
    o = _ops(x, y, phi)
    cp, sp = o.cos(phi), o.sin(phi)
    return cp * x + sp * y, -sp * x + cp * y


def pitch_curve(c: RollerCentre, phi) -> tuple:
    """Roller-centre path in the cam frame (the 'theoretical profile')."""
    return to_cam_frame(c.x, c.y, phi)


def envelope(c: RollerCentre, phi, roller_radius, side: int = -1) -> tuple:
    """Envelope of the roller circles in the cam frame: side -1 inner (working profile), +1 outer."""
    tx, ty = tangent(c)
    norm = _ops(c.x).sqrt(tx**2 + ty**2)
    nx, ny = -ty / norm, tx / norm                    # outward unit normal, ground frame
    return to_cam_frame(c.x + side * roller_radius * nx, c.y + side * roller_radius * ny, phi)


def degrees(x):
    return x * (180.0 / math.pi)
