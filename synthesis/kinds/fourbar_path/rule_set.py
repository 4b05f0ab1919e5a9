"""The rules of a fourbar_path spec, wired once: :func:`path_rules` maps a trace (a design, the crank
angle of each target, the crank direction; floats or CasADi symbols) to every rule of the spec.

The NLP builds them on symbols (their rows are its constraints), ``check`` and the re-check of every
solver start build them on floats (their records are the rule table), so the three cannot drift apart.
What each rule reads:

    grashof                   the class's three linear slacks in r1..r4 (crank-rocker / double-crank)
    assembly                  |r3 - r4| <= |O'A| <= r3 + r4 at every target (a full turn: the Grashof class
                              then closes the loop everywhere), or along the crank's motion from target
                              to target (grashof = "any": sampled in the check, exact in the NLP)
    transmission_angle_min/max  cos mu at theta2 = 0 and 180 deg, its exact extremes over a full turn;
                              or along the motion (grashof = "any": as assembly)
    sequence                  the targets met in order within one turn (free timing, [rules] order)
    peak_input_torque, peak_shaking_force, peak_shaking_moment
                              [dynamics.limits]: the inverse dynamics over a turn at crank_speed (dynamics.py),
                              at [solver] dynamics_samples crank angles (check and the re-check: 10x as many)

The only sampled rules are those of grashof = "any": the check samples ``[solver] samples`` angles per gap
between targets, the re-check 10x more.  The NLP holds them exactly instead (``samples = EXTREMES``): both rules
read the crank angle only through cos(theta2) (d^2 = r1^2 + r2^2 - 2 r1 r2 cos theta2, cos mu falls as d^2 grows),
so over a gap they are extreme where cos(theta2) is, at the two angles of :func:`motion_extremes`.
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np

from synthesis.constraints import Rule, not_evaluated
from synthesis.core.problem import Backoff, relative_backoff
from synthesis.dynamics.linkage import peak_backoff
from synthesis.kinds.fourbar_path.dynamics import path_dynamics_rules
from synthesis.kinds.fourbar_path.rules.assembly import assembly_extremes_rule, assembly_rule
from synthesis.kinds.fourbar_path.rules.grashof_class import grashof_class_rule
from synthesis.kinds.fourbar_path.rules.sequence import sequence_rule, sequence_slacks
from synthesis.kinds.fourbar_path.rules.transmission_turn import (transmission_extremes_rules, transmission_sampled_rules,
                                           transmission_turn_rules)
from synthesis.kinds.fourbar_path.kinematics import cos_transmission
from synthesis.kinematics.fourbar import diagonal_sq
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec, same_target_mm

DEG = 180.0 / math.pi
TURN_SAMPLES = 360        # floats only: where the loop is sought when the targets have no crank angle


def segment_angles(thetas: list, per_segment: int) -> list:
    """The crank's motion from target to target, sampled: per_segment angles in each gap, ends included."""
    out = [thetas[0]]
    for a, b in zip(thetas, thetas[1:]):
        out += [a + (b - a) * k / per_segment for k in range(1, per_segment + 1)]
    return out


#: ``samples`` of :func:`path_rules` for the exact form of the sampled rules (the NLP's): each gap at its extremes
EXTREMES = 0


def motion_extremes(thetas: list) -> list:
    """Per gap between consecutive targets, the two crank angles of the motion from one to the next where
    cos(theta2) is largest and smallest: the point of the gap [lo, hi] nearest to 2 pi k (resp. pi + 2 pi k), k
    the multiple nearest to the gap's middle.  When the gap contains such a point (gaps shorter than a turn contain
    at most one, then the one nearest the middle) that point is the extreme (cos = +1 / -1); otherwise the end
    nearer to it is, because on a stretch between two such points cos is monotone towards each end.  Every rule
    of the motion (closure, transmission) is monotone in cos(theta2), so these two angles per gap hold it exactly
    where sampling holds it only at the samples.  The rows' values are continuous in the targets' angles, with a
    continuous derivative where an extreme leaves an end (d cos/d theta = 0 there); the angle jumps from one end to
    the other where the nearest multiple switches (both ends then equally near, cos equal there), a kink of the
    row -- the max(cos a, cos b) kink the rule itself has over a gap with no such point.  Floats or CasADi symbols."""
    symbolic = any(isinstance(t, (ca.SX, ca.MX)) for t in thetas)
    fmin, fmax, floor = (ca.fmin, ca.fmax, ca.floor) if symbolic else (min, max, math.floor)
    out = []
    for a, b in zip(thetas, thetas[1:]):
        lo, hi, mid = fmin(a, b), fmax(a, b), 0.5 * (a + b)
        for phase in (0.0, math.pi):
            nearest = phase + 2.0 * math.pi * floor((mid - phase) / (2.0 * math.pi) + 0.5)
            out.append(fmin(fmax(nearest, lo), hi))
    return out


def _direction_text(sign, direction: str) -> str:
    if isinstance(sign, (int, float, np.floating)):
        return "ccw" if sign > 0 else "cw"
    return direction


def path_rules(spec: FourbarPathSpec, v: dict, thetas: list | None, sign, samples: int,
               dynamics_samples: int | None = None, crank_speed_rpm=None) -> list[Rule]:
    """Every rule of the spec on the design ``v`` (r1..theta0), the crank angle (rad) of each target and
    the crank direction ``sign`` (+1 counter-clockwise, -1 clockwise); ``samples`` per gap between
    targets for the sampled rules of grashof = "any"; the [dynamics.limits] at ``dynamics_samples`` crank angles of
    a turn (None: [solver] dynamics_samples, the NLP's) and ``crank_speed_rpm`` (None: the spec's).

    ``thetas`` None (floats only): the targets have no crank angle, the loop closing at none; closure
    and transmission are then evaluated over a turn and the sequence is not evaluated."""
    r1, r2, r3, r4 = (v[n] for n in ("r1", "r2", "r3", "r4"))
    lim = spec.rules
    numeric = not any(isinstance(x, (ca.SX, ca.MX)) for x in (r1, r2, r3, r4, *(() if thetas is None else thetas)))

    def over(f, angles, *lengths):
        """f at each crank angle: on numbers one vectorised call (a numpy vector: the re-check samples thousands),
        on symbols a list of expressions (one NLP row each)."""
        if numeric:
            return np.asarray(f(np.asarray(angles, dtype=float).ravel(), *lengths), dtype=float).ravel()
        return [f(th, *lengths) for th in angles]

    rules: list[Rule] = []
    motion: list | None
    if thetas is None:
        motion = list(np.linspace(0.0, 2.0 * math.pi, TURN_SAMPLES, endpoint=False))
    elif lim.grashof == "any" and len(thetas) > 1:
        motion = segment_angles(thetas, samples) if samples != EXTREMES else None
    else:
        motion = thetas
    if lim.grashof != "any":
        rules.append(grashof_class_rule(lim.grashof, r1, r2, r3, r4))
        rules.append(assembly_rule(over(diagonal_sq, motion, r1, r2), r3, r4,
                                   where="at every target" if thetas is not None else "over a turn"))
        if lim.transmission_angle is not None:
            rules += transmission_turn_rules(cos_transmission(0.0, r1, r2, r3, r4),
                                             cos_transmission(math.pi, r1, r2, r3, r4), lim.transmission_angle)
    elif motion is None:            # the exact form: each gap's shortest and longest diagonal (motion_extremes)
        assert thetas is not None, "only the targets' crank angles leave the motion to the exact form"
        extremes = motion_extremes(thetas)
        nearest, farthest = extremes[0::2], extremes[1::2]
        rules.append(assembly_extremes_rule([diagonal_sq(th, r1, r2) for th in nearest],
                                            [diagonal_sq(th, r1, r2) for th in farthest], r3, r4,
                                            where="at the targets and between them"))
        if lim.transmission_angle is not None:
            rules += transmission_extremes_rules([cos_transmission(th, r1, r2, r3, r4) for th in nearest],
                                                 [cos_transmission(th, r1, r2, r3, r4) for th in farthest],
                                                 lim.transmission_angle)
    else:
        rules.append(assembly_rule(over(diagonal_sq, motion, r1, r2), r3, r4,
                                   where="at the targets and between them" if thetas is not None else "over a turn"))
        if lim.transmission_angle is not None:
            rules += transmission_sampled_rules(over(cos_transmission, motion, r1, r2, r3, r4),
                                                lim.transmission_angle)
    if not spec.timed and lim.order:
        direction = _direction_text(sign, lim.direction)
        what = f"targets met in order within one turn, crank {direction}"
        if thetas is None:
            rules.append(not_evaluated("sequence", 0.0, None, "deg", what,
                                       "no crank angle of the targets: the loop closes at no crank angle"))
        else:
            rule = sequence_rule([t * DEG for t in thetas], sign, direction)
            rules.append(dataclasses.replace(rule, note=_shared_angle(spec, thetas, sign)) if numeric else rule)
    turn = spec.solver.dynamics_samples if dynamics_samples is None else dynamics_samples
    rules += path_dynamics_rules(spec, v, turn, crank_speed_rpm)
    return rules


def path_backoff(spec: FourbarPathSpec, fraction: float) -> Backoff:
    """The NLP's back-off: every row ``fraction`` x max(1, |limit|) inside its limit (the core's relative back-off,
    the one rule for a spec without [dynamics.limits]); the rows of the [dynamics.limits] so that each peak is
    :func:`synthesis.dynamics.linkage.dynamics_backoff` of its limit inside it (the shaking force's row is its square: 1 - (1 - b)^2 of the
    row's limit)."""
    general = relative_backoff(fraction)
    if spec.dynamics is None or not spec.dynamics.has_rules():
        return general
    return peak_backoff(spec.solver.dynamics_samples, general)


#: two targets whose crank angles differ by less than this (deg) share one coupler pose
SHARED_ANGLE = 1e-6


def _shared_angle(spec: FourbarPathSpec, thetas, sign) -> str | None:
    """The sequence holds only at its limit where two distinct neighbouring targets get one crank angle: one
    coupler pose then stands for both (its distance to each counts in the objective), which a reader of
    "satisfied" would not guess (a trial: targets 0 and 1, 18.1 mm apart, 5.4e-9 deg apart)."""
    angles = [float(t) * DEG for t in thetas]
    points = np.asarray(spec.targets.points, dtype=float)
    one = same_target_mm(points)        # closer together they are one target (spec.same_targets), said apart
    shared = [i for i, gap in enumerate(sequence_slacks(angles, sign)[:-1])
              if abs(gap) < SHARED_ANGLE and np.hypot(*(points[i + 1] - points[i])) > one]      # not out of order
    if not shared:
        return None
    pairs = ", ".join(f"{i} and {i + 1}" for i in shared)
    return (f"targets {pairs} (from 0) share one crank angle: one coupler pose stands for both, the order holding "
            f"only at its limit")
