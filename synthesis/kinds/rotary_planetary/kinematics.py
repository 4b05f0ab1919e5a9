"""Kinematics of the rotary (planetary) transplanting mechanism with non-circular gears, on floats and CasADi
symbols alike (problems/rotary_planetary/NOTES.md derives every relation used here).

Machine frame: origin on the carrier (gearbox) axis, which is also the fixed sun gear's axis; x points to the
rear of the machine, y up; the machine travels towards -x, so a point's ground-frame position is
x_ground = x_machine - V t (V the forward speed).  The carrier turns counter-clockwise at constant speed, its
angle phi measured from +x (phi = omega t): at the bottom of its circle the carrier moves rearwards, as the
planting claw must.

Gear train of one arm: sun (fixed) -> idler gear 1 | idler gear 2 (one compound idler: two pitch curves on one
shaft) -> planet, the three centres on one line of the carrier at centre distances a1 (sun-idler) and a2
(idler-planet).  The laws, each a Fourier series of the carrier angle (rad):

    idler rotation relative to the carrier   theta2(phi) = phi + G(phi)
    planet rotation relative to the carrier  theta3(phi) = -phi + F(phi)

so the idler turns once and the planet once backwards per carrier turn: the train's integer ratio is 1:1 and
the planet's absolute angle, phi + theta3 = F(phi), has no mean drift -- the arm keeps its attitude on average
and the claw's attitude along the loop is F.  Both arms (180 deg apart) trace the same loop.

Pair k has centre distance a_k and ratio i_k = |d theta_driven| / |d theta_driver| (carrier frame):
    i1 = 1 + G',  i2 = (1 - F') / (1 + G'),   r_driver = a i / (1 + i),  r_driven = a / (1 + i).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import casadi as ca
import numpy as np


def is_symbolic(*values) -> bool:
    """Whether any value (or an entry of a sequence value) is a CasADi symbol or expression."""
    for v in values:
        items = v if isinstance(v, (list, tuple)) else [v]
        if any(isinstance(x, (ca.SX, ca.MX)) for x in items):
            return True
    return False


@dataclass(frozen=True)
class Train:
    """One arm's train and arm, in mm and rad (numbers or CasADi scalars).

    ``planet_cos[k-1], planet_sin[k-1]``: harmonic k of F (the planet's rotation beyond its mean, rad);
    ``idler_cos, idler_sin``: of G.  ``arm_angle``: direction of the tip from the planet's centre when F = 0,
    from +x counter-clockwise; ``claw_angle``: the claw's direction relative to that arm line."""

    a1: Any
    a2: Any
    planet_cos: Sequence[Any]
    planet_sin: Sequence[Any]
    idler_cos: Sequence[Any]
    idler_sin: Sequence[Any]
    arm_length: Any
    arm_angle: Any
    claw_angle: Any

    @property
    def symbolic(self) -> bool:
        return is_symbolic(self.a1, self.a2, list(self.planet_cos), list(self.planet_sin), list(self.idler_cos),
                           list(self.idler_sin), self.arm_length, self.arm_angle, self.claw_angle)

    @property
    def carrier_radius(self):
        """Sun centre to planet centre (the centres are collinear), mm."""
        return self.a1 + self.a2


class Ops:
    """The maths of one evaluation: numpy on numbers (vectorised over the angles), CasADi on symbols."""

    def __init__(self, symbolic: bool):
        self.m = ca if symbolic else np
        self.symbolic = symbolic

    def atan(self, x):
        return ca.atan(x) if self.symbolic else np.arctan(x)

    def angles(self, phi):
        if self.symbolic and not isinstance(phi, (ca.SX, ca.MX)):
            return ca.DM(np.atleast_1d(np.asarray(phi, dtype=float)))
        return phi if self.symbolic else np.asarray(phi, dtype=float)


def ops_of(train: Train, phi=None) -> Ops:
    return Ops(train.symbolic or is_symbolic(phi))


def fourier(o: Ops, cos: Sequence[Any], sin: Sequence[Any], phi, order: int = 0):
    """d^order/dphi^order of sum_k cos_k cos(k phi) + sin_k sin(k phi), k = 1, 2, ..."""
    total = 0.0 * phi
    for k, (a, b) in enumerate(zip(cos, sin), start=1):
        # the n-th derivative of cos(k phi) is k^n cos(k phi + n pi/2)
        shift = order * math.pi / 2.0
        scale = float(k) ** order
        total = total + scale * (a * o.m.cos(k * phi + shift) + b * o.m.sin(k * phi + shift))
    return total


def planet_law(train: Train, phi, order: int = 0):
    """F or its derivatives: the planet's (and arm's) absolute rotation beyond its mean, rad."""
    o = ops_of(train, phi)
    return fourier(o, train.planet_cos, train.planet_sin, o.angles(phi), order)


def idler_law(train: Train, phi, order: int = 0):
    """G or its derivatives: the idler's rotation relative to the carrier beyond phi, rad."""
    o = ops_of(train, phi)
    return fourier(o, train.idler_cos, train.idler_sin, o.angles(phi), order)


def idler_turn(train: Train, phi):
    """theta2 = phi + G(phi): the idler's rotation relative to the carrier, rad."""
    return ops_of(train, phi).angles(phi) + idler_law(train, phi)


def tip(train: Train, phi):
    """The claw tip (x, y), mm, machine frame, at carrier angle(s) phi (rad)."""
    o = ops_of(train, phi)
    phi = o.angles(phi)
    alpha = train.arm_angle + fourier(o, train.planet_cos, train.planet_sin, phi)
    r = train.carrier_radius
    return (r * o.m.cos(phi) + train.arm_length * o.m.cos(alpha),
            r * o.m.sin(phi) + train.arm_length * o.m.sin(alpha))


def tip_rate(train: Train, phi):
    """d tip / d phi (mm/rad), machine frame; times omega it is the tip's velocity."""
    o = ops_of(train, phi)
    phi = o.angles(phi)
    alpha = train.arm_angle + fourier(o, train.planet_cos, train.planet_sin, phi)
    dalpha = fourier(o, train.planet_cos, train.planet_sin, phi, 1)
    r = train.carrier_radius
    return (-r * o.m.sin(phi) - train.arm_length * dalpha * o.m.sin(alpha),
            r * o.m.cos(phi) + train.arm_length * dalpha * o.m.cos(alpha))


def tip_curvature_rate(train: Train, phi):
    """d^2 tip / d phi^2 (mm/rad^2), machine frame; times omega^2 it is the tip's acceleration (constant omega)."""
    o = ops_of(train, phi)
    phi = o.angles(phi)
    alpha = train.arm_angle + fourier(o, train.planet_cos, train.planet_sin, phi)
    d1 = fourier(o, train.planet_cos, train.planet_sin, phi, 1)
    d2 = fourier(o, train.planet_cos, train.planet_sin, phi, 2)
    r, arm = train.carrier_radius, train.arm_length
    return (-r * o.m.cos(phi) - arm * (d2 * o.m.sin(alpha) + d1**2 * o.m.cos(alpha)),
            -r * o.m.sin(phi) + arm * (d2 * o.m.cos(alpha) - d1**2 * o.m.sin(alpha)))


def claw_attitude(train: Train, phi):
    """The claw's absolute direction (root to tip), rad from +x counter-clockwise (pointing down: -pi/2)."""
    return train.arm_angle + train.claw_angle + planet_law(train, phi)


def planet_centre(train: Train, phi):
    o = ops_of(train, phi)
    phi = o.angles(phi)
    return train.carrier_radius * o.m.cos(phi), train.carrier_radius * o.m.sin(phi)


def idler_centre(train: Train, phi):
    o = ops_of(train, phi)
    phi = o.angles(phi)
    return train.a1 * o.m.cos(phi), train.a1 * o.m.sin(phi)


# --- the pitch curves -------------------------------------------------------------------------------------------
# A quantity with its first two derivatives in phi (a "jet"), for the curvature of the pitch curves.

Jet = tuple


def jet_ratio(n: Jet, d: Jet) -> Jet:
    """(n / d) and its two derivatives."""
    q = n[0] / d[0]
    q1 = (n[1] - q * d[1]) / d[0]
    q2 = (n[2] - 2.0 * q1 * d[1] - q * d[2]) / d[0]
    return q, q1, q2


def radius_jets(a, i: Jet) -> tuple[Jet, Jet]:
    """Driver radius a i / (1 + i) and driven radius a / (1 + i) with their phi-derivatives."""
    s = 1.0 + i[0]
    driven = (a / s, -a * i[1] / s**2, a * (2.0 * i[1] ** 2 / s**3 - i[2] / s**2))
    return (a - driven[0], -driven[1], -driven[2]), driven


@dataclass(frozen=True)
class PitchCurve:
    """One gear's pitch curve at carrier angles phi: polar angle in the gear's own frame (rad) and radius (mm),
    with their phi-derivatives (``angle`` and ``radius`` are jets)."""

    angle: Jet
    radius: Jet

    def curvature(self, o: Ops):
        """Signed curvature (1/mm): > 0 convex, < 0 concave (the curve traversed counter-clockwise in its frame)."""
        r, r1, r2 = self.radius
        _, b1, b2 = self.angle
        cross = 2.0 * r1**2 * b1 + r * r1 * b2 - r * r2 * b1 + r**2 * b1**3
        speed = o.m.sqrt(r1**2 + r**2 * b1**2)
        # b1 keeps one sign over a turn (the ratio rules); sign(b1) orients the traversal counter-clockwise
        return cross * (b1 / o.m.sqrt(b1**2)) / speed**3

    def normal_angle(self, o: Ops):
        """Angle between the pitch curve's normal at the contact point and the line of centres, rad: the
        pressure-angle deviation of the teeth cut on it (0 on a circle)."""
        r, r1, _ = self.radius
        return o.atan(r1 / (r * self.angle[1]))


@dataclass(frozen=True)
class Pair:
    ratio: Jet            # i_k and its phi-derivatives
    centre_distance: Any
    driver: PitchCurve
    driven: PitchCurve


def pairs(train: Train, phi) -> tuple[Pair, Pair]:
    """The two meshing pairs at carrier angles phi: (sun -> idler gear 1, idler gear 2 -> planet)."""
    o = ops_of(train, phi)
    phi = o.angles(phi)
    g = [fourier(o, train.idler_cos, train.idler_sin, phi, n) for n in range(4)]
    f = [fourier(o, train.planet_cos, train.planet_sin, phi, n) for n in range(4)]
    i1 = (1.0 + g[1], g[2], g[3])
    i2 = jet_ratio((1.0 - f[1], -f[2], -f[3]), i1)
    sun_r, idler1_r = radius_jets(train.a1, i1)
    idler2_r, planet_r = radius_jets(train.a2, i2)
    zero = 0.0 * phi
    # polar angles in each gear's frame: the sun's is the machine frame (it does not turn); the idler turns by
    # theta2 = phi + G relative to the carrier and meets the sun at the carrier direction + pi, the planet at +0;
    # the planet turns by theta3 = -phi + F and meets the idler at + pi
    sun = PitchCurve((phi, zero + 1.0, zero), sun_r)
    idler1 = PitchCurve((math.pi - phi - g[0], -i1[0], -g[2]), idler1_r)
    idler2 = PitchCurve((-phi - g[0], -i1[0], -g[2]), idler2_r)
    planet = PitchCurve((math.pi + phi - f[0], 1.0 - f[1], -f[2]), planet_r)
    return Pair(i1, train.a1, sun, idler1), Pair(i2, train.a2, idler2, planet)


def harmonics_of(design: dict, law: str) -> int:
    """How many harmonics a design's law has (``planet`` or ``idler``): its ``<law>_cos_k`` entries."""
    k = 0
    while f"{law}_cos_{k + 1}" in design:
        k += 1
    return k


def train_from_design(design: dict) -> Train:
    """The train of a design in spec units (mm, deg; numbers or symbols), in mm and rad."""
    rad = math.pi / 180.0

    def law(name: str, part: str) -> list:
        return [design[f"{name}_{part}_{k}"] * rad for k in range(1, harmonics_of(design, name) + 1)]

    return Train(design["centre_distance_1"], design["centre_distance_2"], law("planet", "cos"),
                 law("planet", "sin"), law("idler", "cos"), law("idler", "sin"), design["arm_length"],
                 design["arm_angle"] * rad, design["claw_angle"] * rad)


def turn_grid(n: int) -> np.ndarray:
    """n carrier angles evenly over one turn, [0, 2 pi)."""
    return np.arange(n) * (2.0 * math.pi / n)
