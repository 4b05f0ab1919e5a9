"""Double crank ABCD and clamp point M of the seed-001 picker (§2.1.2, Fig. 4, eq 1-2).

Our reading of eq (2) (problems/picker/PICKER.md): the frame AD leaves A at the angle -phi3 (phi3
below the +x axis), the crank AB makes the angle phi1 with AD (so its direction is phi1 - phi3, as in
eq 2), the coupler BC carries the clamp point M at |CM| = l5, CM being BC turned counter-clockwise by
phi4:

    M = C + l5 * e(angle(BC) + phi4),     C from the loop A-B-C-D closed on the side ``branch``.

Links: l1 = AB (crank, driven), l2 = BC (coupler), l3 = CD (follower crank), l4 = AD (frame).  This is
:mod:`synthesis.kinematics.fourbar` with O = A, O' = D, (l1, l2, l3, l4) -> (l4, l1, l2, l3) and
zeta = -phi3; machine frame: origin at the power-output bar O, x towards the tray, y up (mm).

The clamp's attitude (a key pose's, ``[key_poses]``) is the direction of the clamp arm C -> M, angle(BC) + phi4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from synthesis.kinematics import fourbar

#: order of the parameter vector p (mm, rad)
PARAMETERS = ("x_a", "y_a", "l1", "l2", "l3", "l4", "l5", "phi3", "phi4")


def loop(phi1, p, branch: int) -> tuple[fourbar.Point, fourbar.Point, fourbar.Point, fourbar.Point, fourbar.Point]:
    """(A, B - A, C - A, D - A, M - C) at crank angle phi1 (rad, from AD): the pivot A in the machine frame, the
    other joints from A, and the clamp arm C -> M (BC turned counter-clockwise by phi4, length l5); p in mm and rad
    (:data:`PARAMETERS`)."""
    xa, ya, l1, l2, l3, l4, l5, phi3, phi4 = (p[i] for i in range(9))
    (bx, by), (cx, cy) = fourbar.coupler_joint(phi1, l4, l1, l2, l3, -phi3, branch)
    dx, dy = fourbar.rocker_pivot(l4, -phi3)
    bc = fourbar.link_direction((bx, by), (cx, cy))
    return (xa, ya), (bx, by), (cx, cy), (dx, dy), fourbar.polar(l5, bc + phi4)


def joints(phi1, p, branch: int) -> dict[str, fourbar.Point]:
    """A, B, C, D, M at crank angle phi1 (rad, from AD); p in mm and rad (:data:`PARAMETERS`)."""
    (xa, ya), (bx, by), (cx, cy), (dx, dy), (mx, my) = loop(phi1, p, branch)
    return {"A": (xa, ya), "B": (xa + bx, ya + by), "C": (xa + cx, ya + cy), "D": (xa + dx, ya + dy),
            "M": (xa + cx + mx, ya + cy + my)}


def clamp_attitude(phi1, p, branch: int):
    """The clamp's attitude: the direction of the clamp arm C -> M (rigid on the coupler BC, turned from it by phi4),
    rad from +x counter-clockwise in (-pi, pi].  The clamp and the seedling it holds are fixed to the coupler while
    the linkage moves (seed 001 §2.1.2), so every line on them turns with CM: a target for the jaws or the seedling
    is a target for CM plus a fixed angle.  One expression for floats and CasADi symbols (the check reads it through
    :func:`attitude_function`, the NLP on its own symbols)."""
    mx, my = loop(phi1, p, branch)[4]
    return ca.atan2(my, mx)


def clamp_point(phi1, p, branch: int) -> fourbar.Point:
    return joints(phi1, p, branch)["M"]


@lru_cache(maxsize=4)
def clamp_function(branch: int) -> ca.Function:
    """(phi1, p) -> (M, dM/dphi1, d2M/dphi1^2, mu): clamp point (mm) and its derivatives by AD, and the
    transmission angle mu at C between CB and CD (rad, in [0, pi])."""
    phi1 = ca.SX.sym("phi1")
    p = ca.SX.sym("p", len(PARAMETERS))
    m = ca.vertcat(*clamp_point(phi1, p, branch))
    dm = ca.jacobian(m, phi1)
    ddm = ca.jacobian(dm, phi1)
    mu = fourbar.transmission_angle(phi1, p[5], p[2], p[3], p[4], -p[7], branch)
    return ca.Function(f"clamp_{'p' if branch > 0 else 'm'}", [phi1, p], [m, dm, ddm, mu],
                       ["phi1", "p"], ["M", "dM", "ddM", "mu"])


@lru_cache(maxsize=4)
def attitude_function(branch: int) -> ca.Function:
    """(phi1, p) -> the clamp's attitude (rad, :func:`clamp_attitude`)."""
    phi1 = ca.SX.sym("phi1")
    p = ca.SX.sym("p", len(PARAMETERS))
    return ca.Function(f"clamp_attitude_{'p' if branch > 0 else 'm'}", [phi1, p], [clamp_attitude(phi1, p, branch)],
                       ["phi1", "p"], ["attitude"])


@dataclass(frozen=True)
class DoubleCrank:
    """One picker linkage in spec units (mm, deg)."""

    x_a: float
    y_a: float
    l1: float
    l2: float
    l3: float
    l4: float
    l5: float
    phi3: float
    phi4: float
    branch: int = 1

    def parameters(self) -> np.ndarray:
        return np.array([self.x_a, self.y_a, self.l1, self.l2, self.l3, self.l4, self.l5,
                         math.radians(self.phi3), math.radians(self.phi4)])

    def grashof_slacks(self) -> np.ndarray:
        """Seed 001 eq (6) as slacks (>= 0 holds): l4 + x <= sum of the other two, x = l1, l2, l3."""
        return np.array(list(fourbar.crank_rotation_slacks(self.l1, self.l4, self.l2, self.l3).values()))


def clamp_states(dc: DoubleCrank, phi1_deg) -> dict[str, np.ndarray]:
    """M (2, N), dM/dphi1 (mm/rad), d2M/dphi1^2 and mu (deg) at crank angles phi1 (deg)."""
    phi = np.radians(np.atleast_1d(np.asarray(phi1_deg, dtype=float)))
    f = clamp_function(dc.branch).map(phi.size)
    m, dm, ddm, mu = (np.asarray(v) for v in f(phi.reshape(1, -1), dc.parameters()))
    return {"M": m.reshape(2, -1), "dM": dm.reshape(2, -1), "ddM": ddm.reshape(2, -1), "mu": np.degrees(mu.ravel())}


def clamp_attitudes(dc: DoubleCrank, phi1_deg) -> np.ndarray:
    """The clamp's attitude (N,) at crank angles phi1 (deg), deg in (-180, 180] (:func:`clamp_attitude`)."""
    phi = np.radians(np.atleast_1d(np.asarray(phi1_deg, dtype=float)))
    f = attitude_function(dc.branch).map(phi.size)
    return np.degrees(np.asarray(f(phi.reshape(1, -1), dc.parameters()), dtype=float).ravel())


def joint_positions(dc: DoubleCrank, phi1_deg: float) -> dict[str, list[float]]:
    pts = joints(math.radians(phi1_deg), dc.parameters(), dc.branch)
    return {k: [float(v[0]), float(v[1])] for k, v in pts.items()}


def assembles(dc: DoubleCrank, phi1_deg) -> bool:
    """True when the loop closes at every given crank angle (triangle B-C-D exists)."""
    phi = np.radians(np.atleast_1d(np.asarray(phi1_deg, dtype=float)))
    return min(closure_height_sq(dc, t) for t in phi) > 0.0


def closure_height_sq(dc: DoubleCrank, theta: float) -> float:
    """The closure's height^2 at crank angle theta; -inf where the crank pin lands on the far pivot (l1 = l4 at
    theta = 0: no triangle to close, the coupler's direction undefined -- a ZeroDivisionError took check down)."""
    try:
        return float(fourbar.assembly_height_sq(theta, dc.l4, dc.l1, dc.l2, dc.l3))
    except ZeroDivisionError:
        return -math.inf
