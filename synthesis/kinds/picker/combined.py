"""Kind ``picker``: the crank-rocker AEFG driving the double crank ABCD (seed 001 Fig. 3), over one turn.

The rocker AE is rigidly joined to the crank AB at the common pivot A, so AB turns by exactly what AE
turns: phi1(t) = phi10 + m (beta(phi7(t)) - beta_pick), where beta is the rocker angle of the
crank-rocker (its own frame), phi7 the crank angle of GF turning at the constant crank speed and
m = +-1 the sense in which the rocker is mounted (read from which way AB must swing).  The clamp
point M(t) = M_dc(phi1(t)); its velocity and acceleration are exact (AD through the chain).

Readings (problems/picker/PICKER.md): t = 0 when the rocker is at its picking extreme
(``installation.picking_extreme``); the crank turns in the sense that makes the picking -> dropping
stroke the ``installation.holding_stroke`` one; theta1 is the angle G-A-E at the picking extreme (a
property of the crank-rocker, checked against the published value) and theta2 the direction of the
frame A -> G from the +x axis, which only places the crank-rocker in the drawing.

With a ``[key_poses]`` table the clamp's attitude (the direction of the clamp arm C -> M, the double crank's) and
position are asked at the picking or dropping instant, at an angle of the crank GF, or where the clamp point comes
nearest a target over a turn: the rules ``pose_<name>`` and ``pose_<name>_attitude`` of the double crank's poses
(synthesis/kinds/picker/poses.py), on the combined motion.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Protocol, cast

import casadi as ca
import numpy as np
from scipy.optimize import brentq

from synthesis.constraints.base import Rule
from synthesis import kinds
from synthesis.spec.design_info import describe_fixed, describe_part
from synthesis.errors import AssemblyError, SpecError
from synthesis.kinematics.rocker_drive import CrankRocker, quick_return, rocker_function
from synthesis.kinematics.rocker_drive import joints as crank_rocker_joints
from synthesis.constraints.poses import nearest_row
from synthesis.kinds.picker.kinematics.linkage import DoubleCrank, attitude_function, clamp_point, joint_positions
from synthesis.kinds.picker import check as double_crank_check
from synthesis.kinds.picker.combined_dynamics import dynamics_facts, dynamics_rules, picker_dynamics
from synthesis.kinds.picker.poses import PoseReading, free_target, pose_rules, reading_facts
from synthesis.kinds.picker.spec import CLAMP_ATTITUDE, Installation, PickerDoubleCrankSpec, PickerSpec
from synthesis.result import Result
from synthesis.spec import LoadedSpec, load_spec

TWO_PI = 2.0 * math.pi
TRAJECTORY_SAMPLES = 361
ANIMATION_FRAMES = 40
#: instants over a turn on which a free key pose's nearest point is looked for (then refined to the root of the
#: nearest-point row between the neighbours of the nearest sample)
POSE_SEARCH_SAMPLES = 3600


class CrankRockerPart(Protocol):
    """What the picker reads of its drive's spec, a crank_rocker one (that kind's model, which this kind does not
    import: kinds know nothing of each other)."""

    name: str
    branch: int

    def design_values(self) -> dict[str, float]: ...


@dataclass(frozen=True)
class Drive:
    """The combined mechanism, fixed numbers only (SI angles in rad, lengths mm, omega rad/s)."""

    cr: CrankRocker
    dc: DoubleCrank
    phi10: float          # rad, AB from AD at the picking instant
    omega: float          # crank GF speed, rad/s
    phi_pick: float       # crank angle (crank-rocker frame) at picking
    phi_drop: float
    beta_pick: float      # rocker angle (crank-rocker frame) at picking
    beta_drop: float
    sense: int            # +1: phi7 increases with time
    mount: int            # +1: AB turns the way beta does; -1: the crank-rocker is mounted mirrored
    holding_angle: float  # crank angle of the picking -> dropping stroke, rad
    theta2: float         # direction of A -> G in the machine frame, rad

    @property
    def period(self) -> float:
        return TWO_PI / self.omega

    @property
    def swing(self) -> float:
        return abs(self.beta_drop - self.beta_pick)


def make_drive(spec: PickerSpec, cr: CrankRocker, dc: DoubleCrank, phi10_deg: float) -> Drive:
    inst = spec.installation
    q = quick_return(cr)
    ex = q.extremes
    if inst.picking_extreme == "folded":
        phi_pick, phi_drop, b_pick, b_drop = ex.phi_folded, ex.phi_extended, ex.beta_folded, ex.beta_extended
    else:
        phi_pick, phi_drop, b_pick, b_drop = ex.phi_extended, ex.phi_folded, ex.beta_extended, ex.beta_folded
    b_drop = b_pick + math.remainder(b_drop - b_pick, TWO_PI)
    ahead = (phi_drop - phi_pick) % TWO_PI            # crank angle to the drop turning with +phi
    want_short = inst.holding_stroke == "quick"
    sense = 1 if (ahead <= math.pi) == want_short else -1
    holding = ahead if sense > 0 else TWO_PI - ahead
    mount = 1 if b_drop > b_pick else -1              # AB must swing from phi10 towards phi10 + psi
    return Drive(cr, dc, math.radians(phi10_deg), spec.operation.crank_speed * TWO_PI / 60.0, phi_pick, phi_drop,
                 b_pick, b_drop, sense, mount, holding, math.radians(inst.theta2))


def clamp_motion(drive: Drive) -> ca.Function:
    """t -> (M, dM/dt, d2M/dt2, phi1, phi7): exact by AD through crank-rocker and double crank."""
    t = ca.SX.sym("t")
    phi7 = drive.phi_pick + drive.sense * drive.omega * t
    beta = rocker_function(drive.cr.branch)(phi7, drive.cr.parameters())[0]
    phi1 = drive.phi10 + drive.mount * (beta - drive.beta_pick)
    m = ca.vertcat(*clamp_point(phi1, drive.dc.parameters(), drive.dc.branch))
    v = ca.jacobian(m, t)
    a = ca.jacobian(v, t)
    return ca.Function("clamp_motion", [t], [m, v, a, phi1, phi7], ["t"], ["M", "V", "A", "phi1", "phi7"])


def states(drive: Drive, t) -> dict[str, np.ndarray]:
    t = np.atleast_1d(np.asarray(t, dtype=float))
    m, v, a, phi1, phi7 = (np.asarray(x) for x in clamp_motion(drive).map(t.size)(t.reshape(1, -1)))
    return {"M": m.reshape(2, -1), "V": v.reshape(2, -1), "A": a.reshape(2, -1), "phi1": phi1.ravel(),
            "phi7": phi7.ravel()}


def machine_joints(drive: Drive, phi1: float, phi7: float) -> dict[str, list[float]]:
    """Every joint in the machine frame at crank angles phi1 (AB) and phi7 (GF), rad: A, B, C, D, M of
    the double crank and G, F, E of the drive.

    The crank-rocker's own frame (G origin, A on +x) is mirrored when ``mount`` = -1 and turned so that
    A -> G points along theta2, then A is put on the double crank's pivot.
    """
    joints = joint_positions(drive.dc, math.degrees(phi1))
    cr = crank_rocker_joints(drive.cr, phi7)
    a_int = np.array(cr["A"])
    rot = drive.theta2 - math.pi
    c, sn = math.cos(rot), math.sin(rot)
    a_m = np.array(joints["A"])
    for name in ("G", "F", "E"):
        dx, dy = np.array(cr[name]) - a_int
        dy *= drive.mount
        joints[name] = [float(a_m[0] + c * dx - sn * dy), float(a_m[1] + sn * dx + c * dy)]
    return joints


def _prefixed(prefix: str, rules: list[Rule]) -> list[dict]:
    out = []
    for r in rules:
        rec = r.record()
        out.append(dataclasses.replace(rec, name=f"{prefix}.{rec.name}").to_json())
    return out


def _load_part(loaded: LoadedSpec, field: str, kind: str) -> LoadedSpec:
    path = cast(PickerSpec, loaded.model).part_path(loaded.path, field)     # load_spec validated the picker spec
    try:
        part = load_spec(path)
    except SpecError as exc:
        raise SpecError(f"picker.{field}: {exc}") from None
    if part.kind != kind:
        raise SpecError(f"picker.{field}: {path} is a {part.kind!r} spec, expected kind {kind!r}")
    return part


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(PickerSpec, loaded.model)       # load_spec validated it with this kind's model
    cr_loaded = _load_part(loaded, "crank_rocker", "crank_rocker")
    dc_loaded = _load_part(loaded, "double_crank", "picker_double_crank")
    # _load_part has made sure of each part's kind, whose model load_spec validated it with
    cr_spec, dc_spec = cast(CrankRockerPart, cr_loaded.model), cast(PickerDoubleCrankSpec, dc_loaded.model)
    v = cr_spec.design_values()
    cr = CrankRocker(v["l7"], v["l8"], v["l9"], v["l10"], cr_spec.branch)
    dc = double_crank_check.linkage(dc_spec)
    # the drive's rules are the crank-rocker kind's own check of its part spec (the registry's public contract,
    # so the two kinds stay independent modules)
    rules = [{**r, "name": f"crank_rocker.{r['name']}"} for r in kinds.get("crank_rocker").check(cr_loaded).rules]
    try:
        rules += _prefixed("double_crank", double_crank_check.evaluate(dc_spec, dc))
    except AssemblyError as exc:
        raise AssemblyError(f"picker.double_crank: {dc_loaded.path}: {exc}") from None
    if not cr.crank_turns():
        raise AssemblyError(f"picker.crank_rocker: {cr_loaded.path}: the crank cannot make a full turn, so the "
                            f"picker has no cycle (Grashof slacks {cr.grashof_slacks()} mm)")
    drive = make_drive(spec, cr, dc, dc_spec.drive.start)
    inst = spec.installation
    theta1 = math.degrees(abs(math.remainder(math.pi - drive.beta_pick, TWO_PI)))
    rules.append(Rule("drive_swing", math.degrees(drive.swing), dc_spec.drive.swing - inst.swing_tolerance,
                      dc_spec.drive.swing + inst.swing_tolerance, "deg", 1.0,
                      "rocker AE swing = crank AB swing").record().to_json())
    rules.append(Rule("installation_theta1", theta1, inst.theta1 - inst.theta1_tolerance,
                      inst.theta1 + inst.theta1_tolerance, "deg", 1.0,
                      f"angle G-A-E at the {inst.picking_extreme} extreme").record().to_json())

    period = drive.period
    t = np.linspace(0.0, period, TRAJECTORY_SAMPLES)
    s = states(drive, t)
    instants = {"picking": 0.0, "dropping": drive.holding_angle / drive.omega, "picking_again": period}
    poses = pose_readings(spec, drive, instants)
    rules += [r.record().to_json() for r in pose_rules([reading for reading, _ in poses])]
    rules += [r.record().to_json() for r in dynamics_rules_of(spec, drive)]
    instant_table = _instant_table(spec, dc_spec, drive, instants)
    speeds = np.hypot(*s["V"]) / 1000.0
    ab = np.degrees(s["phi1"])
    frames_t = np.linspace(0.0, period, ANIMATION_FRAMES, endpoint=False)
    frames = states(drive, frames_t)
    design, described = _design_of(spec, cr_loaded, dc_loaded)
    return Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design, rules=rules,
        design_variables=described,
        trajectory={"frame": "machine", "point": "clamp point M",
                    "note": "t = 0 at picking; crank_deg = angle turned by the crank GF since picking",
                    "t": t.tolist(), "crank_deg": np.degrees(drive.omega * t).tolist(),
                    "x": s["M"][0].tolist(), "y": s["M"][1].tolist(), "vx": s["V"][0].tolist(),
                    "vy": s["V"][1].tolist(), "ax": s["A"][0].tolist(), "ay": s["A"][1].tolist(),
                    "crank_ab_deg": ab.tolist(), "speed_m_s": speeds.tolist()},
        extra={
            "source": spec.source,
            "parts": {"crank_rocker": {"path": str(cr_loaded.path), "sha256": cr_loaded.sha256, "name": cr_spec.name},
                      "double_crank": {"path": str(dc_loaded.path), "sha256": dc_loaded.sha256, "name": dc_spec.name}},
            "operation": {"crank_speed_rpm": spec.operation.crank_speed, "period_s": period},
            "instants": instant_table,
            "holding": {"stroke": inst.holding_stroke, "crank_angle_deg": math.degrees(drive.holding_angle),
                        "time_s": instants["dropping"], "return_time_s": period - instants["dropping"]},
            "peak_speed_m_s": float(speeds.max()),
            "peak_speed_t": float(t[int(np.argmax(speeds))]),
            "crank_ab_range_deg": [float(ab.min()), float(ab.max())],
            "installation": _installation_facts(inst, dc_spec, drive, theta1),
            "target_arc": double_crank_check.facts(dc_spec, dc)["target_arc"],
            "frames": [{"t": float(ft), "joints": machine_joints(drive, float(a), float(c))}
                       for ft, a, c in zip(frames_t, frames["phi1"], frames["phi7"])],
            **key_pose_facts(spec, drive, instants, poses),
            **dynamics_of(spec, drive),
        },
    )


def dynamics_rules_of(spec: PickerSpec, drive: Drive) -> list[Rule]:
    """The ``[dynamics.limits]`` rules on the check's grid of a turn (none without a [dynamics] table or a limit)."""
    return [] if spec.dynamics is None else dynamics_rules(picker_dynamics(spec.dynamics, drive), spec.dynamics)


def dynamics_of(spec: PickerSpec, drive: Drive) -> dict:
    """``{"dynamics": facts.dynamics}`` over a turn of the crank GF at [dynamics] samples instants, or nothing without
    a [dynamics] table."""
    if spec.dynamics is None:
        return {}
    return {"dynamics": dynamics_facts(picker_dynamics(spec.dynamics, drive), spec.dynamics,
                                       spec.operation.crank_speed)}


def pose_instant(drive: Drive, target: tuple[float, float], samples: int = POSE_SEARCH_SAMPLES) -> float:
    """The instant (s, in [0, period)) where the clamp point comes nearest ``target`` (mm) over a turn: the nearest
    of ``samples`` instants, then the root of (M - target) . dM/dt between its neighbours (the shared nearest-point
    row, synthesis.constraints.poses.nearest_row).  The clamp passes each point of its path twice a turn in the same pose
    (AB swings there and back): the first nearest sample is taken."""
    grid = np.linspace(0.0, drive.period, samples, endpoint=False)
    m = states(drive, grid)["M"]
    k = int(np.argmin((m[0] - target[0]) ** 2 + (m[1] - target[1]) ** 2))
    motion = clamp_motion(drive)

    def row(tt: float) -> float:
        pos, vel = (np.asarray(v, dtype=float).ravel() for v in motion(tt)[:2])
        return float(nearest_row(pos[0] - target[0], pos[1] - target[1], vel[0], vel[1]))

    h = grid[1]
    lo, hi = grid[k] - h, grid[k] + h
    found = brentq(row, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps) if row(lo) < 0.0 < row(hi) else grid[k]
    return float(found) % drive.period


def pose_readings(spec: PickerSpec, drive: Drive, instants: dict[str, float]) -> list[tuple[PoseReading, float]]:
    """(the clamp at each key pose, its instant in s): at the picking or dropping instant, at the prescribed angle of
    the crank GF since picking, or where the clamp point comes nearest its target (:func:`pose_instant`)."""
    if not spec.key_poses:
        return []
    attitude, p = attitude_function(drive.dc.branch), drive.dc.parameters()
    out = []
    for name, pose in spec.key_poses.items():
        if pose.at is not None:
            tt = instants[pose.at]
        elif pose.crank_angle is not None:
            tt = math.radians(pose.crank_angle) / drive.omega
        else:
            tt = pose_instant(drive, free_target(pose))
        at = states(drive, [tt])
        phi1 = float(at["phi1"][0])
        out.append((PoseReading(name, pose, phi1, (float(at["M"][0, 0]), float(at["M"][1, 0])),
                                float(attitude(phi1, p)), pose.at), tt))
    return out


def key_pose_facts(spec: PickerSpec, drive: Drive, instants: dict[str, float],
                   poses: list[tuple[PoseReading, float]]) -> dict:
    """``{"key_poses": ...}`` when the spec has a [key_poses] table (else nothing): the clamp's attitude at picking
    and dropping, and at each pose its instant, the crank angles GF and AB, the clamp point and the attitude there and
    their misses."""
    if not spec.key_poses:
        return {}
    attitude, p = attitude_function(drive.dc.branch), drive.dc.parameters()
    at = states(drive, [instants["picking"], instants["dropping"]])
    points = {name: math.degrees(float(attitude(float(phi1), p))) for name, phi1 in zip(("picking", "dropping"),
                                                                                        at["phi1"])}
    return {"key_poses": {
        "attitude": CLAMP_ATTITUDE, "clamp_attitude_at_instants_deg": points,
        "poses": {r.name: reading_facts(r, {"t": tt, "crank_deg": math.degrees(drive.omega * tt),
                                            "crank_ab_deg": math.degrees(r.angle)}) for r, tt in poses}}}


def _instant_table(spec: PickerSpec, dc_spec: PickerDoubleCrankSpec, drive: Drive,
                   instants: dict[str, float]) -> dict:
    """The clamp point at picking, dropping and picking again: where it is, how fast, how far from its target."""
    at = states(drive, list(instants.values()))
    speed = np.hypot(*at["V"]) / 1000.0
    targets = {"picking": dc_spec.target.m1, "dropping": dc_spec.target.m2, "picking_again": dc_spec.target.m1}
    instant_table = {}
    for k, (name, tt) in enumerate(instants.items()):
        mx, my = at["M"][:, k]
        tx, ty = targets[name]
        instant_table[name] = {"t": tt, "speed_m_s": float(speed[k]), "x": float(mx), "y": float(my),
                               "crank_ab_deg": math.degrees(float(at["phi1"][k])),
                               "distance_to_target_mm": float(math.hypot(mx - tx, my - ty))}
    if spec.published.instants is not None:
        for name, tp in zip(instants, spec.published.instants):
            instant_table[name]["published_t"] = tp
    return instant_table


def _design_of(spec: PickerSpec, cr_loaded: LoadedSpec, dc_loaded: LoadedSpec) -> tuple[dict, dict]:
    """The picker's design (both parts' variables, prefixed, and the installation angles) and its description."""
    # the parts run_check loaded: _load_part has made sure of their kinds
    cr_spec, dc_spec = cast(CrankRockerPart, cr_loaded.model), cast(PickerDoubleCrankSpec, dc_loaded.model)
    inst = spec.installation
    design = {f"crank_rocker.{k}": v for k, v in cr_spec.design_values().items()}
    design.update({f"double_crank.{k}": v for k, v in dc_spec.design_values().items()})
    design["double_crank.branch"] = dc_spec.linkage.branch      # as the double crank's own check writes it
    design.update({"theta1": inst.theta1, "theta2": inst.theta2})
    described = describe_part("crank_rocker", cr_loaded.model, str(cr_loaded.path))
    described.update(describe_part("double_crank", dc_spec, str(dc_loaded.path)))
    described.update(describe_fixed(spec, {"theta1": "installation.theta1", "theta2": "installation.theta2"}))
    return design, described


def _installation_facts(inst: Installation, dc_spec: PickerDoubleCrankSpec, drive: Drive, theta1: float) -> dict:
    ae_pick = math.degrees(drive.theta2) + math.degrees(drive.mount * (drive.beta_pick - math.pi))
    return {"picking_extreme": inst.picking_extreme, "theta1_published_deg": inst.theta1,
            "theta1_computed_deg": theta1, "theta2_deg": inst.theta2,
            "crank_sense": "counter-clockwise" if drive.sense * drive.mount > 0 else "clockwise",
            "rocker_mounted_mirrored": drive.mount < 0,
            "rocker_ae_at_picking_deg": ae_pick % 360.0,
            "joint_angle_ab_minus_ae_deg": math.remainder(
                dc_spec.drive.start - dc_spec.design_values()["phi3"] - ae_pick, 360.0)}


