"""Inverse dynamics of one comb-finger unit at the constant speed omega (Newton-Euler, closed form).

The mechanism as the kind models it (geometry.py): the drum (cone) turns about its axis S; its fingers pass through
the drum wall and turn about the hub R, which the eccentric crank P holds fixed to the frame; each finger turns
uniformly at the drum's speed omega (the kind's kinematics: turn angle phi = omega t from straight down, eq 22), its
tip at T = R + r (sin phi, -cos phi).  Moving bodies, front view (machine frame):

    rotor     the drum with its shaft, about S; frame origin S, x along the first finger's direction (sin phi, -cos phi)
    finger k  origin R, x towards its tip, at phi + 2 pi k / n (n fingers evenly spaced over a turn)

Centres of mass and angles are closed-form functions of phi through the kind's own geometry (``g.hub``,
``g.drum_axis``, ``g.tip``); velocities and accelerations are CasADi's exact derivatives in phi times omega and
omega^2.  The drum turns each finger through the wall by a couple (an equal-speed drive: the guide's own force on the
finger, which the kind's uniform finger turn does not resolve, is not modelled), so:

* each finger's couple tau_k from its moments about R (its angular acceleration is 0, but written out);
* the eccentric's force on the fingers at R from their force balances;
* the drive torque on the drum from its moments about S plus every tau_k (the couples it passes on);
* the drum bearing's force at S from the drum's force balance.

The combing load (``combing_load``, our assumption): while finger k's tip is in the combing turn (from its lowest
point, phase 0, to F, phase ``g.combing_turn`` = 90 deg + alpha) a force of constant magnitude opposing the tip's
velocity in the front view; zero elsewhere (a CasADi if_else: exact samples, a jump in the torque at entry and exit).

Sign conventions (the four-bar kinds', synthesis/dynamics/fourbar.py): a joint's reaction is the force of the frame
on the moving body (S: on the drum; R: the eccentric on the fingers together); the drive torque is the motor's on
the drum, counter-clockwise positive (the finger turns counter-clockwise in the front view of the left unit), power
= torque x omega; the shaking force and moment (about S) are what the moving bodies put on the frame, gravity
included (the crop's force is not the frame's).

Energy: torque omega + P_load = d(kinetic + potential)/dt, P_load = sum of F_k . T_k' (machine frame).  One CasADi
Function per finger count serves floats (check, result.json) and symbols (the NLP's rules).
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
from synthesis.dynamics.facts import link_facts, sampled_facts, turn
from synthesis.kinds.comb_finger import geometry as g
from synthesis.kinds.comb_finger.spec import CombFingerDynamicsSection

TWO_PI = 2.0 * math.pi
#: the joints in the order of the ``reactions`` output, and their roles
JOINTS = ("S", "R")
JOINT_ROLES = {"S": "crank_pivot", "R": "eccentric"}
#: the geometry vector: r, e, b (mm), alpha (rad)
GEOMETRY = ("r", "e", "alpha", "b")
OUTPUTS = ("torque", "reactions", "finger_torque", "shaking_force", "shaking_moment", "com", "angle", "com_velocity",
           "angular_velocity", "kinetic_energy", "potential_energy", "load_force", "in_zone", "external_power")
#: where the rules are evaluated
WHERE = "over a turn"


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


@lru_cache(maxsize=8)
def inverse_dynamics(fingers: int) -> ca.Function:
    """(phi rad, geometry (4), rotor mass (4), finger mass (4), load N, omega rad/s, gravity (2) m/s^2) ->
    :data:`OUTPUTS` for a unit of ``fingers`` fingers.

    ``geometry``: :data:`GEOMETRY`; a mass vector: mass kg, centre of mass (m, the body's frame), inertia about it
    kg m^2 (each finger the same).  Outputs: drive torque N m; reactions (2, 2) N at S and R; each finger's couple
    from the drum (n) N m; shaking force (2) N; shaking moment N m about S; com (2, 1 + n) m and angle (1 + n) rad of
    the rotor and each finger; their velocities m/s and rad/s; kinetic and potential energy J; the load on each tip
    (2, n) N; 1 where a tip is in the combing turn (n); the loads' power W.
    """
    n = fingers
    phi, omega, load = ca.SX.sym("phi"), ca.SX.sym("omega"), ca.SX.sym("load")
    geom, rotor, finger, grav = ca.SX.sym("geometry", 4), ca.SX.sym("rotor", 4), ca.SX.sym("finger", 4), \
        ca.SX.sym("g", 2)
    r, e, alpha, b = (geom[i] for i in range(4))
    s = ca.vertcat(*g.drum_axis(r, e, alpha, b)) / 1000.0
    hub = ca.vertcat(*g.hub(r, e, alpha, b)) / 1000.0
    zone_end = g.combing_turn(r, e, alpha, b)

    def body_point(origin, turn, x, y):
        ux, uy = ca.sin(turn), -ca.cos(turn)                  # the finger's direction at turn angle ``turn``
        return ca.vertcat(origin[0] + x * ux - y * uy, origin[1] + x * uy + y * ux)

    phases = [phi + TWO_PI * k / n for k in range(n)]
    com = [body_point(s, phi, rotor[1], rotor[2])] + [body_point(hub, p, finger[1], finger[2]) for p in phases]
    tips = [ca.vertcat(*g.tip(r, e, alpha, b, p)) / 1000.0 for p in phases]
    angles = [phi - math.pi / 2.0] + [p - math.pi / 2.0 for p in phases]
    moving = ca.vertcat(*com, *tips, *angles)
    d1 = ca.jacobian(moving, phi)
    d2 = ca.jacobian(d1, phi)
    vel, acc = d1 * omega, d2 * omega ** 2
    bodies = 1 + n
    com_vel = [vel[2 * j:2 * j + 2] for j in range(bodies)]
    com_acc = [acc[2 * j:2 * j + 2] for j in range(bodies)]
    tip_vel = [vel[2 * bodies + 2 * k:2 * bodies + 2 * k + 2] for k in range(n)]
    spin = [vel[4 * bodies - 2 + j] for j in range(bodies)]
    spin_acc = [acc[4 * bodies - 2 + j] for j in range(bodies)]
    masses = [rotor[0]] + [finger[0]] * n
    inertia = [rotor[3]] + [finger[3]] * n
    # the combing load: the phase of each tip from its lowest point, in [0, 2 pi)
    in_zone, loads = [], []
    for k, p in enumerate(phases):
        phase = p - TWO_PI * ca.floor(p / TWO_PI)
        inside = ca.if_else(phase <= zone_end, 1.0, 0.0)
        speed = ca.sqrt(ca.dot(tip_vel[k], tip_vel[k]))
        in_zone.append(inside)
        loads.append(-inside * load * tip_vel[k] / speed)
    # each finger: the couple from the drum (moments about R), the eccentric's force at R
    couples, f_hub = [], ca.DM.zeros(2)
    for k in range(n):
        need = masses[1 + k] * (com_acc[1 + k] - grav)
        couples.append(inertia[1 + k] * spin_acc[1 + k] + _cross(com[1 + k] - hub, need)
                       - _cross(tips[k] - hub, loads[k]))
        f_hub = f_hub + need - loads[k]
    # the drum: the bearing force at S, the drive torque (its own moments about S and the couples it passes on)
    need_rotor = masses[0] * (com_acc[0] - grav)
    f_bearing = need_rotor
    torque = inertia[0] * spin_acc[0] + _cross(com[0] - s, need_rotor) + sum(couples)
    shaking_force = -(f_bearing + f_hub)
    shaking_moment = -torque - _cross(hub - s, f_hub)
    kinetic = sum(0.5 * masses[j] * ca.dot(com_vel[j], com_vel[j]) + 0.5 * inertia[j] * spin[j] ** 2
                  for j in range(bodies))
    potential = -sum(masses[j] * ca.dot(grav, com[j]) for j in range(bodies))
    external = sum(ca.dot(loads[k], tip_vel[k]) for k in range(n))
    return ca.Function(
        f"comb_finger_inverse_dynamics_{n}", [phi, geom, rotor, finger, load, omega, grav],
        [torque, ca.horzcat(f_bearing, f_hub), ca.vertcat(*couples), shaking_force, shaking_moment,
         ca.horzcat(*com), ca.vertcat(*angles), ca.horzcat(*com_vel), ca.vertcat(*spin), kinetic, potential,
         ca.horzcat(*loads), ca.vertcat(*in_zone), external],
        ["phi", "geometry", "rotor", "finger", "load", "omega", "gravity"], list(OUTPUTS))


@dataclass(frozen=True)
class FingerDynamics:
    """Everything the inverse dynamics reads: geometry (mm, rad), the rotor's and one finger's mass vectors (SI), the
    load on a tip (N), omega (rad/s), gravity (m/s^2).  Geometry, the finger's mass and omega may be CasADi
    symbols."""

    fingers: int
    geometry: tuple
    rotor: tuple
    finger: tuple
    load: float
    omega: Any
    gravity: tuple

    @classmethod
    def of(cls, table: CombFingerDynamicsSection, r, e, alpha_rad, b, omega) -> FingerDynamics:
        """From a spec's ``[dynamics]`` table at the design (r, e, b mm, alpha rad, omega rad/s: floats or symbols).
        A finger given as a bar runs from R to the tip (length r); a point mass at ``"tip"`` sits at the tip."""
        carried = {name: [pm for pm in table.point_masses if pm.link == name] for name in ("rotor", "finger")}
        rotor = mass_properties.link_properties(table.rotor, [], carried["rotor"])
        finger = mass_properties.link_properties(table.finger, [((0.0, 0.0), (r, 0.0))], carried["finger"], (r, 0.0))
        load = 0.0 if table.combing_load is None else table.combing_load.force
        return cls(table.fingers, (r, e, alpha_rad, b), tuple(rotor), tuple(finger), load, omega,
                   tuple(table.gravity))

    def over(self, turn_angles) -> dict:
        """:func:`inverse_dynamics` at the turn angles (rad), by name.  On floats every output is a numpy array with
        the samples last (torque (N,), reactions (2, 2, N), com (2, 1 + n, N) ...); on symbols a CasADi row or matrix
        of the mapped Function (torque 1 x N, shaking force 2 x N, ...), for rules."""
        count = int(np.size(turn_angles))
        f = inverse_dynamics(self.fingers).map(count)
        args = [np.asarray(turn_angles, float).reshape(1, -1), ca.vertcat(*self.geometry), ca.vertcat(*self.rotor),
                ca.vertcat(*self.finger), self.load, self.omega, ca.vertcat(*self.gravity)]
        out = dict(zip(OUTPUTS, f(*args)))
        if any(isinstance(v, (ca.SX, ca.MX)) for v in out.values()):
            return out
        arrays = {k: np.asarray(v, float) for k, v in out.items()}
        bodies = 1 + self.fingers
        arrays["reactions"] = arrays["reactions"].reshape(2, count, 2).transpose(0, 2, 1)   # map stacks per sample
        for key, width in (("com", bodies), ("com_velocity", bodies), ("load_force", self.fingers)):
            arrays[key] = arrays[key].reshape(2, count, width).transpose(0, 2, 1)
        for key in ("torque", "shaking_moment", "kinetic_energy", "potential_energy", "external_power"):
            arrays[key] = arrays[key].ravel()
        return arrays


def _column(values):
    """Sampled values as a column: a CasADi vector for symbols, a flat numpy array for numbers."""
    return np.ravel(values) if isinstance(values, np.ndarray) else ca.vec(values)


def dynamics_rules(dyn: FingerDynamics, limits, turn_angles: np.ndarray) -> list[Rule]:
    """The ``[dynamics.limits]`` rules at the turn angles (none without a limit)."""
    if not limits.any_given():
        return []
    out = dyn.over(turn_angles)
    force = out["shaking_force"]
    rules = []
    if limits.peak_input_torque is not None:
        rules.append(peak_input_torque_rule(_column(out["torque"]), limits.peak_input_torque, f"{WHERE}, on the drum"))
    if limits.peak_shaking_force is not None:
        rules.append(peak_shaking_force_rule(_column(force[0, :]), _column(force[1, :]), limits.peak_shaking_force,
                                             WHERE))
    if limits.peak_shaking_moment is not None:
        rules.append(peak_shaking_moment_rule(_column(out["shaking_moment"]), limits.peak_shaking_moment,
                                              f"{WHERE}, about the drum axis S"))
    return rules


CONVENTIONS = ("one unit (the left; the right is its mirror image in the row's centre line, turning the other way); "
               "crank_deg: the turn angle phi of the first finger from straight down; the drum and the fingers turn "
               "counter-clockwise at omega; reaction at a joint: the frame's force on the moving body (N, machine "
               "frame, front view): S the drum bearing on the drum, R the eccentric on all the fingers; "
               "finger_torque_Nm: the couple the drum puts on each finger (N x n); input torque: the motor's on the "
               "drum, counter-clockwise positive; shaking force and moment (about S): what the moving bodies put on "
               "the frame, gravity included; the loads' power in the machine frame")


def dynamics_facts(dyn: FingerDynamics, samples: int, speed_rpm: float, table: CombFingerDynamicsSection) -> dict:
    """result.json's ``facts.dynamics`` over a turn, with the four-bar kinds' keys
    (synthesis.dynamics.linkage.dynamics_facts; ``crank_deg`` is the turn angle phi) and the unit's own: each
    finger's couple from the drum, the combing load and where it acts; enough to re-check the energy balance from
    the file alone."""
    angles = turn(samples)
    out = dyn.over(angles)
    names = ("drum (rotor) about S",) + tuple(f"finger {k + 1} about R" for k in range(dyn.fingers))
    roles = ("crank",) + ("finger",) * dyn.fingers
    mass = [v for j in range(len(names)) for v in (dyn.rotor if j == 0 else dyn.finger)[:4]]
    loads: bool | dict = False
    load_force = out["load_force"]                                   # (2, n, N)
    if table.combing_load is not None:
        loads = {"loads": [{"name": "combing load on each finger tip", "link": "finger", "at": "tip",
                            "model": "while the tip is in the combing turn (from its lowest point to F, 90 deg + "
                                     "alpha): a constant magnitude opposing its velocity in the front view; zero "
                                     "elsewhere",
                            **table.combing_load.model_dump()}],
                 "external_power_W": out["external_power"].tolist(),
                 "force_N": load_force.sum(axis=1).T.tolist(),
                 "tips_in_zone": np.asarray(out["in_zone"]).sum(axis=0).astype(int).tolist()}
    facts = sampled_facts(angles, out, float(dyn.omega), speed_rpm, JOINTS, tuple(JOINT_ROLES.values()),
                          link_facts(out, mass, names, roles), dyn.gravity, loads, CONVENTIONS, table.assumption)
    facts["finger_torque_Nm"] = out["finger_torque"].T.tolist()
    facts["summary"]["mean_power_W"] = float(np.mean(out["torque"] * float(dyn.omega)))
    if table.combing_load is not None:
        facts["summary"]["mean_load_power_W"] = float(np.mean(out["external_power"]))
    return facts
