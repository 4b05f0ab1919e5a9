"""Dynamics of a spring-loaded roller follower on a disc cam turning at constant speed: the contact force over a
turn, the jump speed and the Hertz stress between roller and cam.

Pure functions of the follower geometry (:mod:`synthesis.kinds.clamp_cam.kinematics.cam_follower`) that run on
floats / numpy arrays and on CasADi symbols alike, so the check and the NLP read the same formulas.

**Equation of motion.**  One degree of freedom q: the displacement s (mm) of a translating follower or the arm
angle psi (rad) of an oscillating one, q = q(phi) prescribed by the cam while the roller touches it.  At constant
cam speed omega, q_t = q' omega and q_tt = q'' omega^2 (' = d/dphi).  The roller centre C moves by dC/dq = G d,
d its unit direction, G = 1 (translating, mm per mm) or the arm length l (oscillating, m per rad).  Friction
neglected, the cam pushes the roller along the common normal n at the contact point, which passes through the
roller centre; by virtual work the contact force F (N) enters the equation of motion as the generalised force
F n . dC/dq = F G cos(alpha), alpha the pressure angle (n . d = cos alpha):

    I q_tt = F G cos(alpha) - Q_spring(q) + Q_gravity(q)

    translating: I = m (kg, q_tt in m/s^2: q'' x 1e-3), Q_spring = F0 + k s (N; preload F0 at s = 0, k N/mm),
                 Q_gravity = m (g . d) (N; g the gravity vector in the cam's ground frame, d = +X)
    oscillating: I = J (kg m^2 about the pivot), Q_spring = T0 + k_t psi (N m; a torsional spring, preload T0 at
                 psi = 0), Q_gravity = m_arm (g . d) c (N m; the arm's centre of mass at c m from the pivot on the
                 line to the roller centre, whose velocity is c psi_t d)

so that

    F(phi, omega) = A(phi) + B(phi) omega^2,   A = (Q_spring - Q_gravity) / (G cos alpha),
                                               B = I q'' / (G cos alpha)

(the roller's own spin inertia and the guide's friction are left out).  F >= 0 is contact; F < 0 is the pull the
cam would have to exert to keep the follower on its profile, which it cannot: the follower leaves the cam.

**Jump speed.**  G cos(alpha) > 0 on a working cam (|alpha| < 90 deg), so F has the sign of
A G cos(alpha) + B G cos(alpha) omega^2 = (Q_spring - Q_gravity) + I q'' omega^2.  Where q'' >= 0 (the follower
accelerates away from the cam) F only grows with omega; where q'' < 0 (the spring must decelerate it) F falls
linearly in omega^2 and reaches 0 at omega^2 = (Q_spring - Q_gravity) / (-I q'').  The follower first leaves the
cam at the smallest such speed over the turn:

    omega_jump^2 = min over phi with q''(phi) < 0 of (Q_spring - Q_gravity)(phi) / (-I q''(phi))

(closed form: the pressure angle and the lever scale the force, not where it vanishes).  If Q_spring - Q_gravity
<= 0 somewhere the spring does not hold the follower even at rest: omega_jump = 0; if q'' >= 0 over the whole turn
nothing ever pulls it off: omega_jump = infinity.

**Hertz stress.**  Roller (radius r, width L) on the cam's working profile: two cylinders in line contact
(K. L. Johnson, Contact Mechanics, Cambridge 1985, section 4.3, contact of cylinders: half-width
a^2 = 4 P R / (pi E*), peak pressure p0 = 2 P / (pi a), P the load per unit length),
the peak pressure

    sigma_max = p0 = sqrt(F E* / (pi L R*)),   1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2,   1/R* = 1/r + 1/rho_w

with rho_w the working profile's radius of curvature (> 0 convex, < 0 concave).  From the pitch curve's signed
curvature kappa (> 0 convex; the working profile is the inner envelope, rho_w = 1/kappa - r):

    1/R* = 1/r + kappa / (1 - kappa r)  =>  R* = r (1 - kappa r)

smooth through inflections (kappa = 0: R* = r, a flat cam) and concave arcs (kappa < 0: R* > r), zero at the
undercut cusp (kappa r = 1).  Units: F N, L and R* mm, E MPa (N/mm^2) give sigma in MPa.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from synthesis.kinds.clamp_cam.kinematics import cam_follower as cf

#: mm -> m
MM = 1e-3


def is_symbolic(*xs) -> bool:
    """Whether any argument is a CasADi symbol or expression."""
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


@dataclass(frozen=True)
class FollowerBody:
    """Mass, spring and gravity of the follower (floats or CasADi symbols).

    translating: ``inertia`` = mass kg, ``preload`` N at s = 0, ``stiffness`` N/mm, ``gravity_mass`` = the mass,
    ``gravity_arm`` unused (1).  oscillating: ``inertia`` kg m^2 about the pivot, ``preload`` N m at psi = 0,
    ``stiffness`` N m/rad, ``gravity_mass`` kg of the arm, ``gravity_arm`` m from the pivot to its centre of mass.
    ``gravity``: (gx, gy) m/s^2 in the cam's ground frame (cam centre at the origin, the follower along +X).
    """

    inertia: Any
    preload: Any
    stiffness: Any
    gravity: tuple[float, float] = (0.0, 0.0)
    gravity_mass: Any = 0.0
    gravity_arm: Any = 1.0


@dataclass(frozen=True)
class ContactLoads:
    """The follower's loads at sampled cam angles: generalised (N for a translating follower, N m for an
    oscillating one) and the contact force F = A + B omega^2 along the common normal (N)."""

    spring: Any              # Q_spring(q)
    gravity: Any             # Q_gravity(q)
    inertia_per_omega2: Any  # I q'' (generalised load per (rad/s)^2)
    lever: Any               # G: 1 (translating) or the arm length, m
    cos_alpha: Any           # cosine of the pressure angle

    @property
    def static(self):
        """A(phi): the contact force at standstill, N."""
        return (self.spring - self.gravity) / (self.lever * self.cos_alpha)

    @property
    def per_omega2(self):
        """B(phi): the contact force's change per (rad/s)^2 of cam speed, N s^2."""
        return self.inertia_per_omega2 / (self.lever * self.cos_alpha)

    def force(self, omega):
        """The contact force at cam speed omega (rad/s), N."""
        return self.static + self.per_omega2 * omega**2

    def inertia(self, omega):
        """The generalised inertia load I q_tt at omega (N or N m)."""
        return self.inertia_per_omega2 * omega**2


def normal_cosine(c: cf.RollerCentre):
    """cos(alpha) = d . n: the follower's direction of motion against the contact normal N = J T (unit)."""
    tx, ty = cf.tangent(c)
    nx, ny = -ty, tx
    dx, dy = c.d
    norm = ca.sqrt(nx**2 + ny**2) if is_symbolic(nx, ny) else np.sqrt(nx**2 + ny**2)
    return (dx * nx + dy * ny) / norm


def contact_loads(follower: cf.Follower, body: FollowerBody, c: cf.RollerCentre, s, dds) -> ContactLoads:
    """The loads at displacement s and d2s/dphi2 (model units: mm or rad) with roller centre ``c``."""
    gx, gy = body.gravity
    dx, dy = c.d
    along = gx * dx + gy * dy                     # g . d, m/s^2
    spring = body.preload + body.stiffness * s
    if isinstance(follower, cf.Translating):
        inertia = body.inertia * dds * MM
        gravity = body.gravity_mass * along
        lever = 1.0
    else:
        inertia = body.inertia * dds
        gravity = body.gravity_mass * along * body.gravity_arm
        lever = follower.arm_length * MM
    return ContactLoads(spring, gravity, inertia, lever, normal_cosine(c))


def jump_speed(spring_minus_gravity, inertia_per_omega2) -> tuple[float, int | None]:
    """(omega_jump rad/s, the sample where contact is first lost) over sampled generalised loads (numbers):
    0.0 where the spring does not hold the follower at rest (that sample), ``inf`` where nothing decelerates the
    follower (None).  See the module docstring for the closed form."""
    held = np.asarray(spring_minus_gravity, dtype=float).ravel()
    b = np.asarray(inertia_per_omega2, dtype=float).ravel()
    if held.size and float(np.min(held)) <= 0.0:
        return 0.0, int(np.argmin(held))
    pulled = b < 0.0
    if not np.any(pulled):
        return math.inf, None
    ratio = np.full(held.shape, np.inf)
    ratio[pulled] = held[pulled] / -b[pulled]
    k = int(np.argmin(ratio))
    return math.sqrt(float(ratio[k])), k


def effective_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """E* of two elastic bodies in contact, MPa: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2."""
    return 1.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2)


def relative_radius(kappa, roller_radius):
    """R* = r (1 - kappa r), mm: the roller against the working profile, kappa the pitch curve's signed curvature
    (1/mm, > 0 convex)."""
    return roller_radius * (1.0 - kappa * roller_radius)


def hertz_stress(force, length: float, radius, e_star: float):
    """Peak line-contact pressure sqrt(F E* / (pi L R*)), MPa (F N, L and R* mm, E* MPa).  On numbers: 0 where
    F <= 0 (no contact), infinite where R* <= 0 (a cusp) and F > 0; on symbols the formula with F clipped at 0."""
    if is_symbolic(force, radius):
        return ca.sqrt(ca.fmax(force, 0.0) * e_star / (math.pi * length * radius))
    f, r = np.broadcast_arrays(np.atleast_1d(np.asarray(force, dtype=float)),
                               np.atleast_1d(np.asarray(radius, dtype=float)))
    pressed = np.maximum(f, 0.0)
    out = np.where(pressed > 0.0, np.inf, 0.0)
    ok = r > 0.0
    out[ok] = np.sqrt(pressed[ok] * e_star / (math.pi * length * r[ok]))
    return out


def hertz_force(stress, length: float, radius, e_star: float):
    """The contact force at which the peak pressure reaches ``stress`` (MPa) at relative radius R* (mm):
    sigma^2 pi L R* / E*, N.  Linear in R*: the NLP's smooth form of sigma_max <= limit."""
    return stress**2 * math.pi * length * radius / e_star
