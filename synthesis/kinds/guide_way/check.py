"""``agrisynth check`` for kind guide_way: evaluate the given claw path against every rule and describe it.

The result carries the rule table and, under ``facts``: every joint (theta, roller centre, tangent and
curvature from both sides, the jumps), the fold conditions, the arm angle at every key point, the
uncontrolled stretch, every undercut stretch (where, how long, smallest radius), the pressure angle
over the cycle, and the curves the figures and the CSV/DXF exports are drawn from (claw tip, roller
centre line, both walls of the groove).
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np

from synthesis.errors import SpecError
from synthesis.kinds.guide_way import conics as cn
from synthesis.kinds.guide_way import scene as sc
from synthesis.kinds.guide_way.spec import GuideWaySpec
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec

#: the check (and solve's re-check) samples every stretch this many times finer than the NLP
FINE = 10


def scene_for(spec, control=None, samples: int | None = None) -> sc.Scene:
    """The scene at the check's resolution; a spline path needs its control points (the fit or a solve's)."""
    n = samples or FINE * spec.solver.samples_per_segment
    if spec.conic is not None:
        return sc.conic_scene(spec, n)
    return sc.spline_scene(spec, n, control)


def _r(a) -> list:
    return [round(float(v), 6) for v in np.asarray(a, float)]


def _theta_deg(arm) -> np.ndarray:
    return np.degrees(np.unwrap(np.asarray(arm.theta, float))) % 360.0


def curves(scene: sc.Scene) -> list[dict]:
    """Per stretch: arm angle, claw tip, roller centre, both walls (left/right of the direction of motion),
    curvature and pressure angle, in time order."""
    rr = scene.spec.arm.roller_radius
    out = []
    for a in scene.arms:
        nx, ny = np.asarray(a.n[0]), np.asarray(a.n[1])
        sp = np.asarray(a.speed)
        tx, ty = np.asarray(a.n1[0]) / sp, np.asarray(a.n1[1]) / sp
        out.append({"name": a.name, "theta_deg": _r(np.degrees(np.unwrap(np.asarray(a.theta, float)))),
                    "claw_x": _r(a.m[0]), "claw_y": _r(a.m[1]), "pivot_x": _r(a.p[0]), "pivot_y": _r(a.p[1]),
                    "centre_x": _r(nx), "centre_y": _r(ny),
                    "left_x": _r(nx - rr * ty), "left_y": _r(ny + rr * tx),
                    "right_x": _r(nx + rr * ty), "right_y": _r(ny - rr * tx),
                    "curvature_per_mm": [float(f"{v:.9g}") for v in np.asarray(a.kappa, float)],
                    "pressure_angle_deg": _r(a.pressure_angle_deg)})
    return out


#: arm poses listed in the facts (``positions``), evenly over the controlled path's samples
POSES = 36


def positions(scene: sc.Scene) -> list[dict]:
    """Arm poses along the controlled path, in time order: the wheel centre O, the pivot P, the claw tip M and the
    roller centre N (mm), for drawing and animating the mechanism."""
    rows = [(a, i) for a in scene.arms for i in range(np.asarray(a.theta).size)]
    step = max(1, -(-len(rows) // POSES))
    out = []
    for a, i in rows[::step]:
        out.append({"theta_deg": float(np.degrees(float(a.theta[i])) % 360.0), "O": [0.0, 0.0],
                    "P": [float(a.p[0][i]), float(a.p[1][i])], "M": [float(a.m[0][i]), float(a.m[1][i])],
                    "N": [float(a.n[0][i]), float(a.n[1][i])]})
    return out


def undercut_stretches(scene: sc.Scene) -> list[dict]:
    """Every run of samples where the centre line bends tighter than the roller: the wall on the concave side
    (left or right of the direction of motion) has a cusp there and cannot be cut."""
    rr = scene.spec.arm.roller_radius
    found = []
    for a in scene.arms:
        k = np.asarray(a.kappa, float)
        bad = np.abs(k) * rr > 1.0
        th = _theta_deg(a)
        nx, ny = np.asarray(a.n[0]), np.asarray(a.n[1])
        i = 0
        while i < k.size:
            if not bad[i]:
                i += 1
                continue
            j = i
            while j + 1 < k.size and bad[j + 1] and np.sign(k[j + 1]) == np.sign(k[i]):
                j += 1
            run = slice(i, j + 1)
            worst = i + int(np.argmax(np.abs(k[run])))
            length = float(np.sum(np.hypot(np.diff(nx[run]), np.diff(ny[run]))))
            found.append({"stretch": a.name, "wall": "left" if k[i] > 0 else "right",
                          "theta_from_deg": float(th[i]), "theta_to_deg": float(th[j]),
                          "claw_tip_from": [float(a.m[0][i]), float(a.m[1][i])],
                          "claw_tip_to": [float(a.m[0][j]), float(a.m[1][j])],
                          "centre_line_length_mm": length, "smallest_radius_mm": float(1.0 / abs(k[worst])),
                          "smallest_at_theta_deg": float(th[worst]),
                          "smallest_at_centre": [float(nx[worst]), float(ny[worst])],
                          "samples": int(j - i + 1)})
            i = j + 1
    return found


def _extreme(scene: sc.Scene, values, pick) -> dict:
    best = None
    for a, v in zip(scene.arms, values):
        v = np.asarray(v, float)
        if v.size == 0:
            continue
        i = int(pick(v))
        if best is None or (pick is np.argmax and v[i] > best[0]) or (pick is np.argmin and v[i] < best[0]):
            best = (float(v[i]), a, i)
    if best is None:
        return {}
    value, a, i = best
    return {"value": value, "stretch": a.name, "theta_deg": float(_theta_deg(a)[i]),
            "claw_tip": [float(a.m[0][i]), float(a.m[1][i])]}


def key_angles(scene: sc.Scene) -> dict:
    """Arm angle theta (deg, 0..360) at every key point of the controlled path, from each stretch that has it."""
    keys = sc.controlled_keys(scene.spec)
    out: dict[str, dict[str, float]] = {}
    for k, a in enumerate(scene.arms):
        th = _theta_deg(a)
        out.setdefault(keys[k], {})["leaving"] = float(th[0])
        out.setdefault(keys[k + 1], {})["arriving"] = float(th[-1])
    if scene.fold_theta is not None:        # a spline's stretches stop short of the fold: its own angle
        assert scene.fold is not None       # the scenes give the fold's arm angles with the fold
        out[scene.fold["point"]] = {"arriving": math.degrees(scene.fold_theta[0]) % 360.0,
                                    "leaving": math.degrees(scene.fold_theta[1]) % 360.0}
    return out


#: result.json keeps the branch's name ("minus": theta = gamma - phi) though the spec writes its sign
IK_BRANCH_NAMES = {-1: "minus", 1: "plus"}


def conic_facts(scene: sc.Scene) -> list[dict]:
    pieces, segments = scene.pieces, scene.spec.conic
    assert pieces is not None and segments is not None, "the facts of a conic path's scene"
    out = []
    for piece, seg in zip(pieces, segments):
        a = seg.coefficients
        entry = {"name": seg.name, "from": seg.start, "to": seg.end, "coefficients": list(a),
                 "type": "hyperbola" if piece.conic.hyperbola else "ellipse", "ik_branch": IK_BRANCH_NAMES[seg.branch],
                 "key_point_gap_mm": piece.gaps,
                 "slope_at": {p: cn.slope(a, *scene.spec.points[p]) for p in (seg.start, seg.end)}}
        if seg.form is not None:
            st = piece.stretch(2001)
            x, y = st.m[:, 0], st.m[:, 1]
            if seg.form.startswith("y"):
                dev = np.abs(cn.explicit(a, seg.form, x) - y)
            else:
                dev = np.abs(cn.explicit(a, seg.form, y) - x)
            entry["paper_form"] = seg.form
            entry["paper_form_max_deviation_mm"] = float(np.nanmax(dev)) if np.all(np.isfinite(dev)) else None
        out.append(entry)
    return out


def describe(scene: sc.Scene) -> dict:
    spec = scene.spec
    keys = sc.controlled_keys(spec)
    angles = key_angles(scene)
    first, last = keys[0], keys[-1]
    theta_last, theta_first = angles[last]["arriving"], angles[first]["leaving"]
    masks = scene.pressure_masks
    pa = [a.pressure_angle_deg for a in scene.arms]
    facts = {
        "source": spec.source,
        "path": "conics" if spec.conic is not None else "spline",
        "controlled_keys": keys,
        "arm": spec.arm.model_dump(),
        "key_theta_deg": angles,
        "uncontrolled": {"from": last, "to": first, "theta_from_deg": theta_last, "theta_to_deg": theta_first,
                         "arm_angle_deg": (theta_first - theta_last) % 360.0},
        "joints": {j.name: j.to_json() for j in scene.joints},
        "fold": scene.fold,
        "undercut": undercut_stretches(scene),
        "smallest_radius": _extreme(scene, [1.0 / np.maximum(np.abs(np.asarray(a.kappa, float)), 1e-12)
                                            for a in scene.arms], np.argmin),
        "pressure_angle_max": _extreme(scene, pa, np.argmax),
        "pressure_angle_max_outside_fold_window": _extreme(scene, [np.where(m, p, -1.0) for p, m in zip(pa, masks)],
                                                           np.argmax),
        "fold_window_deg": spec.rules.fold_window,
        "curves": curves(scene),
        "positions": positions(scene),
    }
    if scene.pieces is not None:
        facts["conics"] = conic_facts(scene)
    if scene.spline is not None:
        facts["spline"] = spline_facts(scene)
    if spec.dynamics is not None:
        # imported here: a spec without [dynamics] imports nothing of the dynamics (nor its shared rules)
        from synthesis.kinds.guide_way.dynamics import dynamics_facts

        facts["dynamics"] = dynamics_facts(scene)
    return facts


def spline_facts(scene: sc.Scene) -> dict:
    from synthesis.kinds.guide_way import spline as sp

    path, closing = scene.spline, scene.closing
    assert path is not None and closing is not None, "the facts of a spline path's scene"
    c = np.asarray(path.control, float)
    met = sc.key_misses(path)
    tol = scene.spec.rules.key_point
    for name, entry in met.items():
        entry.update(x=entry["target"][0], y=entry["target"][1])       # drawn: the key point itself
        if entry["miss_mm"] > tol:                                      # and where the path passes, when it misses
            entry["path_at_" + name] = {"x": entry["point"][0], "y": entry["point"][1]}
    h = sp.energy_matrix(path.n)
    closed = np.vstack([c, c[:1]])
    return {"control_points": [[float(x), float(y)] for x, y in c], "keys": met,
            "control_polygon": {"x": _r(closed[:, 0]), "y": _r(closed[:, 1])},
            "energy": float(c[:, 0] @ h @ c[:, 0] + c[:, 1] @ h @ c[:, 1]),
            "uncontrolled_claw": {"x": _r(closing[:, 0]), "y": _r(closing[:, 1])}}


def dynamics_samples(spec, scene: sc.Scene) -> int | None:
    """The samples of the path the [dynamics.limits] rules are read on -- by `check` and by the solve's re-check
    alike, so both read one rule table: as many as the other rules read, never fewer than the table asks (check read
    the table's alone: a peak torque 0.4964 N m where the solve had 0.4966); None without a [dynamics] table."""
    if spec.dynamics is None:
        return None
    return max(spec.dynamics.samples, FINE * spec.solver.samples_per_segment * len(scene.arms))


def result_of(spec, sha: str, scene: sc.Scene, status: str = "evaluated") -> Result:
    rules = scene.rules
    if spec.dynamics is not None and spec.dynamics.has_rules():
        from synthesis.kinds.guide_way.dynamics import dynamics_rules

        rules = rules + dynamics_rules(scene, dynamics_samples(spec, scene))
    return Result(kind=spec.kind, name=spec.name, spec_sha256=sha, status=status, design=dict(spec.design_values()),
                  rules=[r.record().to_json() for r in rules], extra=describe(scene))


def given_control(spec) -> np.ndarray | None:
    """The (n, 2) control points a spline spec gives (``[spline] control``: fixed values and free ones' start
    values), or None when it leaves them to the convex fit."""
    from synthesis.spec.common import value_of

    if spec.spline is None or spec.spline.control is None:
        return None
    return np.array([[value_of(x), value_of(y)] for x, y in spec.spline.control], float)


def control_to_check(spec) -> np.ndarray | None:
    """What ``check`` evaluates: the spec's control points, else the convex fit (None for the paper's conics)."""
    if spec.spline is None:
        return None
    control = given_control(spec)
    if control is None:
        from synthesis.kinds.guide_way.fit import fit_path

        control = fit_path(spec).control
    return control


def whose_path(spec) -> str:
    """Where a spline path's control points come from, for a message: the spec's ``[spline] control`` or the fit."""
    if given_control(spec) is not None:
        return "[spline] control"
    return "[spline] (the convex fit through its key points)"


def control_names(n: int) -> list[str]:
    """The names of n control points' coordinates in result.json's design and the NLP's decision vector: P0_x ..
    P{n-1}_x, then P0_y .. P{n-1}_y."""
    return [f"P{j}_{c}" for c in ("x", "y") for j in range(n)]


def control_design(control: np.ndarray) -> dict[str, float]:
    """(n, 2) control points as result.json's design names them (:func:`control_names`)."""
    return dict(zip(control_names(len(control)), (float(v) for v in np.concatenate([control[:, 0], control[:, 1]]))))


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(GuideWaySpec, loaded.model)         # load_spec validated it with this kind's model
    try:
        control = control_to_check(spec)
        scene = scene_for(spec, control)
    except SpecError as exc:
        if spec.spline is None:
            raise
        raise SpecError(f"{loaded.path}: {whose_path(spec)}: {exc}") from None
    result = result_of(spec, loaded.sha256, scene)
    if control is not None:     # the design evaluated: the arm and every control point, as a solve writes it
        result.design.update(control_design(control))
    return result


def explicit_design(loaded: LoadedSpec, data: dict) -> dict:
    """The spec file's ``data`` with the control points written out when it leaves them to the convex fit: each
    coordinate ``{init = fit, bounds = [fit - move, fit + move]}``, the very start and box ``solve`` uses then,
    so the spec solves and checks as before, and the studio and ``solved.toml`` have a place for each point."""
    spec = cast(GuideWaySpec, loaded.model)         # load_spec validated it with this kind's model
    if spec.spline is None or spec.spline.control is not None:
        return data
    from synthesis.kinds.guide_way.fit import fit_path

    move = spec.spline.move
    control = fit_path(spec).control
    out = dict(data)
    spline = {k: v for k, v in data["spline"].items() if k != "move"}      # move is in the bounds now
    out["spline"] = dict(spline, control=[[{"init": float(v), "bounds": [float(v) - move, float(v) + move]}
                                                   for v in point] for point in control])
    return out


def headline(result: Result) -> list[str]:
    """The guide way's largest pressure angle and smallest radius (where), the joints' jumps and the fold's reach,
    from result.json facts."""
    facts = result.extra or {}
    pressure, radius = facts.get("pressure_angle_max") or {}, facts.get("smallest_radius") or {}
    if not pressure and not radius:
        return []
    # the largest over the whole path: the pressure_angle rule leaves out a window about the fold, where the largest
    # often is (the arm at its dead point), so the line says where it is and points at the rule's own value
    where = pressure.get("stretch", "-")
    if isinstance(pressure.get("theta_deg"), (int, float)):
        where += f", arm angle {pressure['theta_deg']:.1f} deg"
    rule = next((r for r in result.rules if r.get("name") == "pressure_angle"), None)
    if rule is not None and "fold" in str(rule.get("where", "")):
        where += f"; outside the fold window, the pressure_angle rule's: {figure_text(rule.get('value'), 'deg')}"
    lines = [f"pressure angle max over the whole path {figure_text(pressure.get('value'), 'deg')} ({where}), "
             f"smallest radius {figure_text(radius.get('value'), 'mm')} ({radius.get('stretch', '-')})"]
    joints = facts.get("joints") or {}
    jumps = [f"{name} {figure_text(j.get('position_jump_mm'), 'mm')} / {figure_text(j.get('tangent_jump_deg'), 'deg')}"
             for name, j in joints.items() if isinstance(j, dict)]
    if jumps:
        lines.append(f"joint jumps (position / tangent): {', '.join(jumps)}")
    fold = facts.get("fold") or {}
    if fold:
        lines.append(f"fold at {fold.get('point', '-')}: claw tip {figure_text(fold.get('distance_mm'), 'mm', 4)} "
                     f"from the centre, {figure_text(fold.get('excess_mm'), 'mm')} beyond the fold radius")
    dyn = facts.get("dynamics") or {}
    summary = dyn.get("summary") or {}
    if summary:
        torque, groove = summary.get("input_torque_Nm") or {}, summary.get("groove_force_N") or {}
        outside = (summary.get("groove_force_outside_fold_window_N") or {}).get("peak")
        lines.append(f"dynamics at {figure_text(dyn.get('crank_speed_rpm'), 'r/min')}: peak drive torque "
                     f"{figure_text(torque.get('peak'), 'N m')} ({torque.get('stretch', '-')}), groove force "
                     f"{figure_text(groove.get('peak'), 'N')} ({groove.get('stretch', '-')})"
                     + (f", {figure_text(outside, 'N')} outside the fold window" if outside is not None else "")
                     + f", the roller changes wall {summary.get('wall_changes', '-')} times")
    return lines
