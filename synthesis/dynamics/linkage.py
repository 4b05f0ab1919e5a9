"""A four-bar kind's dynamics: its inputs gathered once, its rules over a turn and result.json's ``facts.dynamics``.

A kind maps its own geometry on :mod:`synthesis.dynamics.fourbar`'s (l1 frame, l2 crank, l3 coupler, l4 rocker,
zeta) and names its joints and links; the rules are the same functions on floats (``check``, the re-check) and on
CasADi symbols (the NLP), so the two cannot drift apart (docs/ARCHITECTURE.md "Dynamics").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from synthesis.constraints import Rule
from synthesis.constraints.dynamics import peak_input_torque_rule, peak_shaking_force_rule, peak_shaking_moment_rule
from synthesis.dynamics import mass as mass_properties
from synthesis.dynamics.facts import link_facts, sampled_facts, turn
from synthesis.dynamics.fluctuation import speed_fluctuation_facts
from synthesis.dynamics.fourbar import JOINTS, LINKS, over_turn
from synthesis.errors import SpecError

TWO_PI = 2.0 * math.pi
CONVENTIONS = ("reaction at a joint: force of the link nearer the frame on the next (N, machine frame); input torque: "
               "the motor's on the crank, counter-clockwise positive; shaking force and moment (about the crank "
               "pivot): what the moving links put on the frame, gravity included")


@dataclass(frozen=True)
class FourbarDynamics:
    """Everything the inverse dynamics reads: geometry (mm, rad), mass and load vectors (SI), crank speed (rad/s),
    gravity (m/s^2); and, for a crank whose speed is not constant or a link another linkage loads, the crank's
    angular acceleration and per-link couples (one value or one per sample, :func:`synthesis.dynamics.fourbar.
    over_turn`), and a soil law on a coupler point (:data:`synthesis.dynamics.fourbar.SOIL`).  Geometry, mass and
    crank speed may be CasADi symbols."""

    branch: int
    geometry: tuple
    mass: tuple
    loads: tuple
    omega: object
    gravity: tuple
    alpha: object = None
    moments: object = None
    soil: tuple | None = None

    @classmethod
    def of(cls, table, branch: int, geometry: tuple, bars: dict[str, list[tuple]], omega,
           tips: dict | None = None, counterweight: tuple | None = None, rocker_counterweight: tuple | None = None,
           soil: tuple | None = None) -> "FourbarDynamics":
        """From a spec's ``[dynamics]`` table (:class:`synthesis.spec.dynamics.DynamicsSection`); ``bars``: each link's
        bars (start, end) in mm in its link frame, read for a link given as a bar; ``tips``: link -> the kind's traced
        point on it (mm, link frame), where a point mass ``at = "tip"`` sits; ``counterweight``: (kg, mm) on the
        crank opposite its pin, ``rocker_counterweight`` on the rocker opposite the coupler-rocker joint, numbers or
        the NLP's symbols; ``soil``: the :data:`synthesis.dynamics.fourbar.SOIL` vector of a kind whose coupler
        works the soil.

        A table with a rocker counterweight the kind did not pass is refused (SpecError): a kind that does not read
        the field would otherwise report the dynamics of another machine without a word."""
        if rocker_counterweight is None and getattr(table, "rocker_counterweight", None) is not None:
            raise SpecError("dynamics.rocker_counterweight: this kind does not read a counterweight on the rocker; "
                            "leave the field out")
        return cls(branch, tuple(geometry),
                   tuple(mass_properties.mass_vector(table, bars, LINKS, tips, counterweight, rocker_counterweight)),
                   tuple(mass_properties.load_vector(table, LINKS)), omega, tuple(table.gravity),
                   soil=None if soil is None else tuple(soil))

    def over_turn(self, crank) -> dict:
        return over_turn(self.branch, crank, self.geometry, self.mass, self.loads, self.omega, self.gravity,
                         self.alpha, self.moments, self.soil)


def _column(values):
    """Sampled values as a column: a CasADi vector for symbols, a flat numpy array for numbers."""
    return np.ravel(values) if isinstance(values, np.ndarray) else ca.vec(values)


def dynamics_rules(dyn: FourbarDynamics | None, limits, samples: int, missing: str | None = None) -> list[Rule]:
    """The ``[dynamics.limits]`` rules over ``samples`` crank angles of a turn (none when no limit is given); not
    evaluated, for the reason ``missing``, when the crank cannot turn."""
    rules = []
    if missing is not None:
        if limits.peak_input_torque is not None:
            rules.append(peak_input_torque_rule(None, limits.peak_input_torque, missing=missing))
        if limits.peak_shaking_force is not None:
            rules.append(peak_shaking_force_rule(None, None, limits.peak_shaking_force, missing=missing))
        if limits.peak_shaking_moment is not None:
            rules.append(peak_shaking_moment_rule(None, limits.peak_shaking_moment, missing=missing))
        return rules
    if not limits.any_given():
        return []
    out = dyn.over_turn(turn(samples))
    if limits.peak_input_torque is not None:
        rules.append(peak_input_torque_rule(_column(out["torque"]), limits.peak_input_torque))
    if limits.peak_shaking_force is not None:
        force = out["shaking_force"]
        rules.append(peak_shaking_force_rule(_column(force[0, :]), _column(force[1, :]), limits.peak_shaking_force))
    if limits.peak_shaking_moment is not None:
        rules.append(peak_shaking_moment_rule(_column(out["shaking_moment"]), limits.peak_shaking_moment))
    return rules


#: the [dynamics.limits] rules, sampled at a kind's solver samples of a turn in the NLP
DYNAMICS_RULES = ("peak_input_torque", "peak_shaking_force", "peak_shaking_moment")
#: the NLP holds each [dynamics.limits] peak this share of its limit inside it at 72 samples of a turn, so that the
#: peak between its samples holds too on the re-check's finer grid; at N samples the share is this x (72 / N)^2, as
#: the miss between samples of a smooth periodic peak falls with the square of their spacing (a kind that takes
#: fewer samples may cap it: :func:`peak_backoff`'s ``most``; crank_rocker's 2 %).
#: picking_arc_torque_limited's starts held only at the kind's relative 1e-9 came to rest up to 1.2 % over the limit
#: between two of 72 samples (54 of its 64 starts: 0.4553 N m against 0.45 at worst); crank_rocker_torque_limited's
#: answer, held at 1e-7 of its scale, 1.4e-5 over it between two of 72
DYNAMICS_BACKOFF_AT_72 = 0.02


def dynamics_backoff(samples: int) -> float:
    """The share of its limit inside which the NLP holds a [dynamics.limits] peak at ``samples`` crank angles."""
    return DYNAMICS_BACKOFF_AT_72 * (72.0 / samples) ** 2


def peak_backoff(samples: int, otherwise, most: float | None = None):
    """A problem's back-off (synthesis.core.problem.Backoff): each [dynamics.limits] peak's row :func:`dynamics_backoff`
    of its limit inside it, at most ``most`` of it (the shaking force's row is its square: 1 - (1 - b)^2 of the row's
    limit), every other rule's ``otherwise``'s."""
    share = dynamics_backoff(samples) if most is None else min(dynamics_backoff(samples), most)
    squared = 1.0 - (1.0 - share) ** 2

    def backoff(rule: Rule, limit: float) -> float:
        if rule.name not in DYNAMICS_RULES:
            return otherwise(rule, limit)
        return (squared if rule.name == "peak_shaking_force" else share) * abs(limit)
    return backoff


#: the min-peak objectives a four-bar kind with a ``[dynamics]`` table offers: name -> (unit, what it minimises)
PEAK_OBJECTIVES = {
    "min_peak_torque": ("N m", "smallest peak |input torque| over a turn, N m ([dynamics] needed)"),
    "min_peak_shaking_force": ("N", "smallest peak shaking force on the frame over a turn, N ([dynamics] needed)"),
    "min_peak_shaking_moment": ("N m", "smallest peak |shaking moment| on the frame over a turn, about the crank "
                                       "pivot, N m ([dynamics] needed)"),
}


def sampled(dyn: FourbarDynamics, samples: int) -> tuple:
    """(input torque N m, shaking force x, y N, shaking moment N m) at ``samples`` crank angles of a turn, as
    columns: the samples a min-peak objective's epigraph rows read (floats or symbols)."""
    out = dyn.over_turn(turn(samples))
    force = out["shaking_force"]
    return _column(out["torque"]), _column(force[0, :]), _column(force[1, :]), _column(out["shaking_moment"])


def peak_epigraph(dyn: FourbarDynamics, which: str, samples: int):
    """The epigraph of a min-peak objective (smooth, as the core's other max-type objectives): a variable t with rows
    t - s >= 0 and t + s >= 0 at every sample s of the input torque (``min_peak_torque``, t in N m) or of the
    shaking moment (``min_peak_shaking_moment``, t in N m), or t - (fx^2 + fy^2) >= 0 (``min_peak_shaking_force``,
    t in N^2), t to be minimised.  Returns (t, rows, unit)."""
    torque, fx, fy, moment = sampled(dyn, samples)
    if which == "min_peak_torque":
        t = ca.SX.sym("peak_torque")
        return t, [(t - torque, 0.0, None), (t + torque, 0.0, None)], "N m"
    if which == "min_peak_shaking_moment":
        t = ca.SX.sym("peak_shaking_moment")
        return t, [(t - moment, 0.0, None), (t + moment, 0.0, None)], "N m"
    t = ca.SX.sym("peak_shaking_force_sq")
    return t, [(t - (fx * fx + fy * fy), 0.0, None)], "N^2"


def peak_of(dyn: FourbarDynamics, which: str, samples: int) -> float:
    """The peak a min-peak objective minimises, on floats: |torque| N m, |shaking force| N or |shaking moment| N m
    over ``samples``."""
    torque, fx, fy, moment = sampled(dyn, samples)
    if which == "min_peak_torque":
        return float(np.abs(torque).max())
    if which == "min_peak_shaking_moment":
        return float(np.abs(moment).max())
    return float(np.hypot(fx, fy).max())


def dynamics_facts(dyn: FourbarDynamics, samples: int, joint_names: tuple[str, ...], link_names: tuple[str, ...],
                   crank_speed_rpm: float, table) -> dict:
    """result.json's ``facts.dynamics``: every sampled quantity over a turn, and each link's mass, inertia, centre of
    mass and angle, so the energy balance can be re-checked from the file alone (docs/ARCHITECTURE.md "result.json");
    with a ``drive`` in the table, ``speed_fluctuation``: the crank's speed over the turn when the motor's torque is
    constant, and the same samples' torque and shaking force at that speed."""
    crank = turn(samples)
    out = dyn.over_turn(crank)
    loads: bool | dict = False
    if table.external_loads:
        loads = {"loads": [load.model_dump() for load in table.external_loads],
                 "external_power_W": out["external_power"].tolist()}
    facts = sampled_facts(crank, out, float(dyn.omega), crank_speed_rpm, joint_names, JOINTS,
                          link_facts(out, dyn.mass, link_names, LINKS), dyn.gravity, loads, CONVENTIONS,
                          table.assumption)
    if getattr(table, "drive", None) is not None:
        # the same samples at the speed a constant motor torque and the flywheel give (synthesis.dynamics.fluctuation)
        facts["speed_fluctuation"] = speed_fluctuation_facts(dyn, crank, table.drive, joint_names)
    return facts
