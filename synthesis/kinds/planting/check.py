"""``agrisynth check`` for kind planting_fourbar: evaluate the given design against every rule."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import cast

import numpy as np

from synthesis.constraints import Rule
from synthesis.constraints.poses import attitude_miss_deg
from synthesis.kinds.planting.kinematics import claw_attitudes, tip_state
from synthesis.dynamics.facts import peaks, turn
from synthesis.dynamics.linkage import FourbarDynamics, dynamics_facts
from synthesis.kinds.planting.dynamics import (JOINTS, LINKS, SoilContact, arm_dynamics, arm_linkage,
                                               unevaluated_arm_dynamics)
from synthesis.kinds.planting.rule_set import Trace, planting_rules
from synthesis.kinds.planting.scene import (POINTS, TWO_PI, PlantingScene, PrecisionPoints, assembly_status,
                                            find_precision_points, float_trace, locate_poses, pose_key, turn_scan)
from synthesis.core.kind import ResultTable, figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.planting.spec import PlantingFourbarSpec


#: the grid `check` evaluates on: samples of each acceleration phase and of a crank turn
CHECK_PHASE_SAMPLES = 400
CHECK_TURN_SAMPLES = 3600


def evaluate(scene: PlantingScene, limits, phase_samples: int = CHECK_PHASE_SAMPLES,
             turn_samples: int = CHECK_TURN_SAMPLES) -> tuple[list[Rule], PrecisionPoints | None]:
    """All rules of the scene; a crank that cannot complete a turn leaves the path rules unevaluated."""
    why = assembly_status(scene.design)   # raises AssemblyError if it never assembles
    if why is None:
        scan = turn_scan(scene.design, turn_samples)    # P5's search and the transmission rule: one pass of a turn
        pts = locate_poses(scene, find_precision_points(scene, scan=scan), turn_samples)
        trace = float_trace(scene, pts, phase_samples, turn_samples, scan=scan)
        return planting_rules(with_dynamics(scene, trace, pts), limits), pts
    return unevaluated(scene, limits, why), None


def soil_contact(scene: PlantingScene, pts: PrecisionPoints | None = None) -> SoilContact | None:
    """Where the claw meets the soil (the surface the precision points were found with, ``pts``'s or found here, and
    the forward speed in m/s), when the spec's [dynamics] table has a soil law; else None."""
    if scene.dynamics is None or getattr(scene.dynamics, "soil", None) is None:
        return None
    surface = (pts if pts is not None else find_precision_points(scene)).soil_level
    return SoilContact(surface, scene.motion.forward / 1000.0)


def with_dynamics(scene: PlantingScene, trace: Trace, pts: PrecisionPoints) -> Trace:
    """The trace with the dynamics rules' input when the spec's [dynamics] table sets a limit."""
    trace.dynamics = arm_dynamics(scene.dynamics, scene.design.parameters(), scene.design.branch, scene.motion.omega,
                                  scene.counterweight, scene.rocker_counterweight, soil_contact(scene, pts))
    return trace


def unevaluated(scene: PlantingScene, limits, why: str) -> list[Rule]:
    """The rules of a design whose crank cannot turn: only those of the link lengths evaluated."""
    nowhere = PrecisionPoints({n: None for n in POINTS}, None, {n: why for n in POINTS})
    trace = float_trace(scene, nowhere, turn_missing=why)
    trace.dynamics = unevaluated_arm_dynamics(scene.dynamics)
    return planting_rules(trace, limits)


def trajectory(scene: PlantingScene, pts: PrecisionPoints | None, samples: int = 361) -> dict | None:
    """One cycle of claw-tip samples (result.json's trajectory keys), ground frame, from soil exit P6 to the next P6."""
    if pts is None:
        return None
    m = scene.motion
    start = pts.theta["P6"] if pts.theta["P6"] is not None else 0.0
    theta = start + np.linspace(0.0, TWO_PI, samples)
    st = tip_state(scene.design, m, theta)
    t = (theta - start) / m.omega
    x_ground = st.pos[0] + m.forward * t
    return {
        "frame": "ground",
        "t": t.tolist(),
        "crank_deg": np.degrees(theta % TWO_PI).tolist(),
        "x": x_ground.tolist(), "y": st.pos[1].tolist(),
        "vx": (st.vel[0] + m.forward).tolist(), "vy": st.vel[1].tolist(),
        "ax": st.acc[0].tolist(), "ay": st.acc[1].tolist(),
        "machine": {"x": st.pos[0].tolist(), "y": st.pos[1].tolist(),
                    "vx": st.vel[0].tolist(), "vy": st.vel[1].tolist()},
    }


def precision_point_table(scene: PlantingScene, pts: PrecisionPoints | None) -> dict:
    """P1-P6 in both frames, on the trajectory's clock (t = 0 at the P6 that starts it)."""
    if pts is None:
        return {}
    m = scene.motion
    start = pts.theta["P6"] if pts.theta["P6"] is not None else 0.0
    table: dict[str, dict[str, bool | float | str | None]] = {}
    for n in POINTS:
        th = pts.theta[n]
        if th is None:
            table[n] = {"found": False, "why": pts.problems.get(n)}
            continue
        rel = (th - start) % TWO_PI
        if n == "P6":
            rel = TWO_PI   # the exit that ends this planting stroke
        st = tip_state(scene.design, m, th)
        table[n] = {"found": True, "crank_deg": math.degrees(th % TWO_PI), "t": rel / m.omega,
                    "x": float(st.pos[0, 0]), "y": float(st.pos[1, 0]),
                    "x_ground": float(st.pos[0, 0] + m.forward * rel / m.omega)}
    return table


def scene_facts(spec, scene: PlantingScene, pts: PrecisionPoints | None) -> dict:
    """The kind-specific part of result.json: operation, precision points, soil and seedbed."""
    seedbed = scene.seedbed
    return {
        "source": spec.source,
        "operation": {"forward_speed_m_s": spec.operation.forward_speed,
                      "crank_speed_rpm": spec.operation.crank_speed,
                      "plant_spacing_mm": scene.motion.forward * scene.motion.period},
        "precision_points": precision_point_table(scene, pts),
        "soil_level_mm": None if pts is None else pts.soil_level,
        "seedbed": {"x": seedbed.point[0], "y": seedbed.point[1], "tilt_deg": math.degrees(seedbed.tilt),
                    "thickness": seedbed.thickness, "seedling_height": seedbed.seedling_height},
        # rule limits the spec did not write, and how they follow from its inputs
        "rule_limits_from_inputs": spec.derived_limits(),
        **dynamics_facts_of(scene, spec.operation.crank_speed, pts),
        **key_pose_facts(scene, pts),
    }


#: what the planting arm's claw attitude is (result.json's facts.key_poses, the spec's [key_poses] attitude)
ATTITUDE_READING = ("direction of the claw arm A -> C (crank pin A to the claw tip C, rigid on the coupler), deg from "
                    "+X (forward) counter-clockwise, in (-180, 180]")


def key_pose_facts(scene: PlantingScene, pts: PrecisionPoints | None) -> dict:
    """``{"key_poses": ...}`` when the spec has a [key_poses] table (else nothing): the claw's attitude at each
    precision point found, and at each pose its crank angle, the tip and the claw there and their misses."""
    if not scene.key_poses:
        return {}
    d, m = scene.design, scene.motion
    points: dict[str, float | None] = {}
    poses: dict[str, dict] = {}
    if pts is not None:
        points = {n: None if pts.theta[n] is None else math.degrees(float(claw_attitudes(d, [pts.theta[n]])[0]))
                  for n in POINTS}
    for name, pose in scene.key_poses.items():
        target = {"x": pose.x, "y": pose.y, "tolerance": pose.tolerance, "attitude": pose.attitude,
                  "attitude_tolerance": pose.attitude_tolerance}
        theta = None if pts is None else pts.poses.get(name)
        if theta is None:
            why = ("the crank does not complete a turn" if pts is None
                   else pts.problems.get(pose_key(name), f"key pose {name} not located"))
            poses[name] = {"at": pose.at, "found": False, "why": why, "target": target}
            continue
        st = tip_state(d, m, theta)
        x, y = float(st.pos[0, 0]), float(st.pos[1, 0])
        attitude = math.degrees(float(claw_attitudes(d, [theta])[0]))
        poses[name] = {"at": pose.at, "found": True, "crank_deg": math.degrees(theta) % 360.0, "x": x, "y": y,
                       "miss_mm": None if pose.tip is None else math.hypot(x - pose.tip[0], y - pose.tip[1]),
                       "attitude_deg": attitude,
                       "attitude_miss_deg": (None if pose.attitude is None
                                             else float(attitude_miss_deg(attitude, pose.attitude))),
                       "target": target}
    return {"key_poses": {"attitude": ATTITUDE_READING, "claw_attitude_at_points_deg": points, "poses": poses}}


def dynamics_facts_of(scene: PlantingScene, crank_speed_rpm: float, pts: PrecisionPoints | None = None) -> dict:
    """``{"dynamics": ...}``: the arm's inverse dynamics over a turn (docs/ARCHITECTURE.md "result.json"), when the
    spec has a [dynamics] table and the crank turns; else nothing.  ``pts``: the precision points found, whose soil
    surface the soil law reads (found here when not given)."""
    if scene.dynamics is None or assembly_status(scene.design) is not None:
        return {}
    d = scene.design
    contact = soil_contact(scene, pts)
    linkage = arm_linkage(scene.dynamics, d.parameters(), d.branch, scene.motion.omega, scene.counterweight,
                          scene.rocker_counterweight, contact)
    facts = dynamics_facts(linkage, scene.dynamics.samples, JOINTS, LINKS, crank_speed_rpm, scene.dynamics)
    if contact is not None:
        with_soil_facts(facts, linkage, scene.dynamics, contact)
    return {"dynamics": facts}


#: the soil law on the claw as result.json states it
SOIL_MODEL = ("while the claw tip C is below the soil surface (depth d > 0, mm): magnitude f0 + k d, opposing C's "
              "velocity relative to the soil (the machine travelling forward, +X, at the forward speed), the "
              "direction blended to zero below 1 mm/s; zero above the surface")


def with_soil_facts(facts: dict, linkage: FourbarDynamics, table, contact: SoilContact) -> None:
    """``facts`` (:func:`synthesis.dynamics.linkage.dynamics_facts`) with the soil on the claw, as the tillage kind
    writes it: in ``external_loads`` the law, the force at each sample (``force_N``, N x 2), C's depth below the
    surface (``depth_mm``, negative above it) and the loads' power with the soil's (``external_power_W``, so the
    energy balance closes from the file); in the summary the peak soil force, the soil force's mean power through the
    crank (``mean_soil_power_W``: F . v_C in the machine frame, negative: the motor supplies it) and the mean power
    the soil dissipates (``mean_soil_dissipation_W``: -F . v_rel in the ground frame, v_rel = v_C + the forward speed;
    the tractor's drawbar supplies the difference, -F_x x the forward speed)."""
    crank = turn(table.samples)
    out = linkage.over_turn(crank)
    without = replace(linkage, soil=None).over_turn(crank)          # the constant loads' power alone
    given = facts["external_loads"]["loads"] if facts["external_loads"] else []
    soil = {"name": "soil force on the claw tip C", "link": "coupler", "at": "tip", "model": SOIL_MODEL,
            "surface_y_mm": float(contact.surface), "forward_speed_m_s": float(contact.forward_speed),
            **table.soil.model_dump()}
    facts["external_loads"] = {"loads": [*given, soil], "external_power_W": out["external_power"].tolist(),
                               "force_N": out["soil_force"].T.tolist(), "depth_mm": out["soil_depth"].tolist()}
    # through the crank, machine frame: F . v_C
    through_crank = float(np.mean(out["external_power"] - without["external_power"]))
    # in the soil, ground frame: -F . (v_C + v_f), the rest of it the drawbar's -F_x v_f
    dissipated = -(through_crank + float(contact.forward_speed) * float(np.mean(out["soil_force"][0])))
    facts["summary"] |= {"soil_force_N": peaks(np.hypot(*out["soil_force"]), crank),
                         "mean_soil_power_W": through_crank, "mean_soil_dissipation_W": dissipated}


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(PlantingFourbarSpec, loaded.model)  # load_spec validated it with this kind's model
    scene = PlantingScene.from_spec(spec)
    rules, pts = evaluate(scene, spec.rules)
    records = [r.record().to_json() for r in rules]
    design = dict(spec.design_values())
    design["branch"] = spec.arm.branch
    return Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
        design=design, rules=records, trajectory=trajectory(scene, pts),
        extra=scene_facts(spec, scene, pts),
    )


#: the rules of the precision points P1-P6 a planting engineer reads first, in the table's order
POINT_RULES = ("p1p3_distance", "p2p3_distance", "p1p2p3_collinearity", "entry_angle", "planting_depth",
               "p4p6_distance", "p2_speed")


def headline(result: Result) -> list[str]:
    """Entry angle, planting depth and hole (P4-P6), the seedling pick (P1-P3), and which point rules miss and by how
    much, from result.json's rules and facts."""
    rules = {r["name"]: r for r in result.rules}

    def value(name: str) -> str:
        rule = rules.get(name) or {}
        return figure_text(rule.get("value"), rule.get("unit", ""))

    points = (result.extra or {}).get("precision_points") or {}
    lines = [f"entry angle {value('entry_angle')}, planting depth {value('planting_depth')}, hole P4-P6 "
             f"{value('p4p6_distance')}",
             f"pick: P1-P3 {value('p1p3_distance')}, P2-P3 {value('p2p3_distance')}, P1-P2-P3 off line "
             f"{value('p1p2p3_collinearity')}, P2 speed {value('p2_speed')}"]
    lost = [name for name, p in points.items() if isinstance(p, dict) and not p.get("found", True)]
    if lost:
        lines.append(f"not found on the path: {', '.join(lost)}")
    failed = [name for name in POINT_RULES if name in rules and not rules[name].get("satisfied")]
    misses = [f"{name} by {figure_text(-rules[name]['margin'], rules[name].get('unit', ''))}"
              if rules[name].get("margin") is not None else f"{name} not evaluated" for name in failed]
    lines.append(f"P1-P6 misses: {'; '.join(misses)}" if misses else "P1-P6: every point rule holds")
    return lines + pose_headline((result.extra or {}).get("key_poses") or {}, rules)


def pose_headline(facts: dict, rules: dict) -> list[str]:
    """A line per key pose: where it is read, the claw's attitude and the tip there against the targets, and which
    of its rules miss (none without a [key_poses] table)."""
    lines = []
    for name, pose in (facts.get("poses") or {}).items():
        where = f" at {pose['at']}" if pose.get("at") else ""
        if not pose.get("found"):
            lines.append(f"pose {name}{where}: not read ({pose.get('why')})")
            continue
        target, parts = pose.get("target") or {}, []
        if target.get("attitude") is not None:
            parts.append(f"attitude {pose['attitude_deg']:.1f} deg, {pose['attitude_miss_deg']:+.2f} deg from "
                         f"{target['attitude']:g} (within {target['attitude_tolerance']:g})")
        if pose.get("miss_mm") is not None:
            parts.append(f"tip {pose['miss_mm']:.2f} mm from ({target['x']:g}, {target['y']:g}) (within "
                         f"{target['tolerance']:g})")
        missed = [n for n in (f"pose_{name}", f"pose_{name}_attitude")
                  if n in rules and not rules[n].get("satisfied")]
        lines.append(f"pose {name}{where}: {'; '.join(parts)}" + (f" -- MISSED ({', '.join(missed)})" if missed else ""))
    return lines


def result_tables(result: Result) -> list[ResultTable]:
    """The key poses (none without a [key_poses] table): each one's target and the claw where it is read."""
    poses = (((result.extra or {}).get("key_poses") or {}).get("poses")) or {}
    if not poses:
        return []
    rows = tuple((name, p.get("at") or "-", p.get("crank_deg"), p["target"]["attitude"], p.get("attitude_deg"),
                  p.get("attitude_miss_deg"), p["target"]["x"], p["target"]["y"], p.get("x"), p.get("y"),
                  p.get("miss_mm")) for name, p in poses.items())
    return [ResultTable("Key poses: target and the claw where the pose is read (attitude: claw arm A -> C)", (
        "pose", "at", "crank angle, deg", "target attitude, deg", "attitude, deg", "attitude miss, deg",
        "target x, mm", "target y, mm", "x, mm", "y, mm", "tip miss, mm"), rows)]
