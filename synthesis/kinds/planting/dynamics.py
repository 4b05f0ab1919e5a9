"""The planting arm's inverse dynamics (docs/ARCHITECTURE.md "Dynamics"): the seed-000 four-bar on the shared one.

The arm is :mod:`synthesis.dynamics.fourbar`'s four-bar with frame l1 at angle zeta, crank l2, coupler l3, rocker l4;
the coupler carries the claw arm AC (AB turned clockwise by phi, length l5), so a coupler given as a bar is two bars of
the same section, AB and AC, rigid together.  The crank turns at the [operation] crank speed.

With ``[dynamics] soil`` the soil resists the claw tip C while C is below the soil surface (the shared four-bar's
soil law at C): the surface is the ``[soil]`` one -- its ``level`` (a number or a design variable), or
``analysis_depth`` above the lowest claw point P5, which moves with the design -- so the caller passes where it is
(:class:`SoilContact`): the check the root-found P5's, the NLP its P5 decision variable's, with the forward speed of
``[operation]`` (a number, or the NLP's symbol when the speed is an operating range).  Counterweights on the crank and
on the rocker (``counterweight``, ``rocker_counterweight``) are design variables of the kind.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

from synthesis.constraints import Rule
from synthesis.dynamics.linkage import FourbarDynamics, dynamics_rules

#: the arm's joints and links by seed 000's names, in synthesis.dynamics.fourbar's order
JOINTS = ("O", "A", "B", "O'")
LINKS = ("crank OA", "coupler AB with claw arm AC", "rocker O'B")


@dataclass(frozen=True)
class ArmDynamics:
    """What the dynamics rules read: the inverse dynamics' inputs (None when the crank cannot turn: the rules are
    then not evaluated) and the ``[dynamics.limits]``."""

    linkage: FourbarDynamics | None
    limits: Any


@dataclass(frozen=True)
class SoilContact:
    """Where the claw meets the soil: the surface's Y (mm, machine frame) and the machine's forward speed (m/s),
    numbers or symbols."""

    surface: Any
    forward_speed: Any


def claw_in_coupler(l5, phi):
    """The claw tip C in the coupler's frame (origin A, x along A -> B), mm: AB turned clockwise by phi, l5 long."""
    return (l5 * ca.cos(phi), -l5 * ca.sin(phi))


def arm_linkage(table, p, branch: int, omega, counterweight: tuple | None = None,
                rocker_counterweight: tuple | None = None, contact: SoilContact | None = None) -> FourbarDynamics:
    """The inverse dynamics' inputs of the arm parameters p = (l1, l2, l3, l4, l5 mm, zeta, phi rad), floats or
    symbols, the crank speed omega (rad/s), the counterweights (mass kg, radius mm) on the crank and on the rocker
    when the table has them, and, when the table has a soil law, where the claw meets the soil."""
    l1, l2, l3, l4, l5, zeta, phi = (p[i] for i in range(7))
    claw = claw_in_coupler(l5, phi)
    bars = {"crank": [((0.0, 0.0), (l2, 0.0))], "coupler": [((0.0, 0.0), (l3, 0.0)), ((0.0, 0.0), claw)],
            "rocker": [((0.0, 0.0), (l4, 0.0))]}
    law = getattr(table, "soil", None)
    soil = None
    if law is not None:
        if contact is None:
            raise ValueError("the soil force on the claw needs the soil surface and the forward speed")
        soil = (law.f0, law.k, contact.surface, contact.forward_speed, claw[0], claw[1])
    return FourbarDynamics.of(table, branch, (l1, l2, l3, l4, zeta), bars, omega, tips={"coupler": claw},
                              counterweight=counterweight, rocker_counterweight=rocker_counterweight, soil=soil)


def arm_dynamics(table, p, branch: int, omega, counterweight: tuple | None = None,
                 rocker_counterweight: tuple | None = None, contact: SoilContact | None = None) -> ArmDynamics | None:
    """The rules' input of a ``[dynamics]`` table with limits; None without a table or a limit (then no rule)."""
    if table is None or not table.has_rules():
        return None
    return ArmDynamics(arm_linkage(table, p, branch, omega, counterweight, rocker_counterweight, contact),
                       table.limits)


def unevaluated_arm_dynamics(table) -> ArmDynamics | None:
    """The rules' input of a design whose crank cannot turn: the limits alone (their rules are not evaluated)."""
    if table is None or not table.has_rules():
        return None
    return ArmDynamics(None, table.limits)


def counterweight_of(values: dict) -> tuple | None:
    """(mass, radius) of the design variables ``counterweight_mass``, ``counterweight_radius`` (numbers or symbols),
    or None when the spec has no counterweight on the crank."""
    if "counterweight_mass" not in values:
        return None
    return values["counterweight_mass"], values["counterweight_radius"]


def rocker_counterweight_of(values: dict) -> tuple | None:
    """(mass, radius) of the design variables ``rocker_counterweight_mass``, ``rocker_counterweight_radius``
    (numbers or symbols), or None when the spec has no counterweight on the rocker."""
    if "rocker_counterweight_mass" not in values:
        return None
    return values["rocker_counterweight_mass"], values["rocker_counterweight_radius"]


def arm_dynamics_rules(dyn: ArmDynamics | None, samples: int, missing: str | None = None) -> list[Rule]:
    """The dynamics rules over ``samples`` crank angles of a turn; not evaluated when the crank cannot turn."""
    return [] if dyn is None else dynamics_rules(dyn.linkage, dyn.limits, samples, missing)
