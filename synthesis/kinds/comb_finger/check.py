"""``agrisynth check`` for kind comb_finger: the given finger design against every rule, with the facts the
report draws (the front view of Fig. 28b reconstructed, the combing turn, the printed relations beside ours).

One rule function (:func:`rules_of`) serves check, the NLP and the fine-grid re-check: it reads a
:class:`Trace` built on floats or CasADi symbols by :func:`trace`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from synthesis.constraints import Rule
from synthesis.kinds.comb_finger.rules import (drum_above_ground_rule, finger_clear_rule, finger_hides_rule, finger_protrudes_rule, root_clearance_rule,
                                     tip_reaches_ground_rule, tip_speed_rule, unit_within_row_rule, units_gap_rule)
from synthesis.kinds.comb_finger import geometry as g
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.comb_finger.spec import CombFingerSpec

#: turn angles of the check's clearance-over-a-turn rule
CHECK_TURN_SAMPLES = 3600
RPM = 2.0 * math.pi / 60.0


@dataclass
class Trace:
    """The design in working units (mm, rad, rad/s) and what the rules read, on floats or symbols."""

    r: Any
    e: Any
    alpha: Any
    omega: Any
    b: Any
    rho: Any
    turn: np.ndarray             # sampled turn angles, rad
    clearance: list              # tip to the other unit's drum surface at each turn angle, mm
    clearance_exact: Any         # the smallest of those over the whole turn, closed form, mm
    pd: Any
    gap: Any
    reaches: list
    lowest: Any
    tip_speed: Any               # m/s
    theta: Any                   # rad
    dynamics: list = field(default_factory=list)   # the [dynamics.limits] rules on the turn grid (none: no limits)


def turn_grid(n: int) -> np.ndarray:
    return np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)


def trace(spec: CombFingerSpec, d: dict, turn_samples: int, machine_speed=None) -> Trace:
    """The finger's geometry over a turn; ``machine_speed`` (m/s: a CasADi symbol of the tolerance analysis's
    build) replaces the spec's in the combing angle (the objective: no rule reads it)."""
    r, e, b, rho = d["r"], d["e"], d["b"], d["rho"]
    alpha, omega = d["alpha"] * (math.pi / 180.0), d["omega"] * RPM
    vs = 1000.0 * (spec.operation.machine_speed if machine_speed is None else machine_speed)
    sx, sy = g.drum_axis(r, e, alpha, b)
    other = (-sx, sy)                                  # the right unit's drum axis (mirror image)
    turn = turn_grid(turn_samples)
    if g._symbolic(r, e, alpha, b, rho):
        clearance = []
        for phi in turn:
            tx, ty = g.tip(r, e, alpha, b, float(phi))
            clearance.append(g.sqrt((tx - other[0]) ** 2 + (ty - other[1]) ** 2) - rho)
    else:                                  # floats: the whole turn at once (the studio drags on this grid)
        tx, ty = g.tip(r, e, alpha, b, np.asarray(turn, dtype=float))
        clearance = [float(c) for c in np.sqrt((tx - other[0]) ** 2 + (ty - other[1]) ** 2) - rho]
    rx, ry = g.hub(r, e, alpha, b)
    exact = g.sqrt((rx - other[0]) ** 2 + (ry - other[1]) ** 2) - r - rho
    return Trace(r, e, alpha, omega, b, rho, turn, clearance, exact, g.root_clearance(r, e, alpha, b),
                 g.cone_distance(r, e, alpha) - 2.0 * rho, [r - rx, -sx + rho], g.lowest_tip(r, e, alpha, b),
                 r * omega / 1000.0, g.combing_angle(r, e, alpha, b, omega, vs),
                 dynamics_rules_of(spec, r, e, alpha, b, omega, turn))


def finger_dynamics(spec: CombFingerSpec, r, e, alpha_rad, b, omega):
    """The inverse dynamics' inputs of a design (floats or symbols; omega rad/s).  Needs a ``[dynamics]`` table."""
    # imported here: a spec without [dynamics] imports nothing of the dynamics (nor its shared rules)
    from synthesis.kinds.comb_finger.dynamics import FingerDynamics

    assert spec.dynamics is not None
    return FingerDynamics.of(spec.dynamics, r, e, alpha_rad, b, omega)


def dynamics_rules_of(spec: CombFingerSpec, r, e, alpha_rad, b, omega, turn: np.ndarray) -> list[Rule]:
    """The ``[dynamics.limits]`` rules on the turn angles ``turn`` (floats or symbols); none without a ``[dynamics]``
    table or without a limit, so such a spec's rules are what they were."""
    if spec.dynamics is None or not spec.dynamics.has_rules():
        return []
    from synthesis.kinds.comb_finger.dynamics import dynamics_rules

    return dynamics_rules(finger_dynamics(spec, r, e, alpha_rad, b, omega), spec.dynamics.limits, turn)


def rules_of(spec: CombFingerSpec, tr: Trace) -> list[Rule]:
    """Every rule on a trace of floats or CasADi symbols."""
    q = spec.requirements
    rules = [root_clearance_rule(tr.pd, q.root_clearance),
             units_gap_rule(tr.gap, q.units_gap),
             finger_clear_rule(tr.clearance, tr.clearance_exact, q.finger_clearance),
             unit_within_row_rule(tr.reaches, spec.operation.row_spacing / 2.0),
             finger_hides_rule(tr.r, tr.e, tr.rho, q.hub_inset),
             finger_protrudes_rule(tr.r + tr.e - tr.rho, q.protrusion),
             tip_reaches_ground_rule(tr.lowest, q.ground_reach),
             drum_above_ground_rule(tr.b, tr.rho)]
    if q.max_tip_speed is not None:
        rules.append(tip_speed_rule(tr.tip_speed, q.max_tip_speed))
    return rules + tr.dynamics


def fine_samples(spec: CombFingerSpec) -> int:
    """The turn grid of check and of the solve's re-check alike (so a solved design's check reproduces the
    solve's rule table): at least CHECK_TURN_SAMPLES and at least 10x the solver's samples."""
    return max(CHECK_TURN_SAMPLES, 10 * spec.solver.turn_samples)


def evaluate(spec: CombFingerSpec, design: dict, turn_samples: int | None = None) -> tuple[list[Rule], Trace]:
    tr = trace(spec, design, fine_samples(spec) if turn_samples is None else turn_samples)
    return rules_of(spec, tr), tr


# ---- facts ------------------------------------------------------------------------------------------------

def _pt(p) -> list[float]:
    return [float(p[0]), float(p[1])]


def working_units(spec: CombFingerSpec, design: dict) -> tuple[float, ...]:
    """(r, e, alpha, b, omega, V_s) of a design on floats, in this module's working units (mm, rad, rad/s, mm/s)."""
    return (design["r"], design["e"], math.radians(design["alpha"]), design["b"], design["omega"] * RPM,
            1000.0 * spec.operation.machine_speed)


def printed_relations(spec: CombFingerSpec, design: dict) -> list[dict]:
    """Eq 17, 19, 21, 22 as printed beside the same quantity from the reconstructed geometry."""
    r, e, alpha, b, omega, vs = working_units(spec, design)
    turn = g.combing_turn(r, e, alpha, b)
    t = g.combing_time(r, e, alpha, b, omega)
    tangent = abs(g.lowest_tip(r, e, alpha, b)) < 1e-9
    rows = [
        ("eq 17: PD = r (csc beta - 1)", g.root_clearance(r, e, alpha, b),
         g.pd_printed(r, g.root_angle(r, e, alpha, b)), "mm",
         "holds when the tip circle touches the ground (b = r + e sin alpha)" + ("" if tangent else "; it does not here")),
        ("eq 19: tan theta = r (1 - cos omega t) / (V_s t)", math.tan(g.combing_angle(r, e, alpha, b, omega, vs)),
         g.tan_theta_eq19(r, omega * t, vs, t), "", "at the end of the combing turn"),
        ("eq 21: tan theta = r (1 + sin alpha) / (V_s t)", math.tan(g.combing_angle(r, e, alpha, b, omega, vs)),
         g.tan_theta_eq21(r, alpha, vs, t), "", ""),
        ("eq 22: t = (alpha + pi/2) / omega", t, g.time_eq22(alpha, omega), "s", "the turn from the lowest point to F"),
        ("eq 20: omega t = alpha + pi/2", math.degrees(turn), math.degrees(alpha) + 90.0, "deg", ""),
    ]
    return [{"relation": n, "geometry": float(a), "printed": float(p), "difference": float(a - p), "unit": u,
             "note": note} for n, a, p, u, note in rows]


def geometry_facts(spec: CombFingerSpec, design: dict) -> dict:
    r, e, alpha, b, omega, vs = working_units(spec, design)
    rho = design["rho"]
    s, hub = g.drum_axis(r, e, alpha, b), g.hub(r, e, alpha, b)
    pe, pf = g.centre_line_points(r, e, alpha, b)
    rd = math.hypot(*hub)
    p = (hub[0] - r * hub[0] / rd, hub[1] - r * hub[1] / rd)
    turn = g.combing_turn(r, e, alpha, b)
    t = g.combing_time(r, e, alpha, b, omega)
    phis = np.linspace(0.0, turn, 61)
    rises = [float(g.rise(r, e, alpha, b, float(ph))) for ph in phis]
    circle = turn_grid(181)
    tips = [g.tip(r, e, alpha, b, float(ph)) for ph in circle]
    a_best = g.best_alpha_at_fixed_omega()
    return {
        "frame": "front view: x across the row from its centre line (toward the right unit), y up from the ground "
                 "line, root D at the origin; left unit given, the right one is its mirror image",
        "points_mm": {"S": _pt(s), "R": _pt(hub), "E": _pt(pe), "F": _pt(pf), "D": [0.0, 0.0], "P": _pt(p)},
        "cone_distance_a_mm": float(g.cone_distance(r, e, alpha)), "drum_height_b_mm": b,
        "tangent_drum_height_mm": float(g.tangent_drum_height(r, e, alpha)),
        "lowest_tip_mm": float(g.lowest_tip(r, e, alpha, b)),
        "root_angle_beta_deg": math.degrees(g.root_angle(r, e, alpha, b)),
        "root_clearance_PD_mm": float(g.root_clearance(r, e, alpha, b)),
        "units_gap_mm": float(g.cone_distance(r, e, alpha) - 2 * rho),
        "combing_turn_deg": math.degrees(turn), "combing_time_s": float(t),
        "combing_lift_l_mm": float(g.combing_lift(r, e, alpha, b)),
        "combing_angle_theta_deg": math.degrees(g.combing_angle(r, e, alpha, b, omega, vs)),
        "tip_speed_m_s": r * omega / 1000.0, "machine_speed_m_s": spec.operation.machine_speed,
        "alpha_best_at_fixed_omega_deg": math.degrees(a_best),
        "combing_angle_at_best_alpha_same_r_omega_deg": math.degrees(math.atan(
            r * (1 + math.sin(a_best)) * omega / (vs * (a_best + math.pi / 2)))),
        "curves": {"tip_circle": {"x": [float(x) for x, _ in tips], "y": [float(y) for _, y in tips]},
                   "drum_radius_mm": rho,
                   "combing": {"turn_deg": np.degrees(phis).tolist(), "travel_mm": (vs * phis / omega).tolist(),
                               "rise_mm": rises}},
        "printed_relations": printed_relations(spec, design),
    }


#: turn angles of the trajectory over one finger turn (the combing turn's end F is added to them)
TRAJECTORY_SAMPLES = 361


def trajectory(spec: CombFingerSpec, design: dict) -> dict:
    """One turn of the left finger's tip (trajectory keys) from its lowest point (turn angle 0, where it picks the stem
    up), in the ground frame's side view: x along the travel, V_s t from that point (the tip turns about a hub the
    machine carries forward at V_s), y the tip's height above the ground line.  The chord from the first sample to F
    (the sample at ``combing_turn_deg``) rises at the combing angle theta (eq 21).  ``machine``: the same samples in
    the machine's front view (x across the row, as ``points_mm``), where the tip turns on its circle."""
    r, e, alpha, b, omega, vs = working_units(spec, design)
    f_turn = g.combing_turn(r, e, alpha, b)
    grid = np.linspace(0.0, 2.0 * math.pi, TRAJECTORY_SAMPLES)
    # F replaces a grid angle it falls on within rounding (alpha a whole degree puts it on the 1-degree grid): two
    # samples 1e-16 s apart would make any difference quotient of the samples meaningless
    phi = np.union1d(grid[np.abs(grid - f_turn) > 1e-9], [f_turn])
    t = phi / omega
    tx, ty = (np.asarray(c, dtype=float) for c in g.tip(r, e, alpha, b, phi))
    # the tip turns on a circle of radius r about the hub: d/dt (sin phi, -cos phi) r = r omega (cos phi, sin phi)
    front_vx, front_vy = r * omega * np.cos(phi), r * omega * np.sin(phi)
    return {
        "frame": "ground",
        "point": "left finger tip; side view: x along the travel from where the tip is lowest (turn angle 0), "
                 "y up from the ground line (its motion across the row is the front view's, under machine)",
        "t": t.tolist(), "crank_deg": np.degrees(phi).tolist(),
        "x": (vs * t).tolist(), "y": ty.tolist(),
        "vx": np.full_like(phi, vs).tolist(), "vy": front_vy.tolist(),
        "ax": np.zeros_like(phi).tolist(), "ay": (r * omega**2 * np.cos(phi)).tolist(),
        "machine": {"view": "front: x across the row from its centre line, y up from the ground line",
                    "x": tx.tolist(), "y": ty.tolist(),
                    "vx": front_vx.tolist(), "vy": front_vy.tolist()},
    }


def dynamics_of(spec: CombFingerSpec, design: dict) -> dict:
    """``{"dynamics": facts.dynamics}`` over a turn at the table's ``samples`` turn angles, or nothing without a
    ``[dynamics]`` table."""
    if spec.dynamics is None:
        return {}
    from synthesis.kinds.comb_finger.dynamics import dynamics_facts

    r, e, alpha, b, omega, _ = working_units(spec, design)
    dyn = finger_dynamics(spec, r, e, alpha, b, omega)
    return {"dynamics": dynamics_facts(dyn, spec.dynamics.samples, design["omega"], spec.dynamics)}


def facts(spec: CombFingerSpec, design: dict) -> dict:
    return {"source": spec.source, "row_spacing_mm": spec.operation.row_spacing, **geometry_facts(spec, design),
            **dynamics_of(spec, design)}


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(CombFingerSpec, loaded.model)       # load_spec validated it with this kind's model
    design = spec.design_values()
    rules, _ = evaluate(spec, design)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], trajectory=trajectory(spec, design),
                  extra=facts(spec, design))


def headline(result: Result) -> list[str]:
    """Tip speed, root clearance, combing angle and lift, the gap between the two units, from result.json facts."""
    facts = result.extra or {}
    if "tip_speed_m_s" not in facts:
        return []
    return [f"tip speed {figure_text(facts.get('tip_speed_m_s'), 'm/s')}, root clearance "
            f"{figure_text(facts.get('root_clearance_PD_mm'), 'mm')}, units gap "
            f"{figure_text(facts.get('units_gap_mm'), 'mm')}",
            f"combing angle {figure_text(facts.get('combing_angle_theta_deg'), 'deg')} over a "
            f"{figure_text(facts.get('combing_turn_deg'), 'deg')} turn, lift "
            f"{figure_text(facts.get('combing_lift_l_mm'), 'mm')}", *_dynamics_line(facts)]


def _dynamics_line(facts: dict) -> list[str]:
    """With a [dynamics] table: the peak drive torque, the mean power and the peak shaking force."""
    summary = (facts.get("dynamics") or {}).get("summary") or {}
    if not summary:
        return []
    return [(f"drive torque peak {figure_text(summary['input_torque_Nm']['peak'], 'N m')}, mean power "
             f"{figure_text(summary['mean_power_W'], 'W')}, shaking force peak "
             f"{figure_text(summary['shaking_force_N']['peak'], 'N')}")]
