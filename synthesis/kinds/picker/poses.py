"""Key poses of the picker kinds (an optional ``[key_poses]`` table; the shared pose model and rules:
:mod:`synthesis.spec.poses`, :mod:`synthesis.constraints.poses`).

A pose asks the clamp's attitude -- the direction of the clamp arm C -> M (:func:`clamp_attitude`) -- and/or the
clamp point M's position.  The double crank reads it at the picking point M1 (crank angle phi10), the drop point M2
(phi10 + psi), a prescribed crank angle, or, for a free pose, where M comes nearest its target over the working
swing: the check finds that angle on floats (:func:`nearest_crank_angle`), the NLP holds an auxiliary crank angle
there by the shared nearest-point row (:func:`symbolic_poses`).  The check, the fine-grid re-check and the NLP build
the rules ``pose_<name>`` and ``pose_<name>_attitude`` with the same functions (:func:`pose_rules`).  The combined
picker reads its poses at instants of its motion (synthesis/kinds/picker/combined.py) and uses the same readings and
rules.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from synthesis.constraints import Rule
from synthesis.constraints.poses import (
    attitude_miss_deg,
    nearest_row,
    pose_attitude_rule,
    pose_tip_rule,
)
from synthesis.kinds.picker.kinematics.linkage import (
    DoubleCrank,
    attitude_function,
    clamp_attitude,
    clamp_function,
    clamp_states,
)
from synthesis.kinds.picker.spec import CLAMP_ATTITUDE, PickerDoubleCrankSpec

DEG = 180.0 / math.pi
#: crank angles over the working swing on which the check looks for a free pose's nearest point (then refined to the
#: root of the nearest-point row between the neighbours of the nearest sample); fixed, so the check and the re-check
#: read a pose at the same angle whatever their transmission grid
POSE_SEARCH_SAMPLES = 2001
#: the double crank's named points: name -> where over the working swing (0: phi10, 1: phi10 + psi)
NAMED_POINTS = {"M1": 0.0, "M2": 1.0}


@dataclass
class PoseReading:
    """The clamp at one key pose: the pose (the spec's ``[key_poses]`` entry), its crank angle AB (rad), the clamp
    point (mm) and the clamp's attitude (rad, :func:`clamp_attitude`) there, floats or CasADi symbols; ``at``: where
    the pose is read, for the rule's text."""

    name: str
    pose: Any
    angle: Any
    pos: tuple
    attitude: Any
    at: str | None = None

    @property
    def where(self) -> str:
        return f"key pose {self.name}" + (f", at {self.at}" if self.at is not None else "")


def pose_rules(readings: list[PoseReading]) -> list[Rule]:
    """Per key pose, in the spec's order: the clamp point within its tolerance of (x, y) if the pose gives them
    (``pose_<name>``), the clamp's attitude within its tolerance if the pose gives one (``pose_<name>_attitude``)."""
    rules = []
    for r in readings:
        pose = r.pose
        if pose.tip is not None:
            rules.append(pose_tip_rule(r.name, r.pos[0] - pose.tip[0], r.pos[1] - pose.tip[1], pose.tolerance,
                                       r.where))
        if pose.attitude is not None:
            rules.append(pose_attitude_rule(r.name, attitude_miss_deg(r.attitude * DEG, pose.attitude),
                                            pose.attitude_tolerance, r.where))
    return rules


# ----------------------------------------------------------------------------- the double crank

def free_poses(spec: PickerDoubleCrankSpec) -> list[str]:
    """The poses whose crank angle the solver finds (no named point, no prescribed angle), in the spec's order."""
    return [n for n, pose in spec.key_poses.items() if pose.at is None and pose.crank_angle is None]


def free_target(pose: Any) -> tuple[float, float]:
    """A free pose's target (mm): the pose models require x and y where no point and no crank angle is named."""
    assert pose.tip is not None
    return pose.tip


def fixed_angle_deg(spec: PickerDoubleCrankSpec, name: str) -> float | None:
    """A pose's crank angle AB (deg) where the spec fixes it (at M1 or M2, or prescribed); None for a free pose."""
    pose = spec.key_poses[name]
    if pose.at is not None:
        return spec.drive.start + spec.drive.swing * NAMED_POINTS[pose.at]
    return pose.crank_angle


def nearest_crank_angle(spec: PickerDoubleCrankSpec, dc: DoubleCrank, target: tuple[float, float],
                        samples: int = POSE_SEARCH_SAMPLES) -> float:
    """The crank angle AB (deg, within the working swing) where the clamp point comes nearest ``target`` (mm): the
    nearest of ``samples`` angles over the swing, then the root of (M - target) . dM/dphi1 between its neighbours
    (the row the NLP pins a free pose's angle with, :func:`synthesis.constraints.poses.nearest_row`); the nearest sample itself
    where the row does not change sign there (the nearest point is an end of the swing)."""
    grid = spec.drive.start + spec.drive.swing * np.linspace(0.0, 1.0, samples)
    m = clamp_states(dc, grid)["M"]
    k = int(np.argmin((m[0] - target[0]) ** 2 + (m[1] - target[1]) ** 2))
    f, p = clamp_function(dc.branch), dc.parameters()

    def row(deg: float) -> float:
        pos, rate, _, _ = f(math.radians(deg), p)
        return float(nearest_row(float(pos[0]) - target[0], float(pos[1]) - target[1], float(rate[0]),
                                 float(rate[1])))

    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, samples - 1)]
    if row(lo) < 0.0 < row(hi):
        return float(brentq(row, lo, hi, xtol=1e-13, rtol=4 * np.finfo(float).eps, maxiter=200))
    return float(grid[k])


def pose_angles_deg(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> dict[str, float]:
    """Each key pose's crank angle AB (deg): its named point's, its prescribed one, or where the clamp point comes
    nearest its target (:func:`nearest_crank_angle`)."""
    out = {}
    for name, pose in spec.key_poses.items():
        fixed = fixed_angle_deg(spec, name)
        out[name] = nearest_crank_angle(spec, dc, free_target(pose)) if fixed is None else fixed
    return out


def float_poses(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> list[PoseReading]:
    """The clamp at each key pose of a numeric design (none without a [key_poses] table)."""
    if not spec.key_poses:
        return []
    angles = pose_angles_deg(spec, dc)
    f, attitude, p = clamp_function(dc.branch), attitude_function(dc.branch), dc.parameters()
    out = []
    for name, pose in spec.key_poses.items():
        phi1 = math.radians(angles[name])
        m = f(phi1, p)[0]
        out.append(PoseReading(name, pose, phi1, (float(m[0]), float(m[1])), float(attitude(phi1, p)), pose.at))
    return out


def symbolic_poses(spec: PickerDoubleCrankSpec, p, free_angles: dict[str, Any]) -> tuple[list[PoseReading], list]:
    """The clamp at each key pose on the NLP's symbols p (:data:`~synthesis.kinds.picker.kinematics.linkage.
    PARAMETERS`) -- at its named point's or its prescribed crank angle, or at its own auxiliary one
    (``free_angles``: name -> rad) -- and the rows (expr, 0, 0) pinning each free pose's angle where the clamp point
    comes nearest its target (the check's reading, :func:`nearest_crank_angle`), mm^2/rad."""
    branch, f = spec.linkage.branch, clamp_function(spec.linkage.branch)
    readings, rows = [], []
    for name, pose in spec.key_poses.items():
        fixed = fixed_angle_deg(spec, name)
        phi1 = free_angles[name] if fixed is None else math.radians(fixed)
        m, dm, _, _ = f(phi1, p)
        if fixed is None:
            x, y = free_target(pose)
            rows.append((nearest_row(m[0] - x, m[1] - y, dm[0], dm[1]), 0.0, 0.0))
        readings.append(PoseReading(name, pose, phi1, (m[0], m[1]), clamp_attitude(phi1, p, branch), pose.at))
    return readings, rows


def start_angles(spec: PickerDoubleCrankSpec, dc: DoubleCrank, samples: int = 201) -> list[float]:
    """A start's free-pose crank angles (rad): the nearest of ``samples`` angles over the swing on the start design's
    path; the middle of the swing where that design does not assemble."""
    grid = spec.drive.start + spec.drive.swing * np.linspace(0.0, 1.0, samples)
    m = clamp_states(dc, grid)["M"]
    out = []
    for name in free_poses(spec):
        x, y = free_target(spec.key_poses[name])
        distance = (m[0] - x) ** 2 + (m[1] - y) ** 2
        k = int(np.nanargmin(distance)) if np.isfinite(distance).any() else samples // 2
        out.append(math.radians(float(grid[k])))
    return out


def key_pose_facts(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> dict:
    """``{"key_poses": ...}`` when the spec has a [key_poses] table (else nothing): the clamp's attitude at M1 and M2,
    and at each pose its crank angle, the clamp point and the attitude there and their misses."""
    if not spec.key_poses:
        return {}
    points = {n: float(a) for n, a in zip(NAMED_POINTS, clamp_attitudes_at(spec, dc))}
    poses = {r.name: reading_facts(r, {"crank_deg": math.degrees(r.angle)}) for r in float_poses(spec, dc)}
    return {"key_poses": {"attitude": CLAMP_ATTITUDE, "clamp_attitude_at_points_deg": points, "poses": poses}}


def clamp_attitudes_at(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> list[float]:
    """The clamp's attitude (deg) at M1 and M2."""
    f, p = attitude_function(dc.branch), dc.parameters()
    return [math.degrees(float(f(math.radians(spec.drive.start + spec.drive.swing * s), p)))
            for s in NAMED_POINTS.values()]


def reading_facts(r: PoseReading, where: dict) -> dict:
    """One pose's facts: where it is read (``where``), the clamp point and attitude there, the misses, the target."""
    pose = r.pose
    x, y = float(r.pos[0]), float(r.pos[1])
    attitude = float(r.attitude) * DEG
    return {"at": pose.at, **where, "x": x, "y": y,
            "miss_mm": None if pose.tip is None else math.hypot(x - pose.tip[0], y - pose.tip[1]),
            "attitude_deg": attitude,
            "attitude_miss_deg": None if pose.attitude is None else float(attitude_miss_deg(attitude, pose.attitude)),
            "target": {"x": pose.x, "y": pose.y, "tolerance": pose.tolerance, "attitude": pose.attitude,
                       "attitude_tolerance": pose.attitude_tolerance}}


def pose_headline(facts: dict, rules: dict, prefix: str = "") -> list[str]:
    """A line per key pose: where it is read, the clamp's attitude and the clamp point there against the targets,
    and which of its rules miss (none without a [key_poses] table); ``prefix``: of the rules' names."""
    lines = []
    for name, pose in (facts.get("poses") or {}).items():
        where = (f" at {pose['at']}" if pose.get("at") else f" at t = {pose['t']:.4f} s" if "t" in pose else
                 f" at crank angle {pose['crank_deg']:.2f} deg")
        target, parts = pose.get("target") or {}, []
        if target.get("attitude") is not None:
            parts.append(f"attitude {pose['attitude_deg']:.1f} deg, {pose['attitude_miss_deg']:+.2f} deg from "
                         f"{target['attitude']:g} (within {target['attitude_tolerance']:g})")
        else:
            parts.append(f"attitude {pose['attitude_deg']:.1f} deg")
        if pose.get("miss_mm") is not None:
            parts.append(f"clamp point {pose['miss_mm']:.2f} mm from ({target['x']:g}, {target['y']:g}) (within "
                         f"{target['tolerance']:g})")
        missed = [n for n in (f"{prefix}pose_{name}", f"{prefix}pose_{name}_attitude")
                  if n in rules and not rules[n].get("satisfied")]
        lines.append(f"pose {name}{where}: {'; '.join(parts)}" + (f" -- MISSED ({', '.join(missed)})" if missed else ""))
    return lines
