"""Closed-form position analysis of a planar four-bar, for floats and CasADi symbols alike.

Every function here is pure and uses only ``casadi`` scalar maths (``ca.cos`` on a float returns a
float, on an ``SX``/``MX`` a symbol), so one definition serves the numeric check and the NLP.

Notation (seed 000, Fig. 2): ground pivots O (crank) and O' (rocker), moving joints A and B.

    O  = (0, 0)
    O' = l1 * (cos zeta, sin zeta)                 frame O'O, at angle zeta
    A  = l2 * (cos(zeta + theta), sin(zeta + theta))   crank OA, theta measured from OO'
    B  : |AB| = l3, |O'B| = l4, on the side ``branch`` of the directed line A -> O'

B is found without any inverse cosine: with d = |O'A| and e the unit vector A -> O',

    a  = (l3^2 - l4^2 + d^2) / (2 d)        (projection of AB on e)
    h2 = l3^2 - a^2                         (squared height of B above the line AO')
    B  = A + a e + branch * sqrt(h2) * n    (n = e rotated +90 deg)

h2 >= 0 is exactly the assembly condition |l3 - l4| <= d <= l3 + l4; it goes to zero at the toggle
(dead-centre) positions, where it is the quantity to watch instead of an arccos argument.
"""

from __future__ import annotations

import casadi as ca

Point = tuple  # (x, y): floats or CasADi scalars


def polar(length, angle) -> Point:
    """length * (cos angle, sin angle)."""
    return (length * ca.cos(angle), length * ca.sin(angle))


def rotate(v: Point, angle) -> Point:
    """v rotated counter-clockwise by ``angle`` (rad)."""
    c, s = ca.cos(angle), ca.sin(angle)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


def crank_pin(theta, l2, zeta) -> Point:
    """A = l2 * e(zeta + theta): the crank pin for crank angle theta measured from the frame line OO'."""
    return polar(l2, zeta + theta)


def rocker_pivot(l1, zeta) -> Point:
    """O' = l1 * e(zeta)."""
    return polar(l1, zeta)


def diagonal_sq(theta, l1, l2):
    """d^2 = |O'A|^2 = l1^2 + l2^2 - 2 l1 l2 cos(theta) (law of cosines in triangle O O' A)."""
    return l1 * l1 + l2 * l2 - 2.0 * l1 * l2 * ca.cos(theta)


def assembly_height_sq(theta, l1, l2, l3, l4):
    """h2 = l3^2 - a^2 with a = (l3^2 - l4^2 + d^2)/(2d): >= 0 iff the loop closes at theta."""
    d2 = diagonal_sq(theta, l1, l2)
    a = (l3 * l3 - l4 * l4 + d2) / (2.0 * ca.sqrt(d2))
    return l3 * l3 - a * a


def coupler_joint(theta, l1, l2, l3, l4, zeta, branch: int) -> tuple[Point, Point]:
    """(A, B) for crank angle theta; ``branch`` = +1 or -1 picks the assembly (side of A -> O')."""
    ax, ay = crank_pin(theta, l2, zeta)
    ox, oy = rocker_pivot(l1, zeta)
    dx, dy = ox - ax, oy - ay
    d2 = dx * dx + dy * dy
    d = ca.sqrt(d2)
    ex, ey = dx / d, dy / d
    a = (l3 * l3 - l4 * l4 + d2) / (2.0 * d)
    h = ca.sqrt(l3 * l3 - a * a)
    bx = ax + a * ex - branch * h * ey
    by = ay + a * ey + branch * h * ex
    return (ax, ay), (bx, by)


def transmission_angle(theta, l1, l2, l3, l4, zeta, branch: int):
    """mu = angle between coupler BA and rocker BO' (rad, in [0, pi]), via atan2 of cross and dot."""
    (ax, ay), (bx, by) = coupler_joint(theta, l1, l2, l3, l4, zeta, branch)
    ox, oy = rocker_pivot(l1, zeta)
    ux, uy = ax - bx, ay - by
    wx, wy = ox - bx, oy - by
    cross = ux * wy - uy * wx
    dot = ux * wx + uy * wy
    return ca.atan2(ca.fabs(cross), dot)


def crank_rotation_slacks(l1, l2, l3, l4) -> dict[str, object]:
    """Slacks of the three inequalities that let crank l2 turn fully (Grashof, crank shortest).

    l2 + l1 <= l3 + l4,  l2 + l3 <= l1 + l4,  l2 + l4 <= l1 + l3.  All three >= 0 is equivalent to
    "l2 is the shortest link and s + l <= p + q": a crank-rocker (or its change-point limit) when
    driven by l2 with l1 as frame. Linear in the lengths.  (synthesis.constraints.grashof states the same
    inequalities as its rule: the rule layer imports no kinematics.)
    """
    return {
        "frame": l3 + l4 - l2 - l1,
        "coupler": l1 + l4 - l2 - l3,
        "rocker": l1 + l3 - l2 - l4,
    }


def link_direction(p: Point, q: Point):
    """Angle of the vector p -> q from the +x axis (rad, atan2): the direction of a link."""
    return ca.atan2(q[1] - p[1], q[0] - p[0])


def rocker_angle(theta, l1, l2, l3, l4, zeta, branch: int):
    """Direction of the rocker O' -> B from the +x axis (rad) at crank angle theta (see coupler_joint)."""
    _, b = coupler_joint(theta, l1, l2, l3, l4, zeta, branch)
    return link_direction(rocker_pivot(l1, zeta), b)
