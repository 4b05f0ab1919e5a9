"""The planting arm's inverse dynamics (docs/ARCHITECTURE.md "Dynamics"): the seed-000 four-bar on the shared one.

The arm is :mod:`synthesis.dynamics.fourbar`'s four-bar with frame l1 at angle zeta, crank l2, coupler l3, rocker l4;
the coupler carries the claw arm AC (AB turned clockwise by phi, length l5), so a coupler given as a bar is two bars of
the same section, AB and AC, rigid together.  The crank turns at the [operation] crank speed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

from constraints import Rule
from synthesis.dynamics.linkage import FourbarDynamics, dynamics_rules

#: the arm's joints and links by seed 000's names, in synthesis.dynamics.fourbar's order
JOINTS = ("O", "A", "B", "O'")
LINKS = ("crank OA", "coupler AB with claw arm AC", "rocker O'B")


@dataclass(frozen=True)
class ArmDynamics:
    """What the dynamics rules read: the inverse dynamics' inputs and the ``[dynamics.limits]``."""

    linkage: FourbarDynamics
    limits: Any


def arm_linkage(table, p, branch: int, omega, counterweight: tuple | None = None) -> FourbarDynamics:
    """The inverse dynamics' inputs of the arm parameters p = (l1, l2, l3, l4, l5 mm, zeta, phi rad), floats or
    symbols, the crank speed omega (rad/s) and the counterweight (mass kg, radius mm) when the table has one."""
    l1, l2, l3, l4, l5, zeta, phi = (p[i] for i in range(7))
    claw = (l5 * ca.cos(phi), -l5 * ca.sin(phi))          # C in the coupler's frame (x along A -> B)
    bars = {"crank": [((0.0, 0.0), (l2, 0.0))], "coupler": [((0.0, 0.0), (l3, 0.0)), ((0.0, 0.0), claw)],
            "rocker": [((0.0, 0.0), (l4, 0.0))]}
    return FourbarDynamics.of(table, branch, (l1, l2, l3, l4, zeta), bars, omega, tips={"coupler": claw},
                              counterweight=counterweight)


def arm_dynamics(table, p, branch: int, omega, counterweight: tuple | None = None) -> ArmDynamics | None:
    """The rules' input of a ``[dynamics]`` table with limits; None without a table or a limit (then no rule)."""
    if table is None or not table.has_rules():
        return None
    return ArmDynamics(arm_linkage(table, p, branch, omega, counterweight), table.limits)


def counterweight_of(values: dict) -> tuple | None:
    """(mass, radius) of the design variables ``counterweight_mass``, ``counterweight_radius`` (numbers or symbols),
    or None when the spec has no counterweight."""
    if "counterweight_mass" not in values:
        return None
    return values["counterweight_mass"], values["counterweight_radius"]


def arm_dynamics_rules(dyn: ArmDynamics | None, samples: int, missing: str | None = None) -> list[Rule]:
    """The dynamics rules over ``samples`` crank angles of a turn; not evaluated when the crank cannot turn."""
    return [] if dyn is None else dynamics_rules(dyn.linkage, dyn.limits, samples, missing)
