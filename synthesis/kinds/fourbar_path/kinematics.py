"""Coupler point of a general four-bar in the path-synthesis variables of the literature.

The variables are those of the standard benchmark formulation (Cabrera, Simon & Prado 2002 and the
papers that compare against it): links r1 (frame), r2 (input crank), r3 (coupler), r4 (output
link), the coupler point (rcx, rcy), the input pivot (x0, y0) and the frame angle theta0.

    O  = (x0, y0)                                  input pivot
    O' = O + r1 e(theta0)                          output pivot
    A  = O + r2 e(theta0 + theta2)                 crank pin; theta2 measured from O -> O', counter-clockwise
    B  : |AB| = r3, |O'B| = r4                     fourbar.coupler_joint, no inverse cosine
    P  = A + rcx u + rcy v                         u = (B - A)/r3, v = u turned +90 deg

Branch: "open" is B on the left of the directed line A -> O' (fourbar branch +1). At theta2 = 90
deg that puts B on the other side of the diagonal AO' from O: the links do not cross. "crossed"
is the mirror assembly (branch -1). A linkage that turns fully never changes branch.

Every function works on floats (numpy arrays included) and on CasADi symbols.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from synthesis.kinematics import fourbar

#: the design variables in result.json order (theta0 in deg there, in rad inside ``p``)
VARIABLES = ("r1", "r2", "r3", "r4", "rcx", "rcy", "x0", "y0", "theta0")

#: the assembly's name (result.json ``facts.branch``; the spec writes [linkage] branch = 1 | -1) -> its sign
BRANCHES = {"open": 1, "crossed": -1}


def coupler_point(theta2, p, branch: int) -> fourbar.Point:
    """P(theta2) for p = (r1, r2, r3, r4, rcx, rcy, x0, y0, theta0[rad]); ``branch`` = +1 open, -1 crossed."""
    r1, r2, r3, r4, rcx, rcy, x0, y0, theta0 = (p[i] for i in range(9))
    (ax, ay), (bx, by) = fourbar.coupler_joint(theta2, r1, r2, r3, r4, theta0, branch)
    ux, uy = (bx - ax) / r3, (by - ay) / r3
    return (x0 + ax + rcx * ux - rcy * uy, y0 + ay + rcx * uy + rcy * ux)


def joints(theta2, p, branch: int) -> dict[str, fourbar.Point]:
    """Every joint of the linkage (O, A, B, O', P), for drawing it."""
    r1, r2, r3, r4, rcx, rcy, x0, y0, theta0 = (p[i] for i in range(9))
    (ax, ay), (bx, by) = fourbar.coupler_joint(theta2, r1, r2, r3, r4, theta0, branch)
    ox, oy = fourbar.rocker_pivot(r1, theta0)
    return {"O": (x0, y0), "A": (x0 + ax, y0 + ay), "B": (x0 + bx, y0 + by), "O'": (x0 + ox, y0 + oy),
            "P": coupler_point(theta2, p, branch)}


def cos_transmission(theta2, r1, r2, r3, r4):
    """cos mu = (r3^2 + r4^2 - d^2) / (2 r3 r4), mu the angle between coupler BA and output link BO'.

    d^2 = |O'A|^2 = r1^2 + r2^2 - 2 r1 r2 cos theta2.  cos mu falls as d grows, so over a full turn mu
    is smallest at theta2 = 0 (d = |r1 - r2|) and largest at theta2 = pi (d = r1 + r2): the extremes of
    the transmission angle over a turn are exact closed forms, no sampling needed.  Polynomial in the
    lengths, independent of the branch, smooth everywhere.
    """
    d2 = fourbar.diagonal_sq(theta2, r1, r2)
    return (r3 * r3 + r4 * r4 - d2) / (2.0 * r3 * r4)


def design_parameters(values: dict) -> list:
    """p for :func:`coupler_point` from result.json/spec values (theta0 deg -> rad)."""
    return [values[n] for n in VARIABLES[:-1]] + [values["theta0"] * (ca.pi / 180.0)]


@lru_cache(maxsize=4)
def coupler_function(branch: int) -> ca.Function:
    """CasADi Function (theta2, p) -> (P, dP/dtheta2, d2P/dtheta2^2), 2x1 each (mm, mm/rad, mm/rad^2).

    Built once per branch: on floats it evaluates, on symbols it embeds in an NLP, ``.map(N)``
    vectorises it over crank angles.
    """
    theta = ca.SX.sym("theta2")
    p = ca.SX.sym("p", len(VARIABLES))
    pos = ca.vertcat(*coupler_point(theta, p, branch))
    d1 = ca.jacobian(pos, theta)
    d2 = ca.jacobian(d1, theta)
    return ca.Function(f"coupler_point_{'open' if branch > 0 else 'crossed'}", [theta, p], [pos, d1, d2],
                       ["theta2", "p"], ["pos", "dpos", "ddpos"])
