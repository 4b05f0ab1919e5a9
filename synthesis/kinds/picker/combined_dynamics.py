"""The combined picker's inverse dynamics over a turn of the crank GF (docs/ARCHITECTURE.md "Dynamics").

Two four-bars on the shared Newton-Euler Function (:func:`synthesis.dynamics.fourbar.inverse_dynamics`), joined as the
kind's kinematics joins them (synthesis/kinds/picker/combined.py): the rocker AE of the crank-rocker AEFG and the
crank AB of the double crank ABCD are **one rigid body turning about A**, so AB turns by what AE turns,
phi1 = phi10 + m (beta(phi7) - beta_pick), phi7 = phi_pick + s omega t (m the mount, s the sense).

* Stage 1, the drive: the crank GF at the constant ``[operation] crank_speed``, in the machine frame (crank pivot O =
  G, the frame G -> A along theta2 + 180 deg, the crank angle m phi7 from it, the assembly branch m times the drive's
  own: a mirrored mount is the mirror image).  Its speed is m s omega.
* Stage 2, the double crank: its crank AB turns at omega_2 = m s beta'(phi7) omega with alpha_2 = m beta''(phi7)
  omega^2, beta' and beta'' exact (CasADi's derivatives of the drive's rocker angle, rocker_drive.rocker_function);
  zero speed at both ends of the swing.  Its input torque T_2 is what AE puts on AB through the rigid body; stage 1's
  rocker gets the reaction, a couple -T_2 (the shared Function's ``moments``).
* The rigid body's mass is split between the stages, each half in its own model: AE's part (``[dynamics.
  crank_rocker] rocker``, link frame A -> E) is stage 1's rocker, AB's (``[dynamics.double_crank] crank``, A -> B)
  stage 2's crank.  Both turn about the same fixed pivot A at the same speed, so the sum of the two halves' equations
  is the whole body's, the couple T_2 internal to it; the frame's force on the body at A is the sum of the two
  stages' pivot forces there (joint ``A``; how it divides between the halves is not determined, and not reported).
* The input torque is stage 1's (the motor's on GF).  The shaking force is the sum of both stages' (the frame's
  pivots G, A and D).  The shaking moment about G: stage 1's (its motor reaction -T_1 and its pivot A), plus stage
  2's frame forces moved to G.  The shared Function counts stage 2's moment as -T_2 - (D - A) x F_D about A, -T_2 being
  the reaction of a motor on the frame; here T_2 comes from AE, whose own reaction stage 1 already carries, so stage
  2 adds only its pivots' forces: M_G = M_1 + (M_2 + T_2) + (A - G) x F_2 (M_2, F_2 its shaking moment about A and
  force).  Check: it equals -sum_k (I_k alpha_k + (c_k - G) x m_k (a_k - g)) over the six links (tests).

One CasADi Function per assembly (drive branch, mount, double crank branch) serves floats (check, result.json) and
symbols (rules on a design's symbols: the same function), mapped over the instants.  Frames: machine (mm, y up);
link frames as the parts' (origin at the first joint, x towards the second, y counter-clockwise from x).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

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
from synthesis.dynamics.fourbar import LINKS as PART_LINKS
from synthesis.dynamics.fourbar import inverse_dynamics
from synthesis.kinds.picker.spec import PickerDynamicsSection
from synthesis.kinematics.rocker_drive import rocker_function

if TYPE_CHECKING:
    from synthesis.kinds.picker.combined import Drive

#: the design parameters of the combined dynamics, in the order of its vector: the drive's lengths (mm), the double
#: crank's parameters (synthesis.kinds.picker.kinematics.linkage.PARAMETERS: mm, rad), AB at picking phi10, the drive's
#: crank and rocker angles at picking (its own frame), the direction theta2 of A -> G (rad), the sense s (+-1) and the
#: crank speed omega (rad/s)
PARAMETERS = ("l7", "l8", "l9", "l10", "x_a", "y_a", "l1", "l2", "l3", "l4", "l5", "phi3", "phi4", "phi10",
              "phi_pick", "beta_pick", "theta2", "sense", "omega")
#: the joints: the drive's G, F, E, the shared pivot A (the frame's force on the rigid body AE + AB), the double
#: crank's B, C, D
JOINTS = ("G", "F", "E", "A", "B", "C", "D")
ROLES = ("crank_pivot", "crank_pin", "coupler_rocker", "rocker_pivot", "driven_crank_pin", "driven_coupler_follower",
         "follower_pivot")
LINKS = ("crank GF", "coupler FE", "rocker AE", "crank AB", "coupler BC with clamp arm CM", "follower CD")
LINK_ROLES = ("crank", "coupler", "rocker", "driven_crank", "driven_coupler", "driven_follower")
OUTPUTS = ("torque", "driven_torque", "reactions", "shaking_force", "shaking_moment", "com", "angle", "com_velocity",
           "angular_velocity", "kinetic_energy", "potential_energy", "crank_ab", "crank_ab_speed",
           "crank_ab_acceleration")
#: instants over a turn at which check evaluates the dynamics rules (every 0.1 deg of GF)
CHECK_SAMPLES = 3600
WHERE = "over a turn of the crank GF"


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _named(f: ca.Function, *args) -> dict:
    return dict(zip(f.name_out(), f(*args)))


@lru_cache(maxsize=8)
def picker_inverse_dynamics(drive_branch: int, mount: int, dc_branch: int) -> ca.Function:
    """(tau rad, q (:data:`PARAMETERS`), drive mass (12), double crank mass (12), gravity (2) m/s^2) -> :data:`OUTPUTS`
    at the instant the crank GF has turned by tau since picking.  ``drive_branch`` is the crank-rocker's own assembly,
    ``mount`` +1 or -1 (mirrored), ``dc_branch`` the double crank's.  Outputs: torque N m (the motor's on GF), the
    driven torque N m (AE's on AB), reactions (2, 7) N in :data:`JOINTS` order, shaking force (2) N, shaking moment N m
    about G, com (2, 6) m (machine frame), angle (6) rad, their velocities, kinetic and potential energy J, AB's angle
    phi1 (rad, from AD), speed and acceleration."""
    tau, q = ca.SX.sym("tau"), ca.SX.sym("q", len(PARAMETERS))
    mass_drive, mass_dc, g = ca.SX.sym("mass_drive", 12), ca.SX.sym("mass_double_crank", 12), ca.SX.sym("g", 2)
    (l7, l8, l9, l10, x_a, y_a, l1, l2, l3, l4, _, phi3, _, phi10, phi_pick, beta_pick, theta2, sense,
     omega) = (q[i] for i in range(len(PARAMETERS)))
    phi7 = phi_pick + sense * tau
    beta, dbeta, ddbeta = rocker_function(drive_branch)(phi7, ca.vertcat(l7, l8, l9, l10))[:3]
    phi1 = phi10 + mount * (beta - beta_pick)
    speed, acceleration = mount * sense * omega * dbeta, mount * omega ** 2 * ddbeta
    no_loads, no_soil = ca.DM.zeros(12), ca.DM.zeros(6)
    second = _named(inverse_dynamics(dc_branch, True, False),
                    phi1, ca.vertcat(l4, l1, l2, l3, -phi3), mass_dc, no_loads, speed, acceleration, ca.DM.zeros(3),
                    no_soil, g)
    driven = second["torque"]
    # the drive in the machine frame: the frame G -> A along theta2 + 180 deg, mirrored (crank angle and assembly
    # side reversed) when mounted so; the reaction of AB's input torque on AE as a couple
    first = _named(inverse_dynamics(mount * drive_branch, True, False),
                   mount * phi7, ca.vertcat(l10, l7, l8, l9, theta2 - math.pi), mass_drive, no_loads,
                   mount * sense * omega, 0.0, ca.vertcat(0.0, 0.0, -driven), no_soil, g)
    pivot_a = ca.vertcat(x_a, y_a) / 1000.0                          # m, machine frame
    a_from_g = -l10 * ca.vertcat(ca.cos(theta2), ca.sin(theta2)) / 1000.0
    com = ca.horzcat(first["com"] + ca.repmat(pivot_a - a_from_g, 1, 3), second["com"] + ca.repmat(pivot_a, 1, 3))
    masses = [mass_drive[4 * k] for k in range(3)] + [mass_dc[4 * k] for k in range(3)]
    r1, r2 = first["reactions"], second["reactions"]
    force = first["shaking_force"] + second["shaking_force"]
    # stage 2's shaking moment about A less its motor term (-T_2: AE's reaction, in stage 1), moved to G
    moment = first["shaking_moment"] + second["shaking_moment"] + driven + _cross(a_from_g, second["shaking_force"])
    outputs = [first["torque"], driven, ca.horzcat(r1[:, 0:3], r1[:, 3] + r2[:, 0], r2[:, 1:4]), force, moment, com,
               ca.vertcat(first["angle"], second["angle"]),
               ca.horzcat(first["com_velocity"], second["com_velocity"]),
               ca.vertcat(first["angular_velocity"], second["angular_velocity"]),
               first["kinetic_energy"] + second["kinetic_energy"],
               -sum(masses[k] * ca.dot(g, com[:, k]) for k in range(6)), phi1, speed, acceleration]
    return ca.Function(f"picker_inverse_dynamics_{drive_branch}_{mount}_{dc_branch}".replace("-", "m"),
                       [tau, q, mass_drive, mass_dc, g], outputs, ["tau", "q", "mass_drive", "mass_double_crank",
                                                                    "gravity"], list(OUTPUTS))


@dataclass(frozen=True)
class PickerDynamics:
    """Everything the combined dynamics reads: the assembly (the drive's branch, its mount, the double crank's
    branch), the parameters q (:data:`PARAMETERS`), both stages' mass vectors and gravity; q and the masses may be
    CasADi symbols."""

    drive_branch: int
    mount: int
    dc_branch: int
    q: tuple
    mass_drive: tuple
    mass_double_crank: tuple
    gravity: tuple

    @classmethod
    def of(cls, table: PickerDynamicsSection, drive_branch: int, mount: int, dc_branch: int, q) -> PickerDynamics:
        """From the spec's ``[dynamics]`` table; bars follow the lengths in q (floats or symbols)."""
        l7, l8, l9, _, _, _, l1, l2, l3, _, l5, _, phi4 = (q[i] for i in range(13))
        clamp = (l2 + l5 * ca.cos(phi4), l5 * ca.sin(phi4))        # M in the coupler's frame (B, x along B -> C)
        drive_bars = {"crank": [((0.0, 0.0), (l7, 0.0))], "coupler": [((0.0, 0.0), (l8, 0.0))],
                      "rocker": [((0.0, 0.0), (l9, 0.0))]}
        dc_bars = {"crank": [((0.0, 0.0), (l1, 0.0))], "coupler": [((0.0, 0.0), (l2, 0.0)), ((l2, 0.0), clamp)],
                   "rocker": [((0.0, 0.0), (l3, 0.0))]}
        return cls(drive_branch, mount, dc_branch, tuple(q[i] for i in range(len(PARAMETERS))),
                   tuple(mass_properties.mass_vector(table.crank_rocker, drive_bars, PART_LINKS)),
                   tuple(mass_properties.mass_vector(table.double_crank, dc_bars, PART_LINKS, {"coupler": clamp})),
                   tuple(table.gravity))

    @property
    def mass(self) -> tuple:
        """The six links' mass properties (mass, com x, y, inertia each), in :data:`LINKS` order."""
        return self.mass_drive + self.mass_double_crank

    def over_turn(self, tau) -> dict:
        """The outputs at the angles ``tau`` (rad) GF has turned since picking: numpy arrays with the samples last
        (torque (N,), reactions (2, 7, N), com (2, 6, N) ...) on floats, the mapped Function's matrices on symbols."""
        n = int(np.size(tau))
        f = picker_inverse_dynamics(self.drive_branch, self.mount, self.dc_branch).map(n)
        out = dict(zip(OUTPUTS, f(np.asarray(tau, float).reshape(1, -1), ca.vertcat(*self.q),
                                  ca.vertcat(*self.mass_drive), ca.vertcat(*self.mass_double_crank),
                                  ca.vertcat(*self.gravity))))
        if any(isinstance(v, (ca.SX, ca.MX)) for v in out.values()):
            return out
        arrays = {k: np.asarray(v, float) for k, v in out.items()}
        for key, columns in (("reactions", len(JOINTS)), ("com", 6), ("com_velocity", 6)):
            arrays[key] = arrays[key].reshape(2, n, columns).transpose(0, 2, 1)   # map stacks columns per sample
        for key in ("torque", "driven_torque", "shaking_moment", "kinetic_energy", "potential_energy", "crank_ab",
                    "crank_ab_speed", "crank_ab_acceleration"):
            arrays[key] = arrays[key].ravel()
        return arrays


def _column(values):
    """Sampled values as a column: a CasADi vector for symbols, a flat numpy array for numbers."""
    return np.ravel(values) if isinstance(values, np.ndarray) else ca.vec(values)


def dynamics_rules(dyn: PickerDynamics, table: PickerDynamicsSection, samples: int = CHECK_SAMPLES) -> list[Rule]:
    """The ``[dynamics.limits]`` rules over ``samples`` instants of a turn of GF (none without a limit): the motor's
    torque on GF, the shaking force summed over G, A and D, the shaking moment about G; floats or symbols."""
    limits = table.limits
    if not limits.any_given():
        return []
    out = dyn.over_turn(turn(samples))
    force = out["shaking_force"]
    rules = []
    if limits.peak_input_torque is not None:
        rules.append(peak_input_torque_rule(_column(out["torque"]), limits.peak_input_torque, f"on GF, {WHERE}"))
    if limits.peak_shaking_force is not None:
        rules.append(peak_shaking_force_rule(_column(force[0, :]), _column(force[1, :]), limits.peak_shaking_force,
                                             f"on the frame at G, A and D, {WHERE}"))
    if limits.peak_shaking_moment is not None:
        rules.append(peak_shaking_moment_rule(_column(out["shaking_moment"]), limits.peak_shaking_moment,
                                              f"{WHERE}, about the crank pivot G"))
    return rules


def conventions(clockwise: bool) -> str:
    return (f"the crank GF at constant speed, turning {'clockwise' if clockwise else 'counter-clockwise'} in the "
            f"machine frame; crank_deg: the angle GF has turned since picking (t = crank_deg / (6 crank_speed_rpm) "
            f"s); reaction at a joint: force of the link nearer the frame on the next (N, machine frame), at A the "
            f"frame's on the rigid body AE + AB; input torque: the motor's on GF, counter-clockwise positive (power = "
            f"torque x GF's signed speed); driven torque: AE's on AB through the rigid body, counter-clockwise "
            f"positive; shaking force: what the moving links put on the frame at G, A and D, gravity included; "
            f"shaking moment: the same about G")


def dynamics_facts(dyn: PickerDynamics, table: PickerDynamicsSection, crank_speed_rpm: float) -> dict:
    """result.json's ``facts.dynamics`` over a turn of GF at ``table.samples`` instants from picking: the keys every
    driven mechanism writes (synthesis.dynamics.facts) with all six moving links, so the energy balance can be
    re-checked from the file alone, and the double crank's own: AB's angle, speed and acceleration, the driven
    torque, the energies."""
    tau = turn(table.samples)
    out = dyn.over_turn(tau)
    sense, omega = (float(dyn.q[PARAMETERS.index(n)]) for n in ("sense", "omega"))
    signed_speed = dyn.mount * sense * omega
    links = link_facts(out, dyn.mass, LINKS, LINK_ROLES)
    facts = sampled_facts(tau, out, signed_speed, crank_speed_rpm, JOINTS, ROLES, links, dyn.gravity, False,
                          conventions(signed_speed < 0.0), table.assumption)
    facts["summary"]["driven_torque_Nm"] = peaks(out["driven_torque"], tau)
    return {"span": "a turn of the crank GF", **facts,
            "driven_torque_Nm": out["driven_torque"].tolist(),
            "crank_ab_deg": np.degrees(out["crank_ab"]).tolist(),
            "crank_ab_speed_radps": out["crank_ab_speed"].tolist(),
            "crank_ab_acceleration_radps2": out["crank_ab_acceleration"].tolist(),
            "kinetic_energy_J": out["kinetic_energy"].tolist(),
            "potential_energy_J": out["potential_energy"].tolist()}


def parameters(drive: Drive) -> tuple[float, ...]:
    """The parameter vector (:data:`PARAMETERS`) of a combined picker's fixed numbers."""
    cr = drive.cr
    return (cr.l7, cr.l8, cr.l9, cr.l10, *(float(v) for v in drive.dc.parameters()), drive.phi10, drive.phi_pick,
            drive.beta_pick, drive.theta2, float(drive.sense), drive.omega)


def picker_dynamics(table: PickerDynamicsSection, drive: Drive) -> PickerDynamics:
    """The combined picker's dynamics on floats, from its drive (synthesis.kinds.picker.combined.make_drive)."""
    return PickerDynamics.of(table, drive.cr.branch, drive.mount, drive.dc.branch, parameters(drive))
