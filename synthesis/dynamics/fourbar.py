"""Inverse dynamics of a planar four-bar driven at its crank (Newton-Euler, closed form).

Geometry is :mod:`synthesis.kinematics.fourbar`'s: crank pivot O at the origin, rocker pivot O' = l1 e(zeta), crank
pin A = l2 e(zeta + theta), coupler-rocker joint B on the side ``branch`` of A -> O'.  The links' centres of mass and
angles are closed-form functions of theta; their velocities and accelerations are CasADi's exact derivatives in theta
times the crank speed omega, and times omega^2 plus the crank's angular acceleration alpha (zero at constant speed;
omega and alpha may differ per sample, for a crank whose speed fluctuates or that is driven through another
linkage).  Each link's Newton-Euler equations then give, without a matrix solve:

* the coupler-rocker force F_B from the rocker's moments about O' and the coupler's about A (a 2x2 system whose
  determinant is (B - O') x (B - A): zero only at a toggle, where the transmission angle is 0 or 180 deg);
* F_A, F_O' and F_O from the force balances of the coupler, the rocker and the crank;
* the input torque from the crank's moments about O.

Sign conventions (docs/ARCHITECTURE.md "Dynamics"): a joint's reaction is the force the link nearer the frame exerts
on the next (frame on crank at O, crank on coupler at A, coupler on rocker at B, frame on rocker at O'); the input
torque is the motor's torque on the crank, counter-clockwise positive, so power = torque x omega; the shaking force
and moment are what the moving links put on the frame (-F_O - F_O', and -T - O' x F_O' about O), gravity included.

Loads: per link a constant force at a point and a moment (a couple, e.g. what a linkage the rocker drives puts back
on it); with ``with_soil``, a soil force on a coupler point while it is below the soil surface, of magnitude
f0 + k d (d the depth, mm) opposing the point's velocity relative to the soil, the machine travelling towards +x at
the forward speed.  That direction is regularised, v / sqrt(|v|^2 + eps^2) with eps = :data:`SOIL_SPEED_EPS`,
because at the bottom of a planting stroke the claw can stand still relative to the soil, where the exact direction
is undefined and would flip the force within one sample.

One CasADi Function per assembly branch (and with or without soil) serves floats (``check``, result.json) and
symbols (the NLP's rules).
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
#: the soil vector (``with_soil``): f0 N, k N/mm, soil surface y mm (machine frame), forward speed m/s, the loaded
#: point on the coupler (link frame) x, y mm
SOIL = ("f0", "k", "surface_y", "forward_speed", "at_x", "at_y")
#: the relative speed (m/s) below which the soil force's direction is blended towards zero (1 mm/s)
SOIL_SPEED_EPS = 1.0e-3
OUTPUTS = ("torque", "reactions", "shaking_force", "shaking_moment", "com", "angle", "com_velocity",
           "angular_velocity", "kinetic_energy", "potential_energy", "external_power", "soil_force", "soil_depth")


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _in_frame(origin, toward, x, y):
    """The point (x, y) of the frame with origin ``origin`` and x axis towards ``toward`` (all in m)."""
    d = toward - origin
    length = ca.sqrt(ca.dot(d, d))
    ux, uy = d[0] / length, d[1] / length
    return ca.vertcat(origin[0] + x * ux - y * uy, origin[1] + x * uy + y * ux)


def _soil_law(soil, at, velocity):
    """(depth mm, force N) of the soil on the point ``at`` (m, machine frame) moving at ``velocity`` (m/s, machine
    frame): :data:`SOIL`'s law, the direction regularised by :data:`SOIL_SPEED_EPS`."""
    depth = soil[2] - at[1] * 1000.0
    relative = velocity + ca.vertcat(soil[3], 0.0)
    blended = relative / ca.sqrt(ca.dot(relative, relative) + SOIL_SPEED_EPS ** 2)
    return depth, ca.if_else(depth > 0.0, -(soil[0] + soil[1] * depth) * blended, ca.DM.zeros(2))


@lru_cache(maxsize=8)
def inverse_dynamics(branch: int, varying: bool = False, with_soil: bool = False) -> ca.Function:
    """(theta rad, geometry (5), mass (12), loads (12), omega rad/s, alpha rad/s^2, moments (3) N m, soil (6), gravity
    (2) m/s^2) -> :data:`OUTPUTS`.

    ``mass``: per link mass kg, centre of mass (m, link frame), inertia about it kg m^2; ``loads``: per link a
    constant force N (machine frame) at a point (m, link frame); ``moments``: per link an external moment N m
    (counter-clockwise), read with ``alpha`` only when ``varying``; ``soil``: :data:`SOIL`, read only ``with_soil``;
    without either, the constant-speed graph operation for operation (an added zero is exact, but a larger Jacobian
    can order AD's sums differently).  Outputs: torque N m; reactions (2, 4) N in :data:`JOINTS` order; shaking
    force (2) N and moment N m about O; com (2, 3) m and angle (3) rad of each link; their velocities m/s and rad/s;
    kinetic and potential energy J; the external loads' power W (forces, moments, soil); the soil force (2) N and
    the loaded point's depth mm (zero and 0 without soil)."""
    theta, omega, alpha = ca.SX.sym("theta"), ca.SX.sym("omega"), ca.SX.sym("alpha")
    geom, mass, loads, g = ca.SX.sym("geometry", 5), ca.SX.sym("mass", 12), ca.SX.sym("loads", 12), ca.SX.sym("g", 2)
    moments, soil = ca.SX.sym("moments", 3), ca.SX.sym("soil", len(SOIL))
    l1, l2, l3, l4, zeta = (geom[i] for i in range(5))
    a_mm, b_mm = fourbar.coupler_joint(theta, l1, l2, l3, l4, zeta, branch)
    o = ca.vertcat(0.0, 0.0)
    a, b = ca.vertcat(*a_mm) / 1000.0, ca.vertcat(*b_mm) / 1000.0
    o_rocker = ca.vertcat(*fourbar.rocker_pivot(l1, zeta)) / 1000.0
    frames = ((o, a), (a, b), (o_rocker, b))
    com = [_in_frame(p, q, mass[4 * k + 1], mass[4 * k + 2]) for k, (p, q) in enumerate(frames)]
    at = [_in_frame(p, q, loads[4 * k + 2], loads[4 * k + 3]) for k, (p, q) in enumerate(frames)]
    angle = [ca.atan2(q[1] - p[1], q[0] - p[0]) for p, q in frames]
    soil_at = _in_frame(a, b, soil[4] / 1000.0, soil[5] / 1000.0)
    moving = ca.vertcat(*com, *angle, *at, soil_at) if with_soil else ca.vertcat(*com, *angle, *at)
    d1 = ca.jacobian(moving, theta)
    d2 = ca.jacobian(d1, theta)
    vel, acc = d1 * omega, (d2 * omega ** 2 + d1 * alpha) if varying else d2 * omega ** 2
    m = [mass[4 * k] for k in range(3)]
    inertia = [mass[4 * k + 3] for k in range(3)]
    com_acc = [acc[2 * k:2 * k + 2] for k in range(3)]
    angular_acc = [acc[6 + k] for k in range(3)]
    force = [loads[4 * k:4 * k + 2] for k in range(3)]
    if with_soil:
        soil_vel = vel[15:17]
        depth, soil_force = _soil_law(soil, soil_at, soil_vel)
        force[1] = force[1] + soil_force
    else:
        depth, soil_force = ca.SX(0.0), ca.SX.zeros(2)
    # what the joints must supply to each link: m (a - g) minus the external load
    need = [m[k] * (com_acc[k] - g) - force[k] for k in range(3)]

    def moment_needed(k, pivot):
        """Moment about ``pivot`` the joint forces must supply to link k (N m)."""
        needed = (inertia[k] * angular_acc[k] + _cross(com[k] - pivot, m[k] * (com_acc[k] - g))
                  - _cross(at[k] - pivot, loads[4 * k:4 * k + 2]))
        if varying:
            needed = needed - moments[k]
        return needed - _cross(soil_at - pivot, soil_force) if (with_soil and k == 1) else needed

    r, s = b - o_rocker, b - a
    m_rocker, m_coupler = moment_needed(2, o_rocker), moment_needed(1, a)
    det = _cross(r, s)
    f_b = ca.vertcat(m_rocker * s[0] + m_coupler * r[0], m_coupler * r[1] + m_rocker * s[1]) / det
    f_a = f_b + need[1]
    f_rocker_pivot = need[2] - f_b
    f_o = f_a + need[0]
    torque = moment_needed(0, o) + _cross(a - o, f_a)
    shaking_force = -(f_o + f_rocker_pivot)
    # the external moments' agents are not the frame (e.g. a linkage the rocker drives, whose own frame loads its
    # kind adds), so only the motor's reaction and the pivots' forces load the frame here
    shaking_moment = -torque - _cross(o_rocker, f_rocker_pivot)
    com_vel = [vel[2 * k:2 * k + 2] for k in range(3)]
    spin = [vel[6 + k] for k in range(3)]
    kinetic = sum(0.5 * m[k] * ca.dot(com_vel[k], com_vel[k]) + 0.5 * inertia[k] * spin[k] ** 2 for k in range(3))
    potential = -sum(m[k] * ca.dot(g, com[k]) for k in range(3))
    external = sum(ca.dot(loads[4 * k:4 * k + 2], vel[9 + 2 * k:11 + 2 * k]) for k in range(3))
    if varying:
        external = external + moments[0] * spin[0] + moments[1] * spin[1] + moments[2] * spin[2]
    if with_soil:
        external = external + ca.dot(soil_force, soil_vel)
    return ca.Function(
        f"fourbar_inverse_dynamics_{'p' if branch > 0 else 'm'}{'_varying' if varying else ''}"
        f"{'_soil' if with_soil else ''}",
        [theta, geom, mass, loads, omega, alpha, moments, soil, g],
        [torque, ca.horzcat(f_o, f_a, f_b, f_rocker_pivot), shaking_force, shaking_moment, ca.horzcat(*com),
         ca.vertcat(*angle), ca.horzcat(*com_vel), ca.vertcat(*spin), kinetic, potential, external, soil_force,
         depth],
        ["theta", "geometry", "mass", "loads", "omega", "alpha", "moments", "soil", "gravity"], list(OUTPUTS))


def over_turn(branch: int, crank: np.ndarray, geometry, mass, loads, omega, gravity, alpha=None, moments=None,
              soil=None) -> dict:
    """:func:`inverse_dynamics` at the crank angles ``crank`` (rad), by name.  ``omega``, ``alpha`` (None: 0) and
    ``moments`` (None: none) are one value for every sample or one per sample (a 1 x N row; moments 3 x N); ``soil`` a
    :data:`SOIL` vector or None.  On floats every output is a numpy array with the samples last (torque (N,), reactions (2, 4, N) ...); on
    symbols a CasADi row or matrix of the mapped Function (torque 1 x N, shaking force 2 x N, ...), for rules."""
    n = int(np.size(crank))
    varying = alpha is not None or moments is not None
    f = inverse_dynamics(branch, varying, soil is not None).map(n)
    args = [np.asarray(crank, float).reshape(1, -1), ca.vertcat(*geometry), ca.vertcat(*mass), ca.vertcat(*loads),
            _row(omega), _row(0.0 if alpha is None else alpha), _stacked((0.0, 0.0, 0.0) if moments is None else moments),
            ca.vertcat(*(soil if soil is not None else [0.0] * len(SOIL))), ca.vertcat(*gravity)]
    out = dict(zip(OUTPUTS, f(*args)))
    if any(isinstance(v, (ca.SX, ca.MX)) for v in out.values()):
        return out
    arrays = {k: np.asarray(v, float) for k, v in out.items()}
    arrays["reactions"] = arrays["reactions"].reshape(2, n, 4).transpose(0, 2, 1)   # map stacks columns per sample
    arrays["com"] = arrays["com"].reshape(2, n, 3).transpose(0, 2, 1)
    arrays["com_velocity"] = arrays["com_velocity"].reshape(2, n, 3).transpose(0, 2, 1)
    for k in ("torque", "shaking_moment", "kinetic_energy", "potential_energy", "external_power", "soil_depth"):
        arrays[k] = arrays[k].ravel()
    return arrays


def _row(value):
    """One value for every sample, or one per sample as a 1 x N row (numbers or symbols)."""
    if isinstance(value, (ca.SX, ca.MX, ca.DM)):
        return value if value.shape[0] == 1 else value.T
    arr = np.asarray(value, float) if not isinstance(value, (list, tuple)) or all(
        isinstance(v, (int, float)) for v in value) else None
    return arr.reshape(1, -1) if arr is not None else ca.horzcat(*value)


def _stacked(moments):
    """Per-link moments: three values for every sample, or a 3 x N matrix (numbers or symbols)."""
    if isinstance(moments, (ca.SX, ca.MX, ca.DM)):
        return moments
    arr = np.asarray(moments, float) if all(isinstance(v, (int, float)) for v in np.ravel(moments)) else None
    return arr.reshape(3, -1) if arr is not None else ca.vertcat(*moments)
