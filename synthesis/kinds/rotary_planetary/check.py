"""``agrisynth check`` for kind rotary_planetary: the given design's gear and transplanting rules, and the trace
the NLP builds its rows from (one function on floats and symbols: :func:`rules_of`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, cast

import casadi as ca
import numpy as np
from scipy.optimize import brentq, minimize_scalar

from synthesis.constraints.base import Rule
from synthesis.constraints.poses import attitude_miss_deg
from synthesis.constraints.poses import pose_rules as shared_pose_rules
from synthesis.core.verdict import FINE
from synthesis.kinds.rotary_planetary import rules as R
from synthesis.kinds.rotary_planetary.kinematics import (
    Train, claw_attitude, idler_turn, is_symbolic, ops_of, pairs, tip, tip_curvature_rate, tip_rate, train_from_design,
    turn_grid,
)
from synthesis.kinds.rotary_planetary.spec import RotaryPlanetarySpec
from synthesis.result import Result
from synthesis.spec import LoadedSpec

RAD = math.pi / 180.0
DEG = 180.0 / math.pi
#: carrier angles of a turn where the tip's extremes and the poses are first looked for (0.1 deg), before refining
CHECK_SAMPLES = 3600
#: samples of the in-soil stroke where no [solver] setting gives them
CHECK_SOIL_SAMPLES = 400


def check_grid(spec: RotaryPlanetarySpec) -> tuple[int, int]:
    """The check's samples over a turn and over the in-soil stroke: the solve's re-check grid (FINE x the [solver]
    samples), so that `check` of a solve's solved.toml reads the solve's rule table."""
    return FINE * spec.solver.samples_per_turn, FINE * spec.solver.in_soil_samples


def train_of(spec: RotaryPlanetarySpec, design: dict) -> Train:
    """The train of a design (spec units: mm, deg; numbers or symbols) in mm and rad."""
    return train_from_design(design)


@dataclass
class Angles:
    """Carrier angles (rad; numbers or symbols) where the rules are read: the loop's top and bottom, soil entry and
    exit (None: the tip never enters the soil, ``missing`` says why) and each key pose."""

    top: Any
    bottom: Any
    entry: Any = None
    exit: Any = None
    poses: dict = field(default_factory=dict)
    missing: str | None = None
    #: with a single idler: per grid angle phi_j, the carrier angle where the idler had turned half a turn less
    half_turn: Any = None


def omega(spec: RotaryPlanetarySpec) -> float:
    """Carrier speed, rad/s."""
    return spec.operation.carrier_speed * 2.0 * math.pi / 60.0


def forward_mm_s(spec: RotaryPlanetarySpec) -> float:
    return spec.operation.forward_speed * 1000.0


def soil_y(spec: RotaryPlanetarySpec) -> float:
    return -spec.operation.axis_height


def plant_spacing(spec: RotaryPlanetarySpec) -> float:
    """Forward travel per plant, mm: half a carrier turn at the forward speed."""
    return forward_mm_s(spec) * math.pi / omega(spec)


def _cat(parts):
    if is_symbolic(*parts):
        return ca.vertcat(*[ca.vec(p) for p in parts])
    return np.concatenate([np.ravel(np.asarray(p, dtype=float)) for p in parts])


def gear_rules(spec: RotaryPlanetarySpec, train: Train, grid) -> list[Rule]:
    o = ops_of(train, grid)
    p1, p2 = pairs(train, grid)
    lim = spec.rules
    curvatures = _cat([c.curvature(o) for c in (p1.driver, p1.driven, p2.driver, p2.driven)])
    normal = _cat([p1.driver.normal_angle(o), p2.driver.normal_angle(o)]) * DEG
    return [R.pair_ratio_rule(_cat([p1.ratio[0], p2.ratio[0]]), lim.ratio_min, lim.ratio_max),
            R.concave_radius_rule(curvatures, lim.min_concave_radius),
            R.normal_angle_rule(normal, lim.max_normal_angle)]


def soil_rules(spec: RotaryPlanetarySpec, train: Train, angles: Angles, soil_samples: int,
               out_samples: int) -> list[Rule]:
    lim, w, v = spec.rules, omega(spec), forward_mm_s(spec)
    if angles.missing:
        return [R.entry_angle_rule(None, None, lim.entry_angle_min, angles.missing),
                R.hole_width_rule(None, None, lim.hole_width_max, angles.missing),
                R.in_soil_speed_rule(None, lim.in_soil_forward_speed_max, angles.missing),
                R.out_of_soil_rule(None, angles.missing)]
    # from soil exit round to the next entry: s in (0, 1), the tip's height above the surface over 4 s (1 - s)
    s_out = np.linspace(0.0, 1.0, out_samples + 2)[1:-1]
    arc = angles.exit + (angles.entry + 2.0 * math.pi - angles.exit) * (ca.DM(s_out) if is_symbolic(angles.exit)
                                                                        else s_out)
    _, y_out = tip(train, arc)
    weight = 4.0 * s_out * (1.0 - s_out)
    above = (y_out - soil_y(spec)) / (ca.DM(weight) if is_symbolic(y_out) else weight)
    dx_in, dy_in = tip_rate(train, angles.entry)
    x_in, _ = tip(train, angles.entry)
    x_out, _ = tip(train, angles.exit)
    s = np.linspace(0.0, 1.0, soil_samples)
    span = angles.exit - angles.entry
    stroke = angles.entry + span * (ca.DM(s) if is_symbolic(span) else s)
    dx, _ = tip_rate(train, stroke)
    return [R.entry_angle_rule(w * dx_in - v, w * dy_in, lim.entry_angle_min),
            R.hole_width_rule(x_in - v * angles.entry / w, x_out - v * angles.exit / w, lim.hole_width_max),
            R.in_soil_speed_rule(v - w * dx, lim.in_soil_forward_speed_max),
            R.out_of_soil_rule(above)]


def pose_rules(spec: RotaryPlanetarySpec, train: Train, angles: Angles) -> list[Rule]:
    out: list[Rule] = []
    for name, pose in spec.key_poses.items():
        x, y = tip(train, angles.poses[name])
        miss = None
        if pose.attitude is not None:
            miss = attitude_miss_deg(claw_attitude(train, angles.poses[name]) * DEG, pose.attitude)
        out += shared_pose_rules(name, x - pose.x, y - pose.y, pose.tolerance, miss, pose.attitude_tolerance)
    return out


def single_idler_rules(spec: RotaryPlanetarySpec, train: Train, grid, half_turn) -> list[Rule]:
    """With a single idler: its radius towards the planet at carrier angle phi', where its polar angle is the one
    it met the sun with at phi_j (theta2(phi') = theta2(phi_j) - pi), against that radius towards the sun."""
    if not spec.rules.single_idler:
        return []
    towards_sun = pairs(train, grid)[0].driven.radius[0]
    towards_planet = pairs(train, half_turn)[1].driver.radius[0]
    return [R.single_idler_rule(towards_planet - towards_sun, spec.rules.single_idler_tolerance)]


def rules_of(spec: RotaryPlanetarySpec, train: Train, angles: Angles, grid, soil_samples: int) -> list[Rule]:
    """Every rule of the spec, on floats (angles found on the grid) or symbols (angles the NLP's variables)."""
    _, y_top = tip(train, angles.top)
    _, y_bottom = tip(train, angles.bottom)
    _, y_grid = tip(train, grid)
    lim = spec.rules
    return [*gear_rules(spec, train, grid), *single_idler_rules(spec, train, grid, angles.half_turn),
            R.trajectory_height_rule(y_top, y_bottom, lim.trajectory_height_min),
            *R.planting_depth_rules(soil_y(spec), y_bottom, _cat([y_grid, y_bottom]), lim.planting_depth),
            *soil_rules(spec, train, angles, soil_samples, len(grid)),
            R.plant_spacing_rule(plant_spacing(spec), lim.plant_spacing),
            *pose_rules(spec, train, angles)]


# --- the angles on floats ----------------------------------------------------------------------------------------

def _refine(f, phi0: float, h: float) -> float:
    """The minimiser of f near phi0 (within one grid step h)."""
    # over the offset from phi0: Brent's bounded search stops at sqrt(eps) |x| relative, 1e-8 rad at phi0 = 4 rad,
    # enough to misplace a pose the solver holds at its tolerance by 1e-8 deg
    r = minimize_scalar(lambda d: f(phi0 + d), bounds=(-h, h), method="bounded", options={"xatol": 1e-14})
    best = phi0 + float(r.x)
    return best if f(best) <= f(phi0) else phi0


def _y(train: Train, phi: float) -> float:
    return float(tip(train, phi)[1])


def _crossing(train: Train, level: float, phi_bottom: float, h: float, direction: int, n: int):
    """The carrier angle nearest phi_bottom (before it: direction -1, after: +1) where the tip crosses y = level."""
    inside = phi_bottom
    for _ in range(n):
        outside = inside + direction * h
        if _y(train, outside) >= level:
            lo, hi = sorted((inside, outside))
            return brentq(lambda p: _y(train, p) - level, lo, hi, xtol=1e-14, rtol=1e-15)
        inside = outside
    return None


def _pose_distance(train: Train, pose, phi: float) -> float:
    px, py = tip(train, phi)
    return math.hypot(float(px) - pose.x, float(py) - pose.y)


def half_turn_angles(train: Train, grid) -> np.ndarray:
    """Per grid angle phi_j, the carrier angle phi' in (phi_j - 2 pi, phi_j) where the idler had turned half a turn
    less: theta2(phi') = theta2(phi_j) - pi (theta2 - target is -pi at phi_j - 2 pi and +pi at phi_j: a root)."""
    def root(phi: float) -> float:
        target = float(idler_turn(train, phi)) - math.pi
        return brentq(lambda q: float(idler_turn(train, q)) - target, phi - 2.0 * math.pi, phi, xtol=1e-14,
                      rtol=1e-15)

    return np.array([root(float(phi)) for phi in grid])


def find_angles(spec: RotaryPlanetarySpec, train: Train, n: int = CHECK_SAMPLES, grid_n: int | None = None
                ) -> Angles:
    """The loop's extremes, soil entry and exit and the key poses' carrier angles of a numeric design (and, with a
    single idler, the half-turn angles of the rules' grid of ``grid_n`` angles, default ``n``)."""
    grid = turn_grid(n)
    h = grid[1]
    x, y = tip(train, grid)
    bottom = _refine(lambda p: _y(train, p), float(grid[np.argmin(y)]), h)
    top = _refine(lambda p: -_y(train, p), float(grid[np.argmax(y)]), h)
    poses = {}
    for name, pose in spec.key_poses.items():
        if pose.carrier_angle is not None:
            poses[name] = pose.carrier_angle * RAD
            continue

        def miss(p, pose=pose):
            return _pose_distance(train, pose, p)

        # the pose is read where the tip is nearest its target (the NLP pins its angle there too)
        poses[name] = _refine(miss, float(grid[np.argmin((x - pose.x) ** 2 + (y - pose.y) ** 2)]), h)
    angles = Angles(top, bottom, poses=poses)
    if spec.rules.single_idler:
        angles.half_turn = half_turn_angles(train, turn_grid(grid_n or n))
    level = soil_y(spec)
    lowest = _y(train, bottom)
    if lowest >= level:
        angles.missing = f"the claw tip never reaches the soil (lowest at y = {lowest:.2f} mm, surface {level:g} mm)"
        return angles
    angles.entry = _crossing(train, level, bottom, h, -1, n)
    angles.exit = _crossing(train, level, bottom, h, +1, n)
    if angles.entry is None or angles.exit is None:
        angles.missing = "the claw tip stays in the soil over a whole turn"
    return angles


def evaluate(spec: RotaryPlanetarySpec, design: dict, n: int = CHECK_SAMPLES, soil_samples: int = CHECK_SOIL_SAMPLES
             ) -> tuple[list[Rule], Train, Angles]:
    train = train_of(spec, design)
    # a law steep enough to stop a gear divides by zero: the rule's record says so (an infinite radius fails its
    # rule, NaN is "not evaluated"); numpy's warning would only repeat it
    with np.errstate(divide="ignore", invalid="ignore"):
        angles = find_angles(spec, train, n)
        return rules_of(spec, train, angles, turn_grid(n), soil_samples), train, angles


# --- facts --------------------------------------------------------------------------------------------------------

def motion_facts(spec: RotaryPlanetarySpec, train: Train, angles: Angles, samples: int = 361) -> dict:
    """What the design does: the loop in the machine and ground frames with the claw's attitude, the laws, the
    pitch-curve ratios, the key poses reached; curves for the figures (from result.json alone)."""
    phi = np.linspace(0.0, 2.0 * math.pi, samples)
    x, y = tip(train, phi)
    w, v = omega(spec), forward_mm_s(spec)
    p1, p2 = pairs(train, phi)
    att = claw_attitude(train, phi) * DEG
    poses = {}
    for name, pose in spec.key_poses.items():
        a = angles.poses[name]
        px, py = tip(train, a)
        poses[name] = {"carrier_deg": a * DEG, "x": float(px), "y": float(py),
                       "miss_mm": math.hypot(float(px) - pose.x, float(py) - pose.y),
                       "attitude_deg": float(claw_attitude(train, a)) * DEG,
                       "target": {"x": pose.x, "y": pose.y, "attitude": pose.attitude}}
    _, y_top = tip(train, angles.top)
    _, y_bottom = tip(train, angles.bottom)
    soil = None
    if not angles.missing:
        xi, _ = tip(train, angles.entry)
        xo, _ = tip(train, angles.exit)
        soil = {"entry_carrier_deg": angles.entry * DEG, "exit_carrier_deg": angles.exit * DEG,
                "hole_width_mm": abs(float(xo - v * angles.exit / w) - float(xi - v * angles.entry / w))}
    return {
        "frame": "machine: origin on the carrier axis, x rearwards, y up; ground: x_ground = x_machine - V t, "
                 "t = carrier angle / omega; the carrier turns counter-clockwise",
        "carrier_speed_rad_s": w, "forward_speed_mm_s": v, "soil_y_mm": soil_y(spec),
        "plant_spacing_mm": plant_spacing(spec),
        "trajectory_height_mm": float(y_top - y_bottom), "planting_depth_mm": float(soil_y(spec) - y_bottom),
        "soil": soil, "poses": poses, "missing": angles.missing,
        "curves": {"carrier_deg": (phi * DEG).tolist(), "x": np.asarray(x).tolist(), "y": np.asarray(y).tolist(),
                   "x_ground": (x - v * phi / w).tolist(), "claw_attitude_deg": np.asarray(att).tolist(),
                   "pair1_ratio": np.asarray(p1.ratio[0]).tolist(), "pair2_ratio": np.asarray(p2.ratio[0]).tolist()},
    }


def trajectory(spec: RotaryPlanetarySpec, train: Train, samples: int = 361) -> dict:
    """One carrier turn of claw-tip samples (result.json's trajectory keys) from carrier angle 0, ground frame, the
    machine frame nested."""
    w, v = omega(spec), forward_mm_s(spec)
    phi = np.linspace(0.0, 2.0 * math.pi, samples)
    with np.errstate(divide="ignore", invalid="ignore"):
        x, y = tip(train, phi)
        dx, dy = tip_rate(train, phi)
        ddx, ddy = tip_curvature_rate(train, phi)
    t = phi / w
    return {"frame": "ground", "t": t.tolist(), "crank_deg": np.degrees(phi).tolist(),
            "x": (x - v * t).tolist(), "y": y.tolist(), "vx": (w * dx - v).tolist(), "vy": (w * dy).tolist(),
            "ax": (w * w * ddx).tolist(), "ay": (w * w * ddy).tolist(),
            "machine": {"x": x.tolist(), "y": y.tolist(), "vx": (w * dx).tolist(), "vy": (w * dy).tolist()}}


def facts(spec: RotaryPlanetarySpec, train: Train, angles: Angles) -> dict:
    with np.errstate(divide="ignore", invalid="ignore"):      # as in evaluate: the rules say it
        motion = motion_facts(spec, train, angles)
    return {"source": spec.source, "harmonics": {"planet": spec.harmonics[0], "idler": spec.harmonics[1]},
            "motion": motion}


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(RotaryPlanetarySpec, loaded.model)  # load_spec validated it with this kind's model
    design = spec.design_values()
    rules, train, angles = evaluate(spec, design, *check_grid(spec))
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], trajectory=trajectory(spec, train),
                  extra=facts(spec, train, angles))
