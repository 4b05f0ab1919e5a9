"""The rotary_planetary problem, as the kind declares it (the core compiles and solves it): the design (spec units) and the carrier angles where the rules are read.

Decision vector: the design variables in ``RotaryPlanetarySpec.variables()`` order (mm, deg; a fixed one has
lo = hi), then the loop's top and bottom, soil entry and exit, and each free key pose's carrier angle (rad).
Structural rows pin each of these angles (the loop's top and bottom where the tip's height is stationary, entry
and exit on the soil surface, a free pose where the tip is nearest its target) and make entry and exit the soil
crossings around the bottom: going down at entry and up at exit, below the surface in between (the in-soil
samples), the stroke shorter than half a turn.  Every rule is :func:`synthesis.kinds.rotary_planetary.check.rules_of` on these symbols, so the check
and the NLP cannot drift apart; the plant spacing, which no design variable moves, is among them for the core's
pre-solve refusal of a violated one (``Kind.fixed_by``).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.constraints.poses import nearest_row
from synthesis.core.declared import Declared, named
from synthesis.core.kind import Setting
from synthesis.core.problem import DEFAULT_BACKOFF, ObjectiveParts, Problem, per_rule_backoff
from synthesis.kinds.rotary_planetary.check import (
    Angles, find_angles, rules_of, soil_y, train_of,
)
from synthesis.kinds.rotary_planetary.kinematics import idler_turn, tip, tip_rate, turn_grid
from synthesis.kinds.rotary_planetary.spec import RotaryPlanetarySpec
from synthesis.spec.common import design_box

TWO_PI = 2.0 * math.pi
#: the rules read on samples of the turn or the stroke: their extremes fall between samples, so the NLP holds them
#: ``[solver] backoff`` x their scale inside (the others are rows at the NLP's own angles, exact)
SAMPLED_RULES = ("pair_ratio", "pitch_curve_concavity", "pitch_normal_angle", "planting_depth_max",
                 "in_soil_forward_speed", "soil_once")
#: the auxiliary carrier angles are kept within this range, rad (a start's are in [-pi, 3 pi))
ANGLE_RANGE = (-2.0 * TWO_PI, 3.0 * TWO_PI)


def smoothness(spec: RotaryPlanetarySpec, design: dict):
    """Mean square of F'' + mean square of G'' over a turn, deg^2/rad^4 (Parseval: half the sum of k^4 (a_k^2 +
    b_k^2) per law): the objective ``smooth_law``."""
    kp, ki = spec.harmonics
    total = 0.0
    for law, n in (("planet", kp), ("idler", ki)):
        for k in range(1, n + 1):
            total = total + 0.5 * k**4 * (design[f"{law}_cos_{k}"] ** 2 + design[f"{law}_sin_{k}"] ** 2)
    return total


def pose_miss(rules) -> list:
    """The key-pose rows' squared misses (mm^2, deg^2) from the rules built on symbols."""
    out = []
    for r in rules:
        if r.name.startswith("pose_"):
            out.append(r.nlp_rows[0][0] if r.nlp_rows else r.expr ** 2)
    return out


def problem(setting: Setting) -> Declared:
    """The problem of one spec: a start's design clipped into its bounds, its carrier angles found on its loop;
    the solver's carrier angles (deg) in each start's details."""
    spec = setting.spec
    variables = spec.variables()
    names = list(variables)
    bounds, init = design_box(variables, names)
    free_poses = [n for n, p in spec.key_poses.items() if p.carrier_angle is None]
    samples, soil_n = spec.solver.samples_per_turn, spec.solver.in_soil_samples
    n_half = samples if spec.rules.single_idler else 0
    n_design, n_aux = len(names), 4 + len(free_poses) + n_half
    z = ca.SX.sym("z", n_design + n_aux)
    design = {n: z[i] for i, n in enumerate(names)}
    top, bottom, entry, exit_ = (z[n_design + i] for i in range(4))
    poses = {n: z[n_design + 4 + j] for j, n in enumerate(free_poses)}
    poses.update({n: p.carrier_angle * math.pi / 180.0 for n, p in spec.key_poses.items()
                  if p.carrier_angle is not None})
    train = train_of(spec, design)
    half = z[n_design + 4 + len(free_poses):] if n_half else None
    angles = Angles(top, bottom, entry, exit_, poses, half_turn=half)
    rules = rules_of(spec, train, angles, turn_grid(samples), soil_n)
    structural = structural_rows(spec, train, angles, free_poses)
    if n_half:
        # each half-turn angle pinned where the idler had turned half a turn less than at its grid angle
        structural.insert(4 + len(free_poses), (idler_turn(train, half) - idler_turn(train, turn_grid(samples))
                                                + math.pi, 0.0, 0.0))
    if spec.objective.name == "key_pose_miss":
        misses = pose_miss(rules)
        f = ca.sum1(ca.vertcat(*misses)) if misses else ca.SX(0.0)
    else:
        f = smoothness(spec, design)
    lbx = np.concatenate([bounds[:, 0], np.full(n_aux, ANGLE_RANGE[0])])
    ubx = np.concatenate([bounds[:, 1], np.full(n_aux, ANGLE_RANGE[1])])
    lengths = ("centre_distance_1", "centre_distance_2", "arm_length")
    declared = Problem("rotary_planetary", z, lbx, ubx, structural, rules, ObjectiveParts(f=f / 100.0),
                       x_units=["mm" if n in lengths else "deg" for n in names] + ["rad"] * n_aux,
                       structural_units=["mm/rad", "mm/rad", "mm", "mm"] + ["mm^2/rad"] * len(free_poses)
                       + ["rad"] * bool(n_half) + ["mm/rad", "mm/rad", "rad", "rad", "rad", "mm"],
                       objective_unit="mm^2" if spec.objective.name == "key_pose_miss" else "deg^2",
                       max_iter=spec.solver.max_iter,
                       backoff=per_rule_backoff(lambda rule: spec.solver.backoff if rule.name in SAMPLED_RULES
                                                else DEFAULT_BACKOFF))

    def start(x_design: np.ndarray, elastic: bool) -> tuple[np.ndarray, None]:
        x_design = np.clip(np.asarray(x_design, dtype=float), bounds[:, 0], bounds[:, 1])
        return np.concatenate([x_design, aux_guess(spec, names, free_poses, x_design, samples)]), None

    def reported(out, design: dict, elastic: bool) -> float:
        return out.objective * 100.0

    def carrier_angles(out, compiled) -> dict:
        aux = [math.degrees(float(v)) for v in out.x[n_design:n_design + n_aux]]
        return {"carrier_deg": {"top": aux[0], "bottom": aux[1], "entry": aux[2], "exit": aux[3],
                                **{p: aux[4 + j] for j, p in enumerate(free_poses)}}}

    return Declared(declared, names, bounds, init, design=named(names), start=start, objective=reported,
                    details=carrier_angles)


def structural_rows(spec: RotaryPlanetarySpec, train, angles: Angles, free_poses: list[str]) -> list:
    """One equality row pinning each auxiliary angle (the tolerance analysis differentiates through them): the top
    and bottom where the tip's height is stationary, entry and exit on the surface, a pose where the tip is nearest
    its target (the check's reading, find_angles); then entry going down and exit up around the bottom, the
    in-soil samples below the surface, the stroke shorter than half a turn."""
    level = soil_y(spec)
    entry, exit_ = angles.entry, angles.exit
    s = ca.DM(np.linspace(0.0, 1.0, spec.solver.in_soil_samples + 2)[1:-1])
    _, y_stroke = tip(train, entry + (exit_ - entry) * s)
    nearest = []
    for name in free_poses:
        (px, py), (dx, dy) = tip(train, angles.poses[name]), tip_rate(train, angles.poses[name])
        pose = spec.key_poses[name]
        nearest.append((nearest_row(px - pose.x, py - pose.y, dx, dy), 0.0, 0.0))
    return [(tip_rate(train, angles.top)[1], 0.0, 0.0), (tip_rate(train, angles.bottom)[1], 0.0, 0.0),
            (tip(train, entry)[1] - level, 0.0, 0.0), (tip(train, exit_)[1] - level, 0.0, 0.0), *nearest,
            (tip_rate(train, entry)[1], None, 0.0), (tip_rate(train, exit_)[1], 0.0, None),
            (angles.bottom - entry, 0.0, None), (exit_ - angles.bottom, 0.0, None), (exit_ - entry, None, math.pi),
            (y_stroke - level, None, 0.0)]


def aux_guess(spec: RotaryPlanetarySpec, names: list[str], free_poses: list[str], x_design: np.ndarray,
              samples: int) -> np.ndarray:
    """A start's carrier angles: its loop's extremes, soil crossings and the poses' best angles on a 0.5 deg grid,
    and with a single idler the half-turn angle of each of the ``samples`` grid angles."""
    design = dict(zip(names, (float(v) for v in x_design)))
    with np.errstate(divide="ignore", invalid="ignore"):
        angles = find_angles(spec, train_of(spec, design), 720, samples)
    entry = angles.entry if angles.entry is not None else angles.bottom - 0.3
    exit_ = angles.exit if angles.exit is not None else angles.bottom + 0.3
    half = [] if angles.half_turn is None else list(angles.half_turn)
    return np.array([angles.top, angles.bottom, entry, exit_, *(angles.poses[n] for n in free_poses), *half])
