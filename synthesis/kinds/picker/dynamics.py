"""The double crank's inverse dynamics (docs/ARCHITECTURE.md "Dynamics"): seed 001's ABCD on the shared four-bar.

Mapping on :mod:`synthesis.dynamics.fourbar`: frame l1 = AD (the kind's l4) at zeta = -phi3, crank l2 = AB (l1),
coupler l3 = BC (l2), rocker l4 = the follower CD (l3), crank pivot O = A; the coupler carries the clamp arm CM (BC
turned counter-clockwise by phi4, length l5), so a coupler given as a bar is BC and CM of the same section, and a
point mass ``at = "tip"`` sits at the clamp point M.  The shared four-bar puts A at the origin: the centres of mass in
``facts.dynamics`` are moved to the machine frame (a translation: forces, torques and energy changes are the same).

Over the **working swing** (phi10 to phi10 + psi, ends included), not a turn: in the picker AB swings with the rocker
AE and never turns further; the kind's rules and path are evaluated there, and outside it the double crank may come
near a toggle it never reaches (the library redesign sits on the Grashof change point, where a turn has none).  AB
turns at the constant ``[dynamics] crank_speed`` over the swing, counter-clockwise (picking -> dropping): the shared
model's assumption, an idealisation here, since the crank-rocker drives AB at a speed that is zero at both ends of
the swing (the combined picker's motion, which this does not model).

The rules and objectives are the same functions on floats (check, re-check) and CasADi symbols (the NLP).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.constraints import Rule
from synthesis.constraints.dynamics import peak_input_torque_rule, peak_shaking_force_rule, peak_shaking_moment_rule
from synthesis.dynamics.fourbar import JOINTS as ROLES
from synthesis.dynamics.fourbar import LINKS as LINK_ROLES
from synthesis.dynamics.facts import link_facts, sampled_facts
from synthesis.dynamics.linkage import FourbarDynamics
from synthesis.spec.dynamics import DynamicsSection, DynamicsLimits

#: the double crank's joints and links by seed 001's names, in synthesis.dynamics.fourbar's order (crank pivot,
#: crank pin, coupler-rocker joint, rocker pivot; crank, coupler, rocker)
JOINTS = ("A", "B", "C", "D")
LINKS = ("crank AB", "coupler BC with clamp arm CM", "follower CD")
#: where the rules are evaluated
WHERE = "over the working swing"
#: the min-peak objectives and the unit of each (the turn-based kinds': synthesis.dynamics.linkage.PEAK_OBJECTIVES)
PEAK_UNITS = {"min_peak_torque": "N m", "min_peak_shaking_force": "N", "min_peak_shaking_moment": "N m"}


def crank_speed_radps(table: DynamicsSection) -> float:
    """AB's constant speed over the working swing, rad/s (the table's crank_speed, r/min)."""
    # called only with a [dynamics] table, whose crank speed PickerDoubleCrankSpec's validator requires
    assert table.crank_speed is not None
    return table.crank_speed * 2 * math.pi / 60


def double_crank_dynamics(table: DynamicsSection, p, branch: int) -> FourbarDynamics:
    """The inverse dynamics' inputs of the parameters p = (x_a, y_a, l1, l2, l3, l4, l5 mm, phi3, phi4 rad), floats or
    symbols (synthesis.kinds.picker.kinematics.linkage.PARAMETERS), at the table's crank speed."""
    _, _, l1, l2, l3, l4, l5, phi3, phi4 = (p[i] for i in range(9))
    clamp = (l2 + l5 * ca.cos(phi4), l5 * ca.sin(phi4))        # M in the coupler's frame (B, x along B -> C)
    bars = {"crank": [((0.0, 0.0), (l1, 0.0))], "coupler": [((0.0, 0.0), (l2, 0.0)), ((l2, 0.0), clamp)],
            "rocker": [((0.0, 0.0), (l3, 0.0))]}
    counterweight = None if table.counterweight is None else table.counterweight.values()
    return FourbarDynamics.of(table, branch, (l4, l1, l2, l3, -phi3), bars, crank_speed_radps(table),
                              tips={"coupler": clamp}, counterweight=counterweight)


def _column(values):
    """Sampled values as a column: a CasADi vector for symbols, a flat numpy array for numbers."""
    return np.ravel(values) if isinstance(values, np.ndarray) else ca.vec(values)


def sampled(dyn: FourbarDynamics, crank: np.ndarray) -> tuple:
    """(input torque N m, shaking force x, y N, shaking moment N m about A) at the crank angles ``crank`` (rad, from
    AD), as columns: what the rules and the min-peak objectives read (floats or symbols)."""
    out = dyn.over_turn(crank)
    force = out["shaking_force"]
    return _column(out["torque"]), _column(force[0, :]), _column(force[1, :]), _column(out["shaking_moment"])


def dynamics_rules(dyn: FourbarDynamics, limits: DynamicsLimits, crank: np.ndarray) -> list[Rule]:
    """The ``[dynamics.limits]`` rules at the crank angles ``crank`` of the working swing (none without a limit)."""
    if not limits.any_given():
        return []
    torque, fx, fy, moment = sampled(dyn, crank)
    rules = []
    if limits.peak_input_torque is not None:
        rules.append(peak_input_torque_rule(torque, limits.peak_input_torque, WHERE))
    if limits.peak_shaking_force is not None:
        rules.append(peak_shaking_force_rule(fx, fy, limits.peak_shaking_force, WHERE))
    if limits.peak_shaking_moment is not None:
        rules.append(peak_shaking_moment_rule(moment, limits.peak_shaking_moment, f"{WHERE}, about the crank pivot A"))
    return rules


def peak_sampled(dyn: FourbarDynamics, which: str, crank: np.ndarray):
    """What a min-peak objective bounds at each crank angle, floats or symbols: the input torque or the shaking moment
    (N m, bounded in absolute value), or the squared shaking force (N^2, smooth where the force vanishes)."""
    torque, fx, fy, moment = sampled(dyn, crank)
    if which == "min_peak_torque":
        return torque
    if which == "min_peak_shaking_moment":
        return moment
    return fx * fx + fy * fy


def peak_epigraph(dyn: FourbarDynamics, which: str, crank: np.ndarray) -> tuple:
    """The epigraph of a min-peak objective (smooth): a variable t with rows t - s >= 0 and t + s >= 0 at every
    sample s of the input torque (``min_peak_torque``) or the shaking moment (``min_peak_shaking_moment``), t in N m,
    or t - (fx^2 + fy^2) >= 0 (``min_peak_shaking_force``, t in N^2), t to be minimised.  Returns (t, rows, unit)."""
    s = peak_sampled(dyn, which, crank)
    if which == "min_peak_shaking_force":
        t = ca.SX.sym("peak_shaking_force_sq")
        return t, [(t - s, 0.0, None)], "N^2"
    t = ca.SX.sym("peak_torque" if which == "min_peak_torque" else "peak_shaking_moment")
    return t, [(t - s, 0.0, None), (t + s, 0.0, None)], "N m"


def peak_of(dyn: FourbarDynamics, which: str, crank: np.ndarray) -> float:
    """The peak a min-peak objective minimises, on floats: |torque| N m, |shaking force| N or |shaking moment| N m
    at ``crank``."""
    torque, fx, fy, moment = sampled(dyn, crank)
    if which == "min_peak_shaking_force":
        return float(np.hypot(fx, fy).max())
    return float(np.abs(torque if which == "min_peak_torque" else moment).max())


CONVENTIONS = ("crank AB at constant speed over the working swing, counter-clockwise (picking -> dropping); reaction "
               "at a joint: force of the link nearer the frame on the next (N, machine frame); input torque: the "
               "motor's on AB, counter-clockwise positive; shaking force and moment (about the crank pivot A): what "
               "the moving links put on the frame, gravity included")


def dynamics_facts(dyn: FourbarDynamics, crank: np.ndarray, pivot_mm: tuple[float, float], table: DynamicsSection
                   ) -> dict:
    """result.json's ``facts.dynamics`` over the working swing, with the keys of the turn-based four-bar kinds
    (synthesis.dynamics.linkage.dynamics_facts): every sampled quantity, and each link's mass, inertia, centre of mass
    (machine frame: moved by the crank pivot A at ``pivot_mm``) and angle, so the energy balance can be re-checked
    from the file alone; ``span``: the working swing, not a turn (the power's integral over it is not zero)."""
    assert table.crank_speed is not None         # PickerDoubleCrankSpec's validator requires it with the table
    out = dyn.over_turn(crank)
    links = link_facts(out, dyn.mass, LINKS, LINK_ROLES, np.asarray(pivot_mm, float))
    loads: bool | dict = False
    if table.external_loads:
        loads = {"loads": [load.model_dump() for load in table.external_loads],
                 "external_power_W": out["external_power"].tolist()}
    return {"span": "working swing",
            **sampled_facts(crank, out, crank_speed_radps(table), table.crank_speed, JOINTS, ROLES, links,
                            dyn.gravity, loads, CONVENTIONS, table.assumption)}
