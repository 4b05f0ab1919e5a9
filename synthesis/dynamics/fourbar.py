"""Inverse dynamics of a planar four-bar driven at constant crank speed (Newton-Euler, closed form).

Geometry is :mod:`synthesis.kinematics.fourbar`'s: crank pivot O at the origin, rocker pivot O' = l1 e(zeta), crank
pin A = l2 e(zeta + theta), coupler-rocker joint B on the side ``branch`` of A -> O'.  The links' centres of mass and
angles are closed-form functions of theta; their velocities and accelerations are CasADi's exact derivatives in theta
times omega and omega^2 (omega constant).  Each link's Newton-Euler equations then give, without a matrix solve:

* the coupler-rocker force F_B from the rocker's moments about O' and the coupler's about A (a 2x2 system whose
  determinant is (B - O') x (B - A): zero only at a toggle, where the transmission angle is 0 or 180 deg);
* F_A, F_O' and F_O from the force balances of the coupler, the rocker and the crank;
* the input torque from the crank's moments about O.

Sign conventions (docs/ARCHITECTURE.md "Dynamics"): a joint's reaction is the force the link nearer the frame exerts
on the next (frame on crank at O, crank on coupler at A, coupler on rocker at B, frame on rocker at O'); the input
torque is the motor's torque on the crank, counter-clockwise positive, so power = torque x omega; the shaking force
and moment are what the moving links put on the frame (-F_O - F_O', and -T - O' x F_O' about O), gravity included.

One CasADi Function per assembly branch serves floats (``check``, result.json) and symbols (the NLP's rules).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from synthesis.kinematics import fourbar

#: the moving links, in the order of the mass and load vectors (synthesis.dynamics.mass)
LINKS = ("crank", "coupler", "rocker")
#: the joints, in the order of the ``reactions`` output: crank pivot, crank pin, coupler-rocker joint, rocker pivot
JOINTS = ("crank_pivot", "crank_pin", "coupler_rocker", "rocker_pivot")
#: the geometry vector: l1 (frame), l2 (crank), l3 (coupler), l4 (rocker) in mm, zeta (frame direction) in rad
GEOMETRY = ("l1", "l2", "l3", "l4", "zeta")
OUTPUTS = ("torque", "reactions", "shaking_force", "shaking_moment", "com", "angle", "com_velocity",
           "angular_velocity", "kinetic_energy", "potential_energy", "external_power")


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _in_frame(origin, toward, x, y):
    """The point (x, y) of the frame with origin ``origin`` and x axis towards ``toward`` (all in m)."""
    d = toward - origin
    length = ca.sqrt(ca.dot(d, d))
    ux, uy = d[0] / length, d[1] / length
    return ca.vertcat(origin[0] + x * ux - y * uy, origin[1] + x * uy + y * ux)


@lru_cache(maxsize=4)
def inverse_dynamics(branch: int) -> ca.Function:
    """(theta rad, geometry (5), mass (12), loads (12), omega rad/s, gravity (2) m/s^2) -> :data:`OUTPUTS`.

    ``mass``: per link mass kg, centre of mass (m, link frame), inertia about it kg m^2; ``loads``: per link a
    constant force N (machine frame) at a point (m, link frame).  Outputs: torque N m; reactions (2, 4) N in
    :data:`JOINTS` order; shaking force (2) N; shaking moment N m about O; com (2, 3) m and angle (3) rad of each
    link; their velocities m/s and rad/s; kinetic and potential energy J; the external loads' power W.
    """
    theta, omega = ca.SX.sym("theta"), ca.SX.sym("omega")
    geom, mass, loads, g = ca.SX.sym("geometry", 5), ca.SX.sym("mass", 12), ca.SX.sym("loads", 12), ca.SX.sym("g", 2)
    l1, l2, l3, l4, zeta = (geom[i] for i in range(5))
    a_mm, b_mm = fourbar.coupler_joint(theta, l1, l2, l3, l4, zeta, branch)
    o = ca.vertcat(0.0, 0.0)
    a, b = ca.vertcat(*a_mm) / 1000.0, ca.vertcat(*b_mm) / 1000.0
    o_rocker = ca.vertcat(*fourbar.rocker_pivot(l1, zeta)) / 1000.0
    frames = ((o, a), (a, b), (o_rocker, b))
    com = [_in_frame(p, q, mass[4 * k + 1], mass[4 * k + 2]) for k, (p, q) in enumerate(frames)]
    at = [_in_frame(p, q, loads[4 * k + 2], loads[4 * k + 3]) for k, (p, q) in enumerate(frames)]
    angle = [ca.atan2(q[1] - p[1], q[0] - p[0]) for p, q in frames]
    moving = ca.vertcat(*com, *angle, *at)
    d1 = ca.jacobian(moving, theta)
    d2 = ca.jacobian(d1, theta)
    vel, acc = d1 * omega, d2 * omega ** 2
    m = [mass[4 * k] for k in range(3)]
    inertia = [mass[4 * k + 3] for k in range(3)]
    com_acc = [acc[2 * k:2 * k + 2] for k in range(3)]
    alpha = [acc[6 + k] for k in range(3)]
    force = [loads[4 * k:4 * k + 2] for k in range(3)]
    # what the joints must supply to each link: m (a - g) minus the external load
    need = [m[k] * (com_acc[k] - g) - force[k] for k in range(3)]

    def moment_needed(k, pivot):
        """Moment about ``pivot`` the joint forces must supply to link k (N m)."""
        return (inertia[k] * alpha[k] + _cross(com[k] - pivot, m[k] * (com_acc[k] - g))
                - _cross(at[k] - pivot, force[k]))

    r, s = b - o_rocker, b - a
    m_rocker, m_coupler = moment_needed(2, o_rocker), moment_needed(1, a)
    det = _cross(r, s)
    f_b = ca.vertcat(m_rocker * s[0] + m_coupler * r[0], m_coupler * r[1] + m_rocker * s[1]) / det
    f_a = f_b + need[1]
    f_rocker_pivot = need[2] - f_b
    f_o = f_a + need[0]
    torque = moment_needed(0, o) + _cross(a - o, f_a)
    shaking_force = -(f_o + f_rocker_pivot)
    shaking_moment = -torque - _cross(o_rocker, f_rocker_pivot)
    com_vel = [vel[2 * k:2 * k + 2] for k in range(3)]
    spin = [vel[6 + k] for k in range(3)]
    kinetic = sum(0.5 * m[k] * ca.dot(com_vel[k], com_vel[k]) + 0.5 * inertia[k] * spin[k] ** 2 for k in range(3))
    potential = -sum(m[k] * ca.dot(g, com[k]) for k in range(3))
    external = sum(ca.dot(force[k], vel[9 + 2 * k:11 + 2 * k]) for k in range(3))
    return ca.Function(
        f"fourbar_inverse_dynamics_{'p' if branch > 0 else 'm'}",
        [theta, geom, mass, loads, omega, g],
        [torque, ca.horzcat(f_o, f_a, f_b, f_rocker_pivot), shaking_force, shaking_moment, ca.horzcat(*com),
         ca.vertcat(*angle), ca.horzcat(*com_vel), ca.vertcat(*spin), kinetic, potential, external],
        ["theta", "geometry", "mass", "loads", "omega", "gravity"], list(OUTPUTS))


def over_turn(branch: int, crank: np.ndarray, geometry, mass, loads, omega, gravity) -> dict:
    """:func:`inverse_dynamics` at the crank angles ``crank`` (rad), by name.  On floats every output is a numpy
    array with the samples last (torque (N,), reactions (2, 4, N) ...); on symbols a CasADi row or matrix of the
    mapped Function (torque 1 x N, shaking force 2 x N, ...), for rules."""
    n = int(np.size(crank))
    f = inverse_dynamics(branch).map(n)
    args = [np.asarray(crank, float).reshape(1, -1), ca.vertcat(*geometry), ca.vertcat(*mass), ca.vertcat(*loads),
            omega, ca.vertcat(*gravity)]
    out = dict(zip(OUTPUTS, f(*args)))
    if any(isinstance(v, (ca.SX, ca.MX)) for v in out.values()):
        return out
    arrays = {k: np.asarray(v, float) for k, v in out.items()}
    arrays["reactions"] = arrays["reactions"].reshape(2, n, 4).transpose(0, 2, 1)   # map stacks columns per sample
    arrays["com"] = arrays["com"].reshape(2, n, 3).transpose(0, 2, 1)
    arrays["com_velocity"] = arrays["com_velocity"].reshape(2, n, 3).transpose(0, 2, 1)
    for k in ("torque", "shaking_moment", "kinetic_energy", "potential_energy", "external_power"):
        arrays[k] = arrays[k].ravel()
    return arrays

