"""Inverse dynamics of the distorted rotary tillage linkage at constant flywheel speed (Newton-Euler, closed form).

The mechanism (kinematics.py): the flywheel with its crank AB turns about A at the constant speed Omega; the tillage
bar BD is pinned to it at B and slides through the roller pair at C (fixed, the origin); the tool at D works the soil
below the ground line y = -height_c.  Two moving links:

    crank   origin A, x towards B (angle = the crank angle q)
    bar     origin B, x towards D along the bar: e = (C - B) / |CB|, angle psi = atan2(e)

Their centres of mass, angles, the tool point D and the length S = |CB| are closed-form functions of q; velocities and
accelerations are CasADi's exact derivatives in q times Omega and Omega^2.  Then, without a matrix solve:

* the roller's normal force N on the bar (along n = e turned +90 deg) from the bar's moments about B: friction at C
  acts along the bar, through B, so it has no moment there, and (C - B) x (N n) = S N;
* the roller's friction T = mu |N| tanh(S' / V_SLIP) along e (it opposes the bar's sliding through the rollers, whose
  speed along e is -S'; tanh instead of sign so the NLP sees a smooth function, V_SLIP below);
* the pin force at B from the bar's force balance, the pivot force at A from the crank's, the input torque from the
  crank's moments about A.

The soil force on the tool (``soil``): while D is below the ground (depth d = -height_c - y_D > 0, mm) a force of
magnitude f0 + k d opposing D's velocity relative to the soil, which in the machine frame is (Omega x_D' + v,
Omega y_D') (the machine travels towards +x at v, the soil is at rest in the ground frame); zero above the ground.
It is exact (a CasADi if_else on d > 0), in the facts and in the NLP's rules alike: with f0 = 0 the force is
continuous in the depth, so a sampled torque is a continuous function of the design with a kink where a sample
crosses the ground line, which IPOPT takes as it takes a max; with f0 > 0 the force jumps at entry and exit.

Sign conventions (the four-bar's, synthesis/dynamics/fourbar.py): a joint's reaction is the force of the link nearer
the frame on the next (frame on crank at A, crank on bar at B, roller on bar at C); the input torque is the motor's on
the crank, counter-clockwise positive, power = torque x Omega; the shaking force and moment (about A) are what the
moving links put on the frame through A and C, gravity and the soil force's reaction included.

Energy: torque Omega + P_soil + P_friction = d(kinetic + potential)/dt, P_soil = F_soil . v_D (machine frame, an
inertial frame: the machine travels at constant speed), P_friction = -T S' <= 0.  One CasADi Function serves floats
(check, result.json) and symbols (the NLP's rules and objective).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from synthesis.constraints import Rule
from synthesis.constraints.dynamics import (
    peak_input_torque_rule,
    peak_shaking_force_rule,
    peak_shaking_moment_rule,
)
from synthesis.dynamics import mass as mass_properties
from synthesis.dynamics.facts import link_facts, peaks, sampled_facts, turn
from synthesis.kinds.tillage_linkage.kinematics import tool_point
from synthesis.kinds.tillage_linkage.spec import TillageDynamicsSection

TWO_PI = 2.0 * math.pi
#: the moving links in the order of the mass vector, and their names in result.json
LINKS = ("crank", "bar")
LINK_NAMES = ("flywheel with crank AB", "tillage bar BD with the tool")
#: the joints in the order of the ``reactions`` output, and their roles
JOINTS = ("A", "B", "C")
JOINT_ROLES = {"A": "crank_pivot", "B": "crank_pin", "C": "roller"}
#: the geometry vector: a, b, c (mm), theta (rad), height of C above the ground (mm)
GEOMETRY = ("a", "b", "c", "theta", "height_c")
#: the soil and roller vector: f0 (N), k (N/mm), forward speed (m/s), roller friction coefficient
SOIL = ("f0", "k", "forward_speed", "roller_friction")
#: the sliding speed (m/s) over which the roller friction turns from one direction to the other: tanh(S' / V_SLIP)
#: differs from sign(S') by less than 1e-9 where |S'| > 11 V_SLIP = 11 mm/s, i.e. outside about 1 deg of crank around
#: the bar's two stroke reversals (omega = theta, theta + 180 deg) at the library's 60 r/min and 120 mm crank
V_SLIP = 1.0e-3
OUTPUTS = ("torque", "reactions", "roller_normal", "shaking_force", "shaking_moment", "com", "angle", "com_velocity",
           "angular_velocity", "kinetic_energy", "potential_energy", "soil_force", "depth", "external_power",
           "friction_power", "sliding_speed")
#: where the rules are evaluated
WHERE = "over a turn"


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


@lru_cache(maxsize=1)
def inverse_dynamics() -> ca.Function:
    """(q rad, geometry (5), mass (8), soil (4), Omega rad/s, gravity (2) m/s^2) -> :data:`OUTPUTS`.

    ``geometry``: :data:`GEOMETRY`; ``mass``: per link (:data:`LINKS`) mass kg, centre of mass (m, link frame),
    inertia about it kg m^2; ``soil``: :data:`SOIL`.  Outputs: torque N m; reactions (2, 3) N at A, B, C; the
    roller's normal force N (signed, along e turned +90 deg); shaking force (2) N; shaking moment N m about A; com
    (2, 2) m and angle (2) rad of each link; their velocities m/s and rad/s; kinetic and potential energy J; the soil
    force (2) N; the tool's depth mm (negative above the ground); the soil force's power and the roller friction's
    (machine frame) W; the bar's sliding speed S' m/s.
    """
    q, omega = ca.SX.sym("q"), ca.SX.sym("omega")
    geom, mass, soil, g = ca.SX.sym("geometry", 5), ca.SX.sym("mass", 8), ca.SX.sym("soil", 4), ca.SX.sym("g", 2)
    a_mm, b_mm, c_mm, theta, height = (geom[i] for i in range(5))
    f0, k, forward, mu = (soil[i] for i in range(4))
    pivot = ca.vertcat(b_mm * ca.cos(theta), b_mm * ca.sin(theta)) / 1000.0
    pin = pivot + a_mm * ca.vertcat(ca.cos(q), ca.sin(q)) / 1000.0
    length = ca.sqrt(ca.dot(pin, pin))                                 # S = |CB| (C at the origin), m
    e = -pin / length
    normal = ca.vertcat(-e[1], e[0])
    tool = ca.vertcat(*tool_point(q, a_mm, b_mm, c_mm, theta)) / 1000.0
    psi = ca.atan2(e[1], e[0])

    def in_frame(origin, ux, uy, x, y):
        return ca.vertcat(origin[0] + x * ux - y * uy, origin[1] + x * uy + y * ux)

    com = [in_frame(pivot, ca.cos(q), ca.sin(q), mass[1], mass[2]), in_frame(pin, e[0], e[1], mass[5], mass[6])]
    moving = ca.vertcat(com[0], com[1], q, psi, tool, length)
    d1 = ca.jacobian(moving, q)
    d2 = ca.jacobian(d1, q)
    vel, acc = d1 * omega, d2 * omega ** 2
    m, inertia = (mass[0], mass[4]), (mass[3], mass[7])
    com_vel = [vel[0:2], vel[2:4]]
    com_acc = [acc[0:2], acc[2:4]]
    spin, alpha = [vel[4], vel[5]], [acc[4], acc[5]]
    tool_vel, sliding = vel[6:8], vel[8]
    # the soil: depth below the ground line (mm) and D's velocity relative to the soil (machine frame, m/s)
    depth = -height - tool[1] * 1000.0
    relative = tool_vel + ca.vertcat(forward, 0.0)
    relative_speed = ca.sqrt(ca.dot(relative, relative))
    soil_force = ca.if_else(depth > 0.0, -(f0 + k * depth) * relative / relative_speed, ca.DM.zeros(2))
    # the bar: what the joints must supply, the roller's normal force from the moments about B, its friction along e
    need_bar = m[1] * (com_acc[1] - g)
    moment_b = inertia[1] * alpha[1] + _cross(com[1] - pin, need_bar) - _cross(tool - pin, soil_force)
    roller_normal = moment_b / length
    friction = mu * ca.fabs(roller_normal) * ca.tanh(sliding / V_SLIP)
    roller = roller_normal * normal + friction * e
    f_pin = need_bar - soil_force - roller
    # the crank
    need_crank = m[0] * (com_acc[0] - g)
    f_pivot = need_crank + f_pin
    torque = inertia[0] * alpha[0] + _cross(com[0] - pivot, need_crank) + _cross(pin - pivot, f_pin)
    shaking_force = -(f_pivot + roller)
    shaking_moment = -torque - _cross(-pivot, roller)
    kinetic = sum(0.5 * m[j] * ca.dot(com_vel[j], com_vel[j]) + 0.5 * inertia[j] * spin[j] ** 2 for j in range(2))
    potential = -sum(m[j] * ca.dot(g, com[j]) for j in range(2))
    external = ca.dot(soil_force, tool_vel)
    dissipated = -friction * sliding
    return ca.Function(
        "tillage_inverse_dynamics", [q, geom, mass, soil, omega, g],
        [torque, ca.horzcat(f_pivot, f_pin, roller), roller_normal, shaking_force, shaking_moment, ca.horzcat(*com),
         ca.vertcat(q, psi), ca.horzcat(*com_vel), ca.vertcat(*spin), kinetic, potential, soil_force, depth,
         external, dissipated, sliding],
        ["q", "geometry", "mass", "soil", "omega", "gravity"], list(OUTPUTS))


@dataclass(frozen=True)
class TillageDynamics:
    """Everything the inverse dynamics reads: geometry (mm, rad), mass vector (SI), soil vector, the flywheel speed
    (rad/s), gravity (m/s^2).  Geometry, mass, speeds may be CasADi symbols."""

    geometry: tuple
    mass: tuple
    soil: tuple
    omega: Any
    gravity: tuple

    @classmethod
    def of(cls, table: TillageDynamicsSection, a, b, c, theta_rad, height_c, crank_rate, forward_speed
           ) -> TillageDynamics:
        """From a spec's ``[dynamics]`` table at the design (a, b, c, height_c mm, theta rad: floats or symbols), the
        flywheel speed (rad/s) and the forward speed (m/s).  A link given as a bar is the segment between its joints
        (crank A -> B, length a; bar B -> D, length c); a point mass at ``"tip"`` sits at D."""
        bars = {"crank": [((0.0, 0.0), (a, 0.0))], "bar": [((0.0, 0.0), (c, 0.0))]}
        tips = {"bar": (c, 0.0)}
        masses = []
        for name in LINKS:
            carried = [pm for pm in table.point_masses if pm.link == name]
            masses += list(mass_properties.link_properties(getattr(table, name), bars[name], carried, tips.get(name)))
        soil = table.soil
        soil_vector = (0.0 if soil is None else soil.f0, 0.0 if soil is None else soil.k, forward_speed,
                       table.roller_friction)
        return cls((a, b, c, theta_rad, height_c), tuple(masses), soil_vector, crank_rate, tuple(table.gravity))

    def over(self, crank) -> dict:
        """:func:`inverse_dynamics` at the crank angles ``crank`` (rad), by name.  On floats every output is a numpy
        array with the samples last (torque (N,), reactions (2, 3, N) ...); on symbols a CasADi row or matrix of the
        mapped Function (torque 1 x N, shaking force 2 x N, ...), for rules."""
        n = int(np.size(crank))
        f = inverse_dynamics().map(n)
        args = [np.asarray(crank, float).reshape(1, -1), ca.vertcat(*self.geometry), ca.vertcat(*self.mass),
                ca.vertcat(*self.soil), self.omega, ca.vertcat(*self.gravity)]
        out = dict(zip(OUTPUTS, f(*args)))
        if any(isinstance(v, (ca.SX, ca.MX)) for v in out.values()):
            return out
        arrays = {k: np.asarray(v, float) for k, v in out.items()}
        arrays["reactions"] = arrays["reactions"].reshape(2, n, 3).transpose(0, 2, 1)   # map stacks columns per sample
        for key in ("com", "com_velocity"):
            arrays[key] = arrays[key].reshape(2, n, 2).transpose(0, 2, 1)
        for key in ("torque", "roller_normal", "shaking_moment", "kinetic_energy", "potential_energy", "depth",
                    "external_power", "friction_power", "sliding_speed"):
            arrays[key] = arrays[key].ravel()
        return arrays


def _column(values):
    """Sampled values as a column: a CasADi vector for symbols, a flat numpy array for numbers."""
    return np.ravel(values) if isinstance(values, np.ndarray) else ca.vec(values)


def sampled(dyn: TillageDynamics, crank: np.ndarray) -> tuple:
    """(input torque N m, shaking force x, y N, shaking moment N m about A) at the crank angles ``crank`` (rad), as
    columns: what the rules and the min-peak objective read (floats or symbols)."""
    out = dyn.over(crank)
    force = out["shaking_force"]
    return _column(out["torque"]), _column(force[0, :]), _column(force[1, :]), _column(out["shaking_moment"])


def dynamics_rules(dyn: TillageDynamics, limits, crank: np.ndarray) -> list[Rule]:
    """The ``[dynamics.limits]`` rules at the crank angles ``crank`` (none without a limit)."""
    if not limits.any_given():
        return []
    torque, fx, fy, moment = sampled(dyn, crank)
    rules = []
    if limits.peak_input_torque is not None:
        rules.append(peak_input_torque_rule(torque, limits.peak_input_torque, f"{WHERE}, on the flywheel"))
    if limits.peak_shaking_force is not None:
        rules.append(peak_shaking_force_rule(fx, fy, limits.peak_shaking_force, WHERE))
    if limits.peak_shaking_moment is not None:
        rules.append(peak_shaking_moment_rule(moment, limits.peak_shaking_moment, f"{WHERE}, about the flywheel "
                                                                                  f"centre A"))
    return rules


def peak_epigraph(dyn: TillageDynamics, crank: np.ndarray) -> tuple:
    """The epigraph of ``min_peak_torque`` (smooth): a variable t (N m) with rows t - torque >= 0 and t + torque >= 0
    at every crank angle of ``crank``, t to be minimised.  Returns (t, rows)."""
    torque, _, _, _ = sampled(dyn, crank)
    t = ca.SX.sym("peak_torque")
    return t, [(t - torque, 0.0, None), (t + torque, 0.0, None)]


def peak_torque(dyn: TillageDynamics, crank: np.ndarray) -> float:
    """The largest |input torque| (N m) at ``crank``, floats."""
    torque, _, _, _ = sampled(dyn, crank)
    return float(np.abs(torque).max())


CONVENTIONS = ("flywheel (crank AB) at constant speed, counter-clockwise; reaction at a joint: force of the link "
               "nearer the frame on the next (N, machine frame): A frame on crank, B crank on bar, C rollers on bar "
               "(normal to the bar, plus friction along it when roller_friction > 0; roller_normal_N: along the bar "
               "direction B -> D turned +90 deg); input torque: the motor's on the flywheel, counter-clockwise "
               "positive; shaking force and moment (about A): what the moving links put on the frame through A and "
               "C, gravity and the soil force included; powers in the machine frame (the soil's: force . D's "
               "velocity relative to the machine)")


def dynamics_facts(dyn: TillageDynamics, samples: int, crank_speed_rpm: float, table: TillageDynamicsSection) -> dict:
    """result.json's ``facts.dynamics`` over a turn, with the four-bar kinds' keys
    (synthesis.dynamics.linkage.dynamics_facts) and the tillage's own: the roller's normal force, the soil force and
    depth, the roller friction's power; enough to re-check the energy balance from the file alone."""
    crank = turn(samples)
    out = dyn.over(crank)
    loads: bool | dict = False
    soil_force = out["soil_force"]
    if table.soil is not None:
        loads = {"loads": [{"name": "soil force on the tool D", "link": "bar", "at": "tip",
                            "model": "while D is below the ground (depth d > 0): magnitude f0 + k d, opposing D's "
                                     "velocity relative to the soil (ground frame); zero above the ground",
                            **table.soil.model_dump()}],
                 "external_power_W": out["external_power"].tolist(),
                 "force_N": soil_force.T.tolist(),
                 "depth_mm": out["depth"].tolist()}
    facts = sampled_facts(crank, out, float(dyn.omega), crank_speed_rpm, JOINTS, tuple(JOINT_ROLES.values()),
                          link_facts(out, dyn.mass, LINK_NAMES, LINKS), dyn.gravity, loads, CONVENTIONS,
                          table.assumption)
    facts["roller_normal_N"] = out["roller_normal"].tolist()
    if table.roller_friction > 0.0:
        facts |= {"roller_friction": table.roller_friction, "friction_power_W": out["friction_power"].tolist()}
    facts["summary"]["mean_power_W"] = float(np.mean(out["torque"] * float(dyn.omega)))
    if table.soil is not None:
        facts["summary"] |= {"soil_force_N": peaks(np.hypot(*soil_force), crank),
                             "mean_soil_power_W": float(np.mean(out["external_power"]))}
    return facts
