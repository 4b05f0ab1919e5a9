"""``agrisynth check`` for kind picker_double_crank: the arc error (eq 4) and the rules of eq 5-7.

The target points lie evenly by arc length on the picking arc; the crank angles are evenly spaced over
the working swing, the i-th point paired with the i-th angle (M1 at phi10).  Rules: Grashof double
crank with the frame AD shortest (eq 5-6), x_A > 0 (eq 7) and the transmission angle at C over the
working swing; with ``[rules] max_arc_error`` the largest miss of a target point, with a ``[dynamics]`` table's
limits the peak input torque, shaking force or moment over the working swing (synthesis/kinds/picker/dynamics.py),
and with a ``[key_poses]`` table the clamp's attitude and position at each pose (synthesis/kinds/picker/poses.py).
The arc error is the objective of ``solve`` (unless a min-peak objective is); ``check`` reports it in ``arc_error``.
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np

from synthesis.constraints import Rule
from synthesis.constraints.grashof import grashof_double_crank_rule
from synthesis.kinds.picker.dynamics import double_crank_dynamics, dynamics_facts, dynamics_rules
from synthesis.kinds.picker.rules import arc_error_rule, frame_point_rule
from synthesis.constraints.transmission import acute_transmission_rule
from synthesis.errors import AssemblyError
from synthesis.kinds.picker.kinematics.arc import arc_through, points_on_arc
from synthesis.kinds.picker.kinematics.linkage import (DoubleCrank, assembles, clamp_states, closure_height_sq,
                                                   joint_positions)
from synthesis.kinds.picker.poses import float_poses, key_pose_facts, pose_headline, pose_rules
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.picker.spec import PickerDoubleCrankSpec

#: crank angles over the working swing in ``check`` (transmission angle)
CHECK_SAMPLES = 2001


def linkage(spec: PickerDoubleCrankSpec, values: dict[str, float] | None = None) -> DoubleCrank:
    v = spec.design_values() if values is None else values
    return DoubleCrank(v["x_a"], v["y_a"], v["l1"], v["l2"], v["l3"], v["l4"], v["l5"], v["phi3"], v["phi4"],
                       spec.linkage.branch)


def target_points(spec: PickerDoubleCrankSpec) -> np.ndarray:
    t = spec.target
    return points_on_arc(t.m1, t.m2, t.tangent_from_vertical, t.points)


def target_angles(spec: PickerDoubleCrankSpec) -> np.ndarray:
    """Crank angles (deg) paired with the target points: phi10 + psi * i / (n - 1)."""
    d = spec.drive
    return d.start + d.swing * np.linspace(0.0, 1.0, spec.target.points)


def swing_angles(spec: PickerDoubleCrankSpec, samples: int) -> np.ndarray:
    d = spec.drive
    return d.start + d.swing * np.linspace(0.0, 1.0, samples)


def require_assembly(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> None:
    angles = swing_angles(spec, 721)
    if not assembles(dc, angles):
        bad = [a for a in angles if closure_height_sq(dc, math.radians(a)) <= 0]
        raise AssemblyError(
            f"picker_double_crank.linkage: the double crank cannot assemble between crank angles {min(bad):.1f} "
            f"and {max(bad):.1f} deg of its working swing (triangle BCD does not close with l1 = {dc.l1:g}, "
            f"l2 = {dc.l2:g}, l3 = {dc.l3:g}, l4 = {dc.l4:g} mm)")


def arc_error(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> dict:
    """Eq (4) (sum of distances), RMS and max of |M(phi_i) - target_i|, and every pair."""
    targets = target_points(spec)
    angles = target_angles(spec)
    m = clamp_states(dc, angles)["M"]
    d = np.hypot(m[0] - targets[:, 0], m[1] - targets[:, 1])
    t = spec.target
    centre, radius, _, _ = arc_through(t.m1, t.m2, t.tangent_from_vertical)
    path = clamp_states(dc, swing_angles(spec, 501))["M"]
    off_arc = np.abs(np.hypot(path[0] - centre[0], path[1] - centre[1]) - radius)
    return {"eq4_sum_mm": float(d.sum()), "rms_mm": float(np.sqrt(np.mean(d * d))), "max_mm": float(d.max()),
            "sum_of_squares_mm2": float(np.sum(d * d)),
            # the shape alone: how far the path over the swing strays from the arc's circle, ignoring timing
            "path_off_circle_max_mm": float(off_arc.max()),
            "points": [{"crank_deg": float(a), "x": float(mx), "y": float(my), "target_x": float(tx),
                        "target_y": float(ty), "distance": float(di)}
                       for a, mx, my, (tx, ty), di in zip(angles, m[0], m[1], targets, d)]}


def evaluate(spec: PickerDoubleCrankSpec, dc: DoubleCrank, samples: int = CHECK_SAMPLES) -> list[Rule]:
    """Every rule of the spec; raises AssemblyError when the loop breaks inside the working swing."""
    require_assembly(spec, dc)
    mu = clamp_states(dc, swing_angles(spec, samples))["mu"]
    misses = clamp_states(dc, target_angles(spec))["M"] - target_points(spec).T
    return rules_of(spec, dc.x_a, dc.l1, dc.l2, dc.l3, dc.l4, mu, tuple(float(v) for v in dc.parameters()), misses,
                    float_poses(spec, dc))


def rules_of(spec: PickerDoubleCrankSpec, x_a, l1, l2, l3, l4, mu, p=None, misses=None, poses=None) -> list[Rule]:
    """Every rule of the spec on a trace of floats or CasADi symbols: pivot A's x, the links l1..l4 (l4 the
    frame AD), the transmission angles at C (deg) over the working swing, the parameters p (PARAMETERS: mm, rad),
    the misses (2 x targets, clamp point - target, mm) and the clamp at each key pose (synthesis/kinds/picker/poses.py
    PoseReading).  Used by check, the NLP and the re-check.  p, the misses and the poses are read only by the rules a
    spec adds ([rules] max_arc_error, [dynamics.limits], [key_poses]): without them the list is eq (5)-(7) and the
    transmission angle, as it always was."""
    rules = [grashof_double_crank_rule(l4, l1, l2, l3),
             frame_point_rule(x_a, spec.rules.x_a_min),
             acute_transmission_rule(mu, spec.rules.min_transmission_angle, "at C, over the working swing")]
    if spec.rules.max_arc_error is not None:
        rules.append(arc_error_rule(misses[0, :].T, misses[1, :].T, spec.rules.max_arc_error))
    if spec.dynamics is not None and spec.dynamics.has_rules():
        # sampled on the transmission angle's grid (the solver's samples, the check's, the re-check's)
        crank = np.radians(swing_angles(spec, mu.numel() if hasattr(mu, "numel") else len(mu)))
        rules += dynamics_rules(double_crank_dynamics(spec.dynamics, p, spec.linkage.branch), spec.dynamics.limits,
                                crank)
    return rules + pose_rules(poses or [])


def facts(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> dict:
    """arc error, the path over the working swing and a full turn, linkage drawings, the target arc."""
    t = spec.target
    centre, radius, start, sweep = arc_through(t.m1, t.m2, t.tangent_from_vertical)
    swing = swing_angles(spec, 201)
    full = np.linspace(0.0, 360.0, 361)
    m_swing = clamp_states(dc, swing)["M"]
    full_ok = [a for a in full if assembles(dc, [a])]
    m_full = clamp_states(dc, full_ok)["M"] if full_ok else np.zeros((2, 0))
    mu = clamp_states(dc, swing)["mu"]
    return {
        "source": spec.source,
        "branch": spec.linkage.branch,
        "arc_error": arc_error(spec, dc),
        "target_arc": {"m1": list(t.m1), "m2": list(t.m2), "tangent_from_vertical_deg": t.tangent_from_vertical,
                       "centre": [float(centre[0]), float(centre[1])], "radius": float(radius),
                       "start_deg": math.degrees(start), "sweep_deg": math.degrees(sweep)},
        "drive": {"start_deg": spec.drive.start, "swing_deg": spec.drive.swing},
        "grashof": {"slacks_mm": [float(s) for s in dc.grashof_slacks()],
                    "frame_shortest": bool(dc.l4 <= min(dc.l1, dc.l2, dc.l3)),
                    "double_crank": bool(min(dc.grashof_slacks()) >= 0.0)},
        "path": {"crank_deg": swing.tolist(), "x": m_swing[0].tolist(), "y": m_swing[1].tolist(),
                 "transmission_deg": mu.tolist()},
        "coupler_curve": {"crank_deg": full_ok, "x": m_full[0].tolist(), "y": m_full[1].tolist()},
        "positions": [{"crank_deg": float(a), "joints": joint_positions(dc, float(a))} for a in target_angles(spec)],
        **dynamics_of(spec, dc),
        **key_pose_facts(spec, dc),
    }


def dynamics_of(spec: PickerDoubleCrankSpec, dc: DoubleCrank) -> dict:
    """``{"dynamics": facts.dynamics}`` over the working swing at the table's ``samples`` crank angles (ends
    included), or nothing without a [dynamics] table."""
    if spec.dynamics is None:
        return {}
    dyn = double_crank_dynamics(spec.dynamics, tuple(float(v) for v in dc.parameters()), dc.branch)
    crank = np.radians(swing_angles(spec, spec.dynamics.samples))
    return {"dynamics": dynamics_facts(dyn, crank, (dc.x_a, dc.y_a), spec.dynamics)}


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(PickerDoubleCrankSpec, loaded.model)     # load_spec validated it with this kind's model
    dc = linkage(spec)
    try:
        rules = evaluate(spec, dc)
    except AssemblyError as exc:
        raise AssemblyError(f"{loaded.path}: {exc}") from None
    design = dict(spec.design_values())
    design["branch"] = spec.linkage.branch
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra=facts(spec, dc))


def headline(result: Result) -> list[str]:
    """The clamp's miss of its target arc (rms, maximum, eq 4's sum) and the smallest transmission angle, and with
    [key_poses] a line per pose, from result.json facts and rules."""
    arc = (result.extra or {}).get("arc_error") or {}
    rules = {r["name"]: r for r in result.rules}
    if not arc:
        return []
    points = arc.get("points") or []
    mu = rules.get("min_transmission_angle") or {}
    return [f"arc error over {len(points)} points: rms {figure_text(arc.get('rms_mm'), 'mm')}, max "
            f"{figure_text(arc.get('max_mm'), 'mm')} (eq 4 sum {figure_text(arc.get('eq4_sum_mm'), 'mm')})",
            f"path off the circle at most {figure_text(arc.get('path_off_circle_max_mm'), 'mm')}, transmission angle "
            f"min {figure_text(mu.get('value'), 'deg')}",
            *pose_headline((result.extra or {}).get("key_poses") or {}, rules)]


def combined_headline(result: Result) -> list[str]:
    """The combined picker (drive and linkage): how near the clamp picks and drops to its targets and when, its peak
    speed and, with [key_poses], a line per pose, from result.json facts."""
    facts = result.extra or {}
    instants = facts.get("instants") or {}
    lines = []
    for name in ("picking", "dropping"):
        at = instants.get(name)
        if isinstance(at, dict):
            lines.append(f"{name}: {figure_text(at.get('distance_to_target_mm'), 'mm')} from its target at "
                         f"t = {figure_text(at.get('t'), 's')} (published {figure_text(at.get('published_t'), 's')})")
    if facts.get("peak_speed_m_s") is not None:
        lines.append(f"peak clamp speed {figure_text(facts.get('peak_speed_m_s'), 'm/s')}")
    return lines + pose_headline(facts.get("key_poses") or {}, {r["name"]: r for r in result.rules})
