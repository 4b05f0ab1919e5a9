"""Inverse dynamics of the rotary-arm slide guide way at constant arm speed (Newton-Euler, closed form).

Two moving bodies: the arm OP, turning about O at the constant speed omega (theta grows in time order, clockwise in
the machine frame x right, y up), and the claw body (the claw PM and the crank arm PN, rigid, pivoting on the arm at
P), steered by its roller at N in the fixed groove.  The groove is two walls: its force on the roller is along the
centre line's normal, either sign (frictionless).  Each body's mass properties are given in its own frame: the arm's
origin O, x towards P; the claw's origin P, x towards M (N is at (r cos beta, -r sin beta) there).

The path is the kind's own: a stretch's samples of the claw tip M, M', M'' in its parameter u (conic or spline,
:mod:`synthesis.kinds.guide_way.path`).  Near a sample M(u) is the quadratic M + M' du + M'' du^2 / 2, exact to
second order; theta(u), alpha(u) are :func:`synthesis.kinds.guide_way.kinematics.inverse` of it (the kind's code
path), every position a function of u, and its derivatives CasADi's exact ones in u at du = 0.  In time
u' = omega / theta_u and u'' = -omega^2 theta_uu / theta_u^3, so q' = q_u u' and q'' = q_uu u'^2 + q_u u''.

Then, without a matrix solve:

* the groove force Fn (along n, the left normal of the centre line's direction of motion) from the claw's moments
  about P: Fn (N - P) x n = I2 psi2'' + (G2 - P) x m2 (a2 - g); (N - P) x n = r cos(pressure angle) up to sign,
  so Fn grows without bound towards the fold's dead point, where the pressure angle is 90 deg;
* the pivot force at P (arm on claw) from the claw's force balance, the bearing force at O (frame on arm) from the
  arm's;
* the drive torque from the arm's moments about O.

The same Function serves the check and the re-check (numbers) and the NLP of a spline path (mapped over its
symbolic samples, the control points as symbols): the ``[dynamics.limits]`` rules are one model on both.

Sign conventions: a joint's force is the one the body nearer the frame exerts on the next (frame on arm at O, arm
on claw at P, groove on roller at N); the input torque is the motor's on the arm, positive in the arm's direction
of turning (theta growing), so power = torque x omega; the shaking force and moment (about O) are what the moving
bodies put on the frame (-F_O - F_N; the motor's reaction -T_ccw and -N x F_N), gravity included.  Fn > 0: the
groove pushes the roller to the left of its direction of motion, i.e. the right wall carries it (the walls of
facts.curves: left = N + roller radius x n).
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np
from scipy.integrate import trapezoid       # numpy's own is numpy >= 2 only

from synthesis.constraints.dynamics import peak_input_torque_rule, peak_shaking_force_rule, peak_shaking_moment_rule
from synthesis.dynamics import mass as mass_properties
from synthesis.kinds.guide_way import kinematics as ra
from synthesis.kinds.guide_way.scene import arm_of, controlled_keys, fold_stretches, nearest_turn, spline_path

#: the moving bodies, in the order of the mass vector
BODIES = ("arm", "claw")
#: the joints and their roles in facts.dynamics
JOINTS = {"O": "arm_pivot", "P": "claw_pivot", "N": "roller"}
OUTPUTS = ("torque", "groove_force", "normal", "reactions", "shaking_force", "shaking_moment", "com", "angle",
           "com_velocity", "angular_velocity", "kinetic_energy", "potential_energy", "theta", "arm_rate")


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _in_frame(origin, toward, x, y):
    """The point (x, y) of the frame with origin ``origin`` and x axis towards ``toward`` (all in m)."""
    d = toward - origin
    length = ca.sqrt(ca.dot(d, d))
    ux, uy = d[0] / length, d[1] / length
    return ca.vertcat(origin[0] + x * ux - y * uy, origin[1] + x * uy + y * ux)


@lru_cache(maxsize=2)
def inverse_dynamics(branch: float) -> ca.Function:
    """(m[2], m1[2], m2[2] mm, arm (R, d, r mm, beta rad), mass (8), omega rad/s, gravity (2) m/s^2) -> OUTPUTS.

    ``mass``: per body (arm, claw) mass kg, centre of mass (m, body frame), inertia about it kg m^2.  Outputs: torque
    N m (positive driving the arm forward); groove force N (signed along ``normal``); normal (2); reactions (2, 3) at
    O, P, N; shaking force (2) N; shaking moment N m about O; com (2, 2) m and angle (2) rad of each body (the
    arm's: direction of OP, the claw's: direction of PM, counter-clockwise from +x); their velocities m/s, rad/s;
    kinetic and potential energy J; theta rad and dtheta/du."""
    m0, m1, m2 = ca.SX.sym("m", 2), ca.SX.sym("m1", 2), ca.SX.sym("m2", 2)
    g_arm, mass, omega, g = ca.SX.sym("arm", 4), ca.SX.sym("mass", 8), ca.SX.sym("omega"), ca.SX.sym("g", 2)
    du = ca.SX.sym("du")
    R, d, r, beta = g_arm[0], g_arm[1], g_arm[2], g_arm[3]
    m = m0 + m1 * du + m2 * du * du / 2.0
    theta, alpha = ra.inverse(R, d, m[0], m[1], branch)
    o = ca.vertcat(0.0, 0.0)
    p = ca.vertcat(*ra.pivot(R, theta)) / 1000.0
    tip = ca.vertcat(*ra.claw_tip(R, d, theta, alpha)) / 1000.0
    n = ca.vertcat(*ra.roller_centre(R, r, beta, theta, alpha)) / 1000.0
    com = [_in_frame(o, p, mass[1], mass[2]), _in_frame(p, tip, mass[5], mass[6])]
    angle = [ca.atan2(p[1], p[0]), ca.atan2(tip[1] - p[1], tip[0] - p[0])]
    moving = ca.vertcat(theta, *com, *angle, n)
    d1 = ca.jacobian(moving, du)
    d2 = ca.jacobian(d1, du)
    q, q1, q2 = (ca.substitute(v, du, ca.SX(0.0)) for v in (moving, d1, d2))
    theta_u, theta_uu = q1[0], q2[0]
    rate = omega / theta_u
    accel = -omega * omega * theta_uu / theta_u ** 3
    vel, acc = q1 * rate, q2 * rate * rate + q1 * accel
    com = [q[1:3], q[3:5]]
    angle = [q[5], q[6]]
    n_at, n_u = q[7:9], q1[7:9]
    p_at = ca.vertcat(*ra.pivot(R, q[0])) / 1000.0
    masses, inertia = [mass[0], mass[4]], [mass[3], mass[7]]
    com_vel = [vel[1:3], vel[3:5]]
    com_acc = [acc[1:3], acc[3:5]]
    spin, spin_rate = [vel[5], vel[6]], [acc[5], acc[6]]
    need = [masses[k] * (com_acc[k] - g) for k in range(2)]
    speed = ca.sqrt(ca.dot(n_u, n_u))
    normal = ca.vertcat(-n_u[1], n_u[0]) / speed
    lever = _cross(n_at - p_at, normal)
    groove = (inertia[1] * spin_rate[1] + _cross(com[1] - p_at, need[1])) / lever
    f_n = groove * normal
    f_p = need[1] - f_n
    f_o = need[0] + f_p
    torque_ccw = inertia[0] * spin_rate[0] + _cross(com[0], need[0]) + _cross(p_at, f_p)
    shaking_force = -(f_o + f_n)
    shaking_moment = -torque_ccw - _cross(n_at, f_n)
    kinetic = sum(0.5 * masses[k] * ca.dot(com_vel[k], com_vel[k]) + 0.5 * inertia[k] * spin[k] ** 2
                  for k in range(2))
    potential = -sum(masses[k] * ca.dot(g, com[k]) for k in range(2))
    return ca.Function(
        f"guide_way_inverse_dynamics_{'plus' if branch > 0 else 'minus'}",
        [m0, m1, m2, g_arm, mass, omega, g],
        [-torque_ccw, groove, normal, ca.horzcat(f_o, f_p, f_n), shaking_force, shaking_moment, ca.horzcat(*com),
         ca.vertcat(*angle), ca.horzcat(*com_vel), ca.vertcat(*spin), kinetic, potential, q[0], theta_u],
        ["m", "m1", "m2", "arm", "mass", "omega", "gravity"], list(OUTPUTS))


def along(stretch, arm: list[float], mass: list[float], omega: float, gravity) -> dict:
    """:func:`inverse_dynamics` at a numeric stretch's samples, by name, numpy arrays with the samples last (torque
    (N,), reactions (2, 3, N), com (2, 2, N) ...)."""
    k = np.asarray(stretch.u).size
    f = inverse_dynamics(float(stretch.branch)).map(k)
    mm, mm1, mm2 = (np.asarray(v, float).T for v in (stretch.m, stretch.m1, stretch.m2))
    out = dict(zip(OUTPUTS, f(mm, mm1, mm2, arm, mass, omega, list(gravity))))
    a = {name: np.asarray(v, float) for name, v in out.items()}
    a["reactions"] = a["reactions"].reshape(2, k, 3).transpose(0, 2, 1)
    a["com"] = a["com"].reshape(2, k, 2).transpose(0, 2, 1)
    a["com_velocity"] = a["com_velocity"].reshape(2, k, 2).transpose(0, 2, 1)
    for name in ("torque", "groove_force", "shaking_moment", "kinetic_energy", "potential_energy", "theta",
                 "arm_rate"):
        a[name] = a[name].ravel()
    return a


def body_frames(spec) -> dict[str, dict]:
    """Per body: its bars (start, end) in mm in its own frame and its named points (``tip``: M, ``roller``: N)."""
    a = spec.arm
    beta = math.radians(a.beta)
    n = (a.crank * math.cos(beta), -a.crank * math.sin(beta))
    return {"arm": {"bars": [((0.0, 0.0), (a.radius, 0.0))], "points": {}},
            "claw": {"bars": [((0.0, 0.0), (a.claw, 0.0)), ((0.0, 0.0), n)],
                     "points": {"tip": (a.claw, 0.0), "roller": n}}}


def mass_vector(spec) -> list[float]:
    """The 8 mass parameters (mass kg, centre of mass x, y m in the body frame, inertia kg m^2 about it) of the arm
    and the claw body from the spec's ``[dynamics]`` table, point masses included."""
    table, frames = spec.dynamics, body_frames(spec)
    out: list[float] = []
    for name in BODIES:
        section = getattr(table, name)
        if hasattr(section, "density"):
            parts = [mass_properties.bar(section.density, section.area, s, e) for s, e in frames[name]["bars"]]
        else:
            parts = [(section.mass, section.com[0] / 1000.0, section.com[1] / 1000.0, section.inertia)]
        for pm in table.point_masses:
            if pm.link == name:
                at = frames[name]["points"][pm.at] if isinstance(pm.at, str) else pm.at
                parts.append(mass_properties.point(pm.mass, at))
        out += [float(v) for v in mass_properties.combine(parts)]
    return out


def stretches_of(scene, samples: int) -> list:
    """The controlled path's stretches in time order, ``samples`` spread evenly over them (each in its own
    parameter, as the check samples them)."""
    count = len(scene.arms)
    per = max(3, -(-samples // count))
    if scene.pieces is not None:
        return [piece.stretch(per) for piece in scene.pieces]
    return scene.spline.stretches(per)


def over_path(scene, samples: int | None = None) -> dict:
    """The inverse dynamics over the controlled path of a numeric scene: per sample in time order, every output of
    :func:`inverse_dynamics` (samples last), with ``stretch`` (the stretch's name) and ``claw_tip`` (N x 2, mm);
    ``samples`` over the whole path (default ``[dynamics] samples``)."""

    spec = scene.spec
    table = spec.dynamics
    omega = table.arm_speed * 2.0 * math.pi / 60.0
    mass = mass_vector(spec)
    parts = []
    names: list[str] = []
    index = []
    tips = []
    for k, st in enumerate(stretches_of(scene, samples or table.samples)):
        parts.append(along(st, arm_of(spec), mass, omega, table.gravity))
        names += [st.name] * np.asarray(st.u).size
        index += [k] * np.asarray(st.u).size
        tips.append(np.asarray(st.m, float))
    out: dict = {k: np.concatenate([p[k] for p in parts], axis=-1) for k in parts[0]}
    out.update(stretch=names, index=np.array(index), claw_tip=np.vstack(tips), mass=mass, omega=omega)
    return out


def outside_fold_window(scene, out: dict) -> np.ndarray:
    """Per sample of :func:`over_path`: whether it lies outside ``[rules] fold_window`` deg of arm angle about the
    fold, on the fold's two stretches (the check's own window: its centre the fold's arm angle, or direction)."""

    spec = scene.spec
    keep = np.ones(out["theta"].size, bool)
    w = spec.rules.fold_window
    centre = scene.window_centre or scene.fold_theta
    if w <= 0 or centre is None:
        return keep
    for side, k in enumerate(fold_stretches(spec)):
        at = np.flatnonzero(out["index"] == k)
        th = np.degrees(np.unwrap(out["theta"][at]))
        near = nearest_turn(math.degrees(centre[side]), float(th[0]))
        keep[at] = np.abs(th - near) >= w
    return keep


def wall_changes(out: dict) -> list[dict]:
    """Where the groove force changes sign along the path (the roller crosses from one wall to the other), within
    a stretch and across a joint, by linear interpolation between the two samples."""
    f, th = out["groove_force"], np.degrees(np.unwrap(out["theta"]))
    found = []
    for i in np.flatnonzero(np.sign(f[:-1]) * np.sign(f[1:]) < 0):
        w = f[i] / (f[i] - f[i + 1])
        tip = (1 - w) * out["claw_tip"][i] + w * out["claw_tip"][i + 1]
        found.append({"stretch": out["stretch"][i] if out["stretch"][i] == out["stretch"][i + 1] else
                      f"{out['stretch'][i]}/{out['stretch'][i + 1]}",
                      "theta_deg": float(((1 - w) * th[i] + w * th[i + 1]) % 360.0),
                      "claw_tip": [float(tip[0]), float(tip[1])],
                      "from_wall": _wall(f[i]), "to_wall": _wall(f[i + 1])})
    return found


def _wall(force: float) -> str:
    return "right" if force > 0 else "left"


def _peak(values: np.ndarray, crank_deg: np.ndarray, out: dict) -> dict:
    values = np.asarray(values, float)
    k = int(np.argmax(np.abs(values)))
    return {"peak": float(abs(values[k])), "peak_at_crank_deg": float(crank_deg[k]), "stretch": out["stretch"][k],
            "rms": float(np.sqrt(np.mean(values ** 2)))}


def dynamics_facts(scene) -> dict:
    """result.json's ``facts.dynamics`` over the controlled path: the four-bar kinds' keys where they apply
    (``crank_deg`` the arm angle theta in time order; the path is not a whole turn: A -> E is not guided), the
    groove force, the walls it presses and where it changes wall."""
    out = over_path(scene)
    table = scene.spec.dynamics
    crank = np.degrees(np.unwrap(out["theta"]))
    crank = crank - 360.0 * math.floor(crank[0] / 360.0)
    torque, omega = out["torque"], out["omega"]
    power = torque * omega
    force = out["shaking_force"]
    mass = out["mass"]
    links = []
    for k, name in enumerate(BODIES):
        links.append({"name": name, "role": "crank" if name == "arm" else "claw", "mass_kg": mass[4 * k],
                      "inertia_kgm2": mass[4 * k + 3], "com_mm": (out["com"][:, k, :].T * 1000.0).tolist(),
                      "angle_deg": np.degrees(np.unwrap(out["angle"][k])).tolist(),
                      "com_velocity_mps": out["com_velocity"][:, k, :].T.tolist(),
                      "angular_velocity_radps": out["angular_velocity"][k].tolist()})
    groove = out["groove_force"]
    changes = wall_changes(out)
    joints = {name: out["reactions"][:, j, :].T.tolist() for j, name in enumerate(JOINTS)}
    summary = {"input_torque_Nm": _peak(torque, crank, out), "power_W": _peak(power, crank, out),
               "mean_power_W": float(trapezoid(power, crank) / (crank[-1] - crank[0])) if crank[-1] != crank[0]
               else 0.0,
               "shaking_force_N": _peak(np.hypot(force[0], force[1]), crank, out),
               "shaking_moment_Nm": _peak(out["shaking_moment"], crank, out),
               "groove_force_N": _peak(groove, crank, out),
               "joints_N": {name: _peak(np.hypot(*out["reactions"][:, j, :]), crank, out)
                            for j, name in enumerate(JOINTS)},
               "wall_changes": len(changes)}
    outside = outside_fold_window(scene, out)
    if not np.all(outside):
        summary["groove_force_outside_fold_window_N"] = _peak(np.where(outside, groove, 0.0), crank, out)
    return {
        "span": "controlled path " + "-".join(_keys(scene)) + " (A -> E is not guided)",
        "crank_deg": crank.tolist(),
        "crank_speed_rpm": table.arm_speed,
        "input_torque_Nm": torque.tolist(),
        "power_W": power.tolist(),
        "shaking_force_N": force.T.tolist(),
        "shaking_moment_Nm": out["shaking_moment"].tolist(),
        "joints": joints,
        "joint_roles": dict(JOINTS),
        "links": links,
        "gravity_mps2": [float(v) for v in table.gravity],
        "external_loads": False,
        "stretch": out["stretch"],
        "groove_force_N": groove.tolist(),
        "groove_normal": out["normal"].T.tolist(),
        "groove_wall": [_wall(v) for v in groove],
        "wall_changes": changes,
        "kinetic_energy_J": out["kinetic_energy"].tolist(),
        "potential_energy_J": out["potential_energy"].tolist(),
        "summary": summary,
        "conventions": "reaction at a joint: force of the body nearer the frame on the next (frame on arm at O, arm "
                       "on claw at P, groove on roller at N; N, machine frame); input torque: the motor's on the "
                       "arm, positive in the arm's direction of turning (theta growing), power = torque x omega; "
                       "shaking force and moment (about O): what the moving bodies put on the frame, gravity "
                       "included; groove force: along groove_normal (the left normal of the roller's direction of "
                       "motion), > 0 when the right wall carries the roller",
        "assumption": table.assumption,
    }


def _keys(scene) -> list[str]:

    return controlled_keys(scene.spec)


def symbolic_samples(spec, control, samples: int) -> tuple:
    """(input torque, shaking force x, y, shaking moment) as SX columns over a spline path whose control points are
    the NLP's symbols, ``samples`` per stretch: the same Function as on floats, mapped over the symbolic samples."""

    table = spec.dynamics
    omega = table.arm_speed * 2.0 * math.pi / 60.0
    mass, arm = ca.DM(mass_vector(spec)), ca.DM(arm_of(spec))
    torque, fx, fy, moment = [], [], [], []
    for st in spline_path(spec, control).stretches(samples):
        f = inverse_dynamics(float(st.branch)).map(np.asarray(st.u).size)
        out = dict(zip(OUTPUTS, f(st.m, st.m1, st.m2, arm, mass, omega, ca.DM(list(table.gravity)))))
        torque.append(out["torque"].T)
        fx.append(out["shaking_force"][0, :].T)
        fy.append(out["shaking_force"][1, :].T)
        moment.append(out["shaking_moment"].T)
    return tuple(ca.vertcat(*v) for v in (torque, fx, fy, moment))


def limit_rules(spec, torque, fx, fy, moment) -> list:
    """The ``[dynamics.limits]`` rules on sampled columns (floats or symbols)."""

    table = spec.dynamics
    limits = table.limits
    where = f"over the controlled path {'-'.join(_spec_keys(spec))} at {table.arm_speed:g} r/min"
    rules = []
    if limits.peak_input_torque is not None:
        rules.append(peak_input_torque_rule(torque, limits.peak_input_torque, where))
    if limits.peak_shaking_force is not None:
        rules.append(peak_shaking_force_rule(fx, fy, limits.peak_shaking_force, where))
    if limits.peak_shaking_moment is not None:
        rules.append(peak_shaking_moment_rule(moment, limits.peak_shaking_moment, where + ", about O"))
    return rules


def _spec_keys(spec) -> list[str]:

    return controlled_keys(spec)


def dynamics_rules(scene, samples: int | None = None) -> list:
    """The ``[dynamics.limits]`` rules over the controlled path of a numeric scene at ``samples`` (default the
    table's: the check; a solve's re-check asks at least as many as its other rules read); none without a limit."""
    table = scene.spec.dynamics
    if table is None or not table.has_rules():
        return []
    out = over_path(scene, samples)
    force = out["shaking_force"]
    return limit_rules(scene.spec, out["torque"], force[0], force[1], out["shaking_moment"])


def nlp_rules(spec, control, samples: int) -> list:
    """The same rules on the NLP's symbolic spline path, ``samples`` per stretch; none without a limit."""
    table = spec.dynamics
    if table is None or not table.has_rules():
        return []
    return limit_rules(spec, *symbolic_samples(spec, control, samples))
