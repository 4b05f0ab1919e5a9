"""Numeric scene of a planting-arm design: precision points P1-P6 and the rule inputs.

This is the ``check`` side: every precision point is found by root finding (scipy ``brentq``) on
the exact AD kinematics, and the semi-infinite rules are sampled on fine grids (:func:`float_trace`).
The ``solve`` side traces the same points from decision variables instead
(:mod:`synthesis.kinds.planting.nlp`); both hand their trace to :func:`synthesis.kinds.planting.rule_set.planting_rules`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import cast

import numpy as np
from scipy.optimize import brentq

from synthesis.constraints.poses import nearest_row
from synthesis.errors import AssemblyError
from synthesis.kinds.planting.kinematics import (ArmDesign, Motion, attitude_function, lowest_rocker_counterweight_y,
                                                 path_positions, scalar_function, tip_accelerations_y, tip_derivatives,
                                                 tip_heights_and_transmission, tip_position, tip_positions, tip_state,
                                                 transmission_angles)
from synthesis.kinds.planting.rule_set import PHASES, POINTS, TWO_PI, PoseReading, Trace, phase_bounds
from synthesis.kinds.planting.rules.counterweight import CounterweightReading, declared, longer_than_link
from synthesis.spec.common import value_of
from synthesis.kinds.planting.spec import PlantingDynamicsSection, PlantingFourbarSpec


@dataclass(frozen=True)
class Seedbed:
    """Seedbed-bottom line through ``point`` at ``tilt`` (rad); seedlings on the side of ``normal``."""

    point: tuple[float, float]
    tilt: float
    thickness: float
    seedling_height: float

    @property
    def normal(self) -> tuple[float, float]:
        return (-math.sin(self.tilt), math.cos(self.tilt))

    def height(self, pos) -> np.ndarray:
        """Signed distance of pos (2, N) above the seedbed bottom, mm."""
        n = self.normal
        return n[0] * (pos[0] - self.point[0]) + n[1] * (pos[1] - self.point[1])


@dataclass(frozen=True)
class PlantingScene:
    design: ArmDesign
    motion: Motion
    seedbed: Seedbed
    soil_level: float | None       # Y of the soil surface, machine frame; None = analysis convention
    analysis_depth: float | None   # soil this far above the lowest point
    #: typical |a_y| normalising the acceleration margins (mm/s^2): omega^2 x the spec's *given* crank
    #: length, the same number the NLP uses; None: omega^2 x this design's crank length
    reference_acc: float | None = None
    #: the spec's [dynamics] table, or None
    dynamics: PlantingDynamicsSection | None = None
    #: the design's counterweight on the crank (mass kg, radius mm), or None
    counterweight: tuple | None = None
    #: the spec's [key_poses]: name -> pose (synthesis.kinds.planting.spec.KeyPose); empty without the table
    key_poses: dict = field(default_factory=dict)
    #: the design's counterweight on the rocker (mass kg, radius mm), or None
    rocker_counterweight: tuple | None = None

    @property
    def acc_scale(self) -> float:
        return self.reference_acc if self.reference_acc is not None else self.motion.omega**2 * self.design.l2

    @classmethod
    def from_spec(cls, spec: PlantingFourbarSpec, values: dict[str, float] | None = None) -> "PlantingScene":
        """The scene at the spec's given values, or at ``values`` (design-variable name -> value)."""
        v = spec.design_values() if values is None else values
        arm = ArmDesign(v["l1"], v["l2"], v["l3"], v["l4"], v["l5"], v["zeta"], v["phi"], spec.arm.branch)
        # numbers once validated: resolve_ranges puts a range's nominal value in its place
        crank_speed, forward_speed = cast(float, spec.operation.crank_speed), cast(float, spec.operation.forward_speed)
        motion = Motion(omega=crank_speed * TWO_PI / 60.0, forward=forward_speed * 1000.0)
        bed = Seedbed((v["seedbed_x"], v["seedbed_y"]), math.radians(v["seedbed_tilt"]),
                      spec.seedbed.thickness, spec.seedbed.seedling_height)
        soil = v.get("soil_level") if spec.soil.level is not None else None
        weight = (v["counterweight_mass"], v["counterweight_radius"]) if "counterweight_mass" in v else None
        rocker_weight = ((v["rocker_counterweight_mass"], v["rocker_counterweight_radius"])
                         if "rocker_counterweight_mass" in v else None)
        return cls(arm, motion, bed, soil, spec.soil.analysis_depth, motion.omega**2 * value_of(spec.arm.l2),
                   spec.dynamics, weight, dict(spec.key_poses), rocker_weight)


@dataclass
class PrecisionPoints:
    """Crank angles (rad, increasing through one cycle from P5) of P1-P6; None where not found."""

    theta: dict[str, float | None]
    soil_level: float | None
    problems: dict[str, str] = field(default_factory=dict)
    #: each key pose's crank angle (rad; None where it cannot be read, ``problems[pose_key(name)]`` says why),
    #: filled in by :func:`locate_poses`
    poses: dict[str, float | None] = field(default_factory=dict)

    def missing(self, *names: str) -> str | None:
        """Why any of ``names`` is absent (the first reason), or None when all exist."""
        for n in names:
            if self.theta.get(n) is None:
                return self.problems.get(n, f"{n} not found")
        return None


# ----------------------------------------------------------------------------- assembly

def assembly_status(d: ArmDesign) -> str | None:
    """None if the loop closes over the whole turn; else why the crank cannot complete a turn.

    Raises AssemblyError if it closes at no crank angle at all.  With the diagonal
    d(theta) = |O'A| in [|l1 - l2|, l1 + l2], triangle O'AB closes iff |l3 - l4| <= d <= l3 + l4.
    """
    reach, gap = d.l3 + d.l4, abs(d.l3 - d.l4)
    dmin, dmax = abs(d.l1 - d.l2), d.l1 + d.l2
    if dmin > reach:
        raise AssemblyError(
            f"linkage cannot assemble at any crank angle: at crank angle 0 deg |O'A| = l1 - l2 = {dmin:g} mm "
            f"> l3 + l4 = {reach:g} mm (triangle O'AB cannot close)")
    if dmax < gap:
        raise AssemblyError(
            f"linkage cannot assemble at any crank angle: at crank angle 180 deg |O'A| = l1 + l2 = {dmax:g} mm "
            f"< |l3 - l4| = {gap:g} mm (triangle O'AB cannot close)")
    if dmax > reach:
        bad = math.degrees(math.acos(max(-1.0, min(1.0, (d.l1**2 + d.l2**2 - reach**2) / (2 * d.l1 * d.l2)))))
        return (f"crank cannot complete a turn: between crank angles {bad:.1f} and {360 - bad:.1f} deg "
                f"|O'A| > l3 + l4 = {reach:g} mm (triangle O'AB cannot close)")
    if dmin < gap:
        bad = math.degrees(math.acos(max(-1.0, min(1.0, (d.l1**2 + d.l2**2 - gap**2) / (2 * d.l1 * d.l2)))))
        return (f"crank cannot complete a turn: between crank angles -{bad:.1f} and {bad:.1f} deg "
                f"|O'A| < |l3 - l4| = {gap:g} mm (triangle O'AB cannot close)")
    return None


# ----------------------------------------------------------------------------- precision points

def _refine(fun, a: float, b: float) -> float:
    """Root of fun in [a, b] (a sign change is known to lie there)."""
    fa, fb = fun(a), fun(b)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    return brentq(fun, a, b, xtol=1e-13, rtol=4 * np.finfo(float).eps, maxiter=200)


@dataclass(frozen=True)
class TurnScan:
    """The claw's Y (mm) and the transmission angle mu (rad) at ``theta``: a turn from crank angle 0, its end
    excluded, evaluated in one pass (P5's search scans Y on the very grid the transmission rule samples)."""

    theta: np.ndarray
    y: np.ndarray
    mu: np.ndarray


def turn_scan(design: ArmDesign, samples: int) -> TurnScan:
    theta = np.linspace(0.0, TWO_PI, samples, endpoint=False)
    return TurnScan(theta, *tip_heights_and_transmission(design, theta))


def _crossings(values: np.ndarray, level: float, downward: bool) -> np.ndarray:
    """Indices k with values[k] and values[k+1] on opposite sides of level, in the given direction."""
    above = values >= level
    if downward:
        return np.flatnonzero(above[:-1] & ~above[1:])
    return np.flatnonzero(~above[:-1] & above[1:])


def find_precision_points(scene: PlantingScene, grid: int = 3600, scan: TurnScan | None = None) -> PrecisionPoints:
    """P5 = lowest point (vy = 0), P4/P6 = soil crossings around it, P3/P2/P1 = seedbed crossings.

    One cycle is scanned from P5: P5 < P6 < P1 < P2 < P3 < P4 < P5 + 360 deg.  P3 is the last
    downward crossing of the seedbed bottom before P4, P2 the last of the seedbed top before P3,
    P1 the last of the seedling-top line before P2.  ``scan``: the turn already scanned (used when it has ``grid``
    samples).
    """
    d, bed = scene.design, scene.seedbed
    # the root finders' functions: only the row each reads (a re-check is a Monte-Carlo sample)
    p = d.parameters()
    y_at, vy_at = scalar_function(tip_position, d.branch, 0, (1,)), scalar_function(tip_derivatives, d.branch, 1, (1,))
    pos_at = scalar_function(tip_position, d.branch, 0, (0, 1))

    def y(th):
        return y_at.scalar(th, p)

    def vy(th):
        return vy_at.scalar(th, p)

    def height(th):
        x_, y_ = pos_at.values(th, p)[:, 0].tolist()
        return float(bed.height((x_, y_)))

    if scan is None or scan.theta.size != grid:
        scan = turn_scan(d, grid)
    coarse, ys = scan.theta, scan.y
    k = int(np.argmin(ys))
    h = coarse[1]
    # the lowest point: vy changes sign from - to + around the grid minimum
    th5 = _refine(vy, coarse[k] - h, coarse[k] + h) if vy(coarse[k] - h) < 0 < vy(coarse[k] + h) else coarse[k]
    theta: dict[str, float | None] = {n: None for n in POINTS}
    theta["P5"] = th5
    problems: dict[str, str] = {}
    y5 = y(th5)
    soil = scene.soil_level if scene.soil_level is not None else y5 + scene.analysis_depth

    cycle = th5 + np.linspace(0.0, TWO_PI, grid + 1)
    positions = tip_positions(d, cycle)
    ycyc = positions[1]
    if not np.all(np.isfinite(ycyc)):
        # a linkage that does not assemble over the whole turn has no claw path to cross the soil (a tolerance
        # box's corner of a design near its Grashof limit: an IndexError on the empty crossings)
        why = "the claw path cannot be traced over a turn: the linkage does not assemble at every crank angle"
        problems.update({"P4": why, "P6": why})
    elif soil <= y5:
        why = f"the claw never reaches the soil: lowest point Y = {y5:.1f} mm is above the soil surface Y = {soil:.1f} mm"
        problems.update({"P4": why, "P6": why})
    elif soil >= ycyc.max():
        why = f"the whole claw path (top Y = {ycyc.max():.1f} mm) lies below the soil surface Y = {soil:.1f} mm"
        problems.update({"P4": why, "P6": why})
    else:
        up = _crossings(ycyc, soil, downward=False)
        dn = _crossings(ycyc, soil, downward=True)
        theta["P6"] = _refine(lambda t: y(t) - soil, cycle[up[0]], cycle[up[0] + 1])
        theta["P4"] = _refine(lambda t: y(t) - soil, cycle[dn[-1]], cycle[dn[-1] + 1])

    if theta["P4"] is not None:
        s = bed.height(positions)
        end = theta["P4"]
        exit_ = theta["P6"]
        assert exit_ is not None          # found with P4, the soil's other crossing
        levels = (("P3", 0.0), ("P2", bed.thickness), ("P1", bed.seedling_height))
        for k, (name, level) in enumerate(levels):
            idx = [i for i in _crossings(s, level, downward=True)
                   if exit_ < cycle[i] and cycle[i + 1] <= end]
            if not idx:
                what = {"P1": "[seedbed] seedling_height", "P2": "[seedbed] thickness"}.get(name)
                hint = (f" (that line is {what} = {level:g} mm: lower it, or give the arm a taller loop)"
                        if what else "")
                problems[name] = (f"{name} not found: the claw does not cross the line {level:g} mm above the "
                                  f"seedbed bottom on its way down between soil exit and entry{hint}" if what else
                                  f"{name} not found: {_misses_the_bottom(s, cycle, exit_, end)}")
                for later, _ in levels[k + 1:]:      # searched before `name` on the way down: its reason is theirs
                    problems[later] = f"{later} not searched: {problems[name]}"
                break
            i = idx[-1]
            end = _refine(lambda t, lv=level: height(t) - lv, cycle[i], cycle[i + 1])
            theta[name] = end
    else:
        for name in ("P1", "P2", "P3"):
            problems[name] = problems["P4"]
    return PrecisionPoints(theta, soil, problems)


def _misses_the_bottom(heights: np.ndarray, cycle: np.ndarray, exit_: float, entry: float) -> str:
    """Why the claw (its heights above the seedbed bottom at crank angles ``cycle``, mm and rad) never comes down
    through the seedbed bottom between soil exit ``exit_`` and soil entry ``entry``, in what the tip does ("the line
    0 mm above the seedbed bottom" said nothing a designer could act on)."""
    inside = (cycle > exit_) & (cycle <= entry)
    way = heights[inside]
    if not way.size or way.min() > 0.0:
        lowest = f": its tip stays {way.min():.1f} mm above it" if way.size else ""
        return f"the claw never reaches the seedbed bottom between soil exit and entry{lowest}"
    later = [i for i in _crossings(heights, 0.0, downward=True) if cycle[i] > entry]
    if later:
        return (f"the claw enters the soil (crank angle {math.degrees(entry) % 360:.1f} deg) before it comes down "
                f"to the seedbed bottom ({math.degrees(cycle[later[0]]) % 360:.1f} deg)")
    if way.max() < 0.0:
        return (f"the claw stays below the seedbed bottom all the way between soil exit and entry (at least "
                f"{-way.max():.1f} mm below it)")
    return "the claw crosses the seedbed bottom only on its way up between soil exit and entry, never down"


# ----------------------------------------------------------------------------- key poses

def pose_key(name: str) -> str:
    """The key of a pose's reason in :attr:`PrecisionPoints.problems` (apart from P1-P6's own)."""
    return f"key pose {name}"


def nearest_crank_angle(design: ArmDesign, target: tuple[float, float], samples: int) -> float:
    """The crank angle (rad, in [0, 2 pi)) where the claw tip comes nearest ``target`` (mm): the nearest of
    ``samples`` angles over a turn, then the root of (C - target) . dC/dtheta between its neighbours (the row the NLP
    pins a free pose's angle with, :func:`synthesis.constraints.poses.nearest_row`)."""
    grid = np.linspace(0.0, TWO_PI, samples, endpoint=False)
    pos = path_positions(design, grid)
    k = int(np.argmin((pos[0] - target[0]) ** 2 + (pos[1] - target[1]) ** 2))
    h, p, f = grid[1], design.parameters(), tip_derivatives(design.branch)

    def row(th: float) -> float:
        c, dc, _ = f(th, p)
        return float(nearest_row(float(c[0]) - target[0], float(c[1]) - target[1], float(dc[0]), float(dc[1])))

    lo, hi = grid[k] - h, grid[k] + h
    return _refine(row, lo, hi) if row(lo) < 0.0 < row(hi) else float(grid[k])


def locate_poses(scene: PlantingScene, pts: PrecisionPoints, samples: int = 3600) -> PrecisionPoints:
    """Each key pose's crank angle into ``pts.poses``: its precision point's (None where that point was not found,
    with the reason), its prescribed crank angle, or where the tip comes nearest its target on a turn of
    ``samples`` angles (:func:`nearest_crank_angle`)."""
    for name, pose in scene.key_poses.items():
        theta: float | None
        if pose.at is not None:
            theta = pts.theta[pose.at]
            if theta is None:
                pts.problems[pose_key(name)] = f"{pose.at}: {pts.problems.get(pose.at, f'{pose.at} not found')}"
        elif pose.crank_angle is not None:
            theta = math.radians(pose.crank_angle)
        else:
            theta = nearest_crank_angle(scene.design, pose.tip, samples)
        pts.poses[name] = theta
    return pts


def float_poses(scene: PlantingScene, pts: PrecisionPoints, turn_missing: str | None = None) -> list[PoseReading]:
    """The claw at each key pose of a numeric design, at the crank angles :func:`locate_poses` found."""
    if not scene.key_poses:
        return []
    d, out = scene.design, []
    attitude = attitude_function(d.branch)
    for name, pose in scene.key_poses.items():
        theta = None if turn_missing else pts.poses.get(name)
        if theta is None:
            why = turn_missing or pts.problems.get(pose_key(name), f"key pose {name} not located")
            out.append(PoseReading(name, pose, missing=why))
            continue
        at = tip_state(d, scene.motion, theta)
        out.append(PoseReading(name, pose, theta, (float(at.pos[0, 0]), float(at.pos[1, 0])),
                               float(attitude(theta, d.parameters()))))
    return out


# ----------------------------------------------------------------------------- rules

def phase_grid(a: float, b: float, n: int) -> np.ndarray:
    """n crank angles evenly from a to b inclusive (b may exceed a by up to a turn)."""
    return np.linspace(a, b, n)


def float_trace(scene: PlantingScene, pts: PrecisionPoints, phase_samples: int = 400, turn_samples: int = 3600,
                turn_missing: str | None = None, scan: TurnScan | None = None) -> Trace:
    """The rules' trace of a numeric design: the found precision points, phases and a turn sampled.

    ``turn_missing`` says why the crank cannot complete a turn (then the turn rules are unevaluated); ``scan``: the
    turn already scanned (its transmission angles are the turn's when it has ``turn_samples`` samples).
    """
    d, m = scene.design, scene.motion
    found = [n for n in POINTS if pts.theta[n] is not None]
    theta = {n: pts.theta[n] for n in found}
    pos: dict[str, tuple] = {}
    vel: dict[str, tuple] = {}
    if found:
        at = tip_state(d, m, [theta[n] for n in found])       # one call for every point found
        pos = {n: tuple(at.pos[:, k]) for k, n in enumerate(found)}
        vel = {n: tuple(at.vel[:, k]) for k, n in enumerate(found)}
    accel = {}
    for phase, (a, b) in PHASES.items():
        if a in theta and b in theta:
            accel[phase] = tip_accelerations_y(d, m, phase_grid(*phase_bounds(theta, phase), phase_samples))
    return Trace(theta=theta, pos=pos, vel=vel, accel_y=accel,
                 links=(d.l1, d.l2, d.l3, d.l4),
                 mu_deg=None if turn_missing else (np.degrees(scan.mu) if scan is not None and scan.theta.size ==
                                                   turn_samples else transmission_angles_deg(d, turn_samples)),
                 omega=m.omega,
                 forward=m.forward, acc_scale=scene.acc_scale, problems=dict(pts.problems),
                 turn_missing=turn_missing, poses=float_poses(scene, pts, turn_missing),
                 counterweights=float_counterweights(scene, pts, turn_samples, turn_missing))


def float_counterweights(scene: PlantingScene, pts: PrecisionPoints, turn_samples: int,
                         turn_missing: str | None = None) -> list[CounterweightReading]:
    """Each counterweight of the design with a mass (crank's, then rocker's) at its lowest point over a turn, its
    height above the soil surface the precision points were found with: the crank's exactly (it circles the origin O:
    -radius), the rocker's on ``turn_samples`` crank angles refined (rules.counterweight)."""
    if scene.dynamics is None:
        return []
    clearance = scene.dynamics.counterweight_clearance
    d, out = scene.design, []
    for name, weight, length in (("counterweight", scene.counterweight, d.l2),
                                 ("rocker_counterweight", scene.rocker_counterweight, d.l4)):
        if not declared(weight, free=False):
            continue
        assert weight is not None            # declared: a counterweight with a mass
        radius = float(weight[1])
        note = longer_than_link(name, radius, length)
        if turn_missing is not None or pts.soil_level is None:
            why = turn_missing or "the soil surface is not found"
            out.append(CounterweightReading(name, None, clearance, note, why))
            continue
        lowest = (-radius if name == "counterweight"
                  else lowest_rocker_counterweight_y(d.parameters(), radius, d.branch, turn_samples))
        out.append(CounterweightReading(name, lowest - pts.soil_level, clearance, note))
    return out


def transmission_angles_deg(d: ArmDesign, samples: int) -> np.ndarray:
    return np.degrees(transmission_angles(d, np.linspace(0.0, TWO_PI, samples, endpoint=False)))
