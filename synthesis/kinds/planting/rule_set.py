"""The rule set of kind planting_fourbar, wired once: a :class:`Trace` of the claw tip -> every rule.

A trace holds what the rules read: the crank angle, position and velocity of P1-P6, the claw's
Y acceleration sampled over the hold, throw and release phases, the link lengths and the
transmission angle sampled over a turn, and the claw at each key pose.  ``check`` and the solver's fine-grid
re-check build it on floats (root-found precision points, fine grids: :func:`synthesis.kinds.planting.scene.float_trace`),
the NLP on CasADi symbols (the crank angles of P1-P6 and of the free key poses are decision variables:
:mod:`synthesis.kinds.planting.nlp`); :func:`planting_rules` turns either into the same named rules.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca

from synthesis.constraints import Rule
from synthesis.constraints.poses import attitude_miss_deg, pose_attitude_rule, pose_tip_rule
from synthesis.kinds.planting.rules.acceleration import acceleration_sign_rule
from synthesis.kinds.planting.rules.angles import entry_angle_rule
from synthesis.kinds.planting.rules.counterweight import counterweight_clearance_rule
from synthesis.kinds.planting.rules.depth import depth_rule
from synthesis.constraints.grashof import grashof_rule
from synthesis.kinds.planting.rules.precision_points import p4p6_rule, seedbed_rules
from synthesis.kinds.planting.rules.speed import p2_speed_rule
from synthesis.constraints.transmission import transmission_rules
from synthesis.kinds.planting.dynamics import arm_dynamics_rules

TWO_PI = 2.0 * math.pi
POINTS = ("P1", "P2", "P3", "P4", "P5", "P6")
#: acceleration phases: name -> (from, to); the cycle runs from P5, so throw ends at P5 one turn on
PHASES = {"hold": ("P3", "P4"), "throw": ("P4", "P5"), "release": ("P5", "P6")}
DEG = 180.0 / math.pi


@dataclass
class PoseReading:
    """The claw at one key pose: the pose (the spec's ``[key_poses]`` entry), its crank angle (rad), the tip's
    position (mm) and the claw's attitude (rad, :func:`synthesis.kinds.planting.kinematics.claw_attitude`) there,
    floats or CasADi symbols; ``missing`` says why the pose could not be read (its point not found, the crank not
    turning), and then the other fields are None."""

    name: str
    pose: Any
    theta: Any = None
    pos: tuple | None = None
    attitude: Any = None
    missing: str | None = None

    @property
    def where(self) -> str:
        at = getattr(self.pose, "at", None)
        return f"key pose {self.name}" + (f", at {at}" if at is not None else "")


def pose_rules(readings: list[PoseReading]) -> list[Rule]:
    """Per key pose, in the spec's order: the tip within its tolerance of (x, y) if the pose gives them
    (``pose_<name>``), the claw's attitude within its tolerance if the pose gives one (``pose_<name>_attitude``)."""
    rules = []
    for r in readings:
        pose, missing = r.pose, r.missing
        if pose.tip is not None:
            dx, dy = (None, None) if r.pos is None else (r.pos[0] - pose.tip[0], r.pos[1] - pose.tip[1])
            rules.append(pose_tip_rule(r.name, dx, dy, pose.tolerance, r.where, missing))
        if pose.attitude is not None:
            miss = None if r.attitude is None else attitude_miss_deg(r.attitude * DEG, pose.attitude)
            rules.append(pose_attitude_rule(r.name, miss, pose.attitude_tolerance, r.where, missing))
    return rules


@dataclass
class Trace:
    """The claw tip where the rules read it (machine frame unless said), floats or CasADi symbols.

    ``theta``, ``pos`` and ``vel`` have an entry for every precision point found (crank angle in rad,
    increasing through one cycle from P5; position mm; velocity mm/s); ``problems`` says why a point
    is absent.  ``accel_y``: sampled a_y (mm/s^2) of each phase whose ends exist.  ``mu_deg``:
    transmission angle over a turn (None when the crank cannot complete one, ``turn_missing`` says why).
    ``acc_scale``: the typical |a_y| that normalises the acceleration margins, a number fixed per
    spec (omega^2 x the given crank length), so solver and re-check normalise alike.
    """

    theta: dict[str, Any]
    pos: dict[str, tuple]
    vel: dict[str, tuple]
    accel_y: dict[str, Any]
    links: tuple                      # l1, l2, l3, l4, mm
    mu_deg: Any
    omega: float | ca.SX              # crank speed, rad/s
    forward: float | ca.SX            # machine speed, mm/s
    acc_scale: float
    problems: dict[str, str] = field(default_factory=dict)
    turn_missing: str | None = None
    #: the inverse dynamics and its limits when the spec's [dynamics] table sets one
    #: (synthesis.kinds.planting.dynamics.ArmDynamics), else None: no dynamics rule
    dynamics: Any = None
    #: the claw at each of the spec's key poses, in its order (none without a [key_poses] table)
    poses: list[PoseReading] = field(default_factory=list)
    #: each counterweight's heights above the soil surface
    #: (synthesis.kinds.planting.rules.counterweight.CounterweightReading; none without a counterweight)
    counterweights: list = field(default_factory=list)

    def missing(self, *names: str) -> str | None:
        """Why any of ``names`` is absent (the first reason), or None when all exist."""
        for n in names:
            if n not in self.pos:
                return self.problems.get(n, f"{n} not found")
        return None

    def ground(self, name: str, turns: int = 0) -> tuple:
        """Ground-frame position of a point (X_g = X + v t, t = theta / omega), ``turns`` cycles later."""
        theta = self.theta[name] + TWO_PI * turns if turns else self.theta[name]
        t = theta / self.omega
        return (self.pos[name][0] + self.forward * t, self.pos[name][1])


def planting_rules(tr: Trace, limits) -> list[Rule]:
    """Every rule of a planting_fourbar spec (``limits``: its ``[rules]``), in result.json order."""
    pos, vel = tr.pos, tr.vel
    rules = seedbed_rules(pos.get("P1"), pos.get("P2"), pos.get("P3"), limits.p1p3, limits.p2p3,
                          limits.collinearity, tr.missing("P1", "P2", "P3"))
    miss4 = tr.missing("P4")
    rules.append(entry_angle_rule(None if miss4 else vel["P4"][0] + tr.forward, None if miss4 else vel["P4"][1],
                                  limits.entry_angle_min, miss4))
    miss45 = tr.missing("P4", "P5")
    rules.append(depth_rule(None if miss45 else pos["P4"][1], None if miss45 else pos["P5"][1], limits.depth,
                            miss45))
    # the cycle is scanned from P5, so the planting stroke's P4 lies one turn before theta['P4']
    miss46 = tr.missing("P4", "P6")
    rules.append(p4p6_rule(None if miss46 else tr.ground("P4", turns=-1), None if miss46 else tr.ground("P6"),
                           limits.p4p6_min, miss46))
    miss2 = tr.missing("P2")
    rules.append(p2_speed_rule(None if miss2 else vel["P2"][0], None if miss2 else vel["P2"][1],
                               limits.p2_speed_min, miss2))
    signs = limits.acceleration
    for phase, (a, b) in PHASES.items():
        rules.append(acceleration_sign_rule(phase, tr.accel_y.get(phase), getattr(signs, phase), tr.acc_scale,
                                            tr.missing(a, b)))
    rules.append(grashof_rule(*tr.links))
    rules += transmission_rules(tr.mu_deg, limits.transmission_angle, tr.turn_missing)
    if tr.dynamics is not None:      # on the transmission angle's grid over the turn
        samples = 0 if tr.mu_deg is None else (tr.mu_deg.numel() if hasattr(tr.mu_deg, "numel") else len(tr.mu_deg))
        rules += arm_dynamics_rules(tr.dynamics, samples, tr.turn_missing)
    rules += [counterweight_clearance_rule(reading) for reading in tr.counterweights]
    return rules + pose_rules(tr.poses)


def phase_bounds(theta: dict[str, Any], phase: str) -> tuple[Any, Any]:
    """Crank angles at the start and end of an acceleration phase (the end one turn on for throw)."""
    a, b = PHASES[phase]
    return theta[a], theta[b] + (TWO_PI if b == "P5" else 0.0)
