"""What the page draws, read from a check's Result: the kind's own curves, key points and mechanism poses.

Generic over kinds: every polyline the check already computed (a table with equal-length ``x`` and ``y``
lists, or ``<name>_x`` / ``<name>_y`` pairs), every key point (a table with numbers ``x`` and ``y``; a
list of ``[x, y]`` targets), the traced point's trajectory, and mechanism poses (a ``positions`` list of
joint tables, or a ``joints`` table).  A kind whose check gives no poses gives them itself (``Kind.poses``:
from the kinematics its own figures draw the linkage with, on the trajectory's crank angles).
"""

from __future__ import annotations

import math
from typing import Any

from synthesis import kinds
from synthesis.result import Result

#: longest polyline sent to the page (a longer one is thinned evenly, its ends kept)
MOST_POINTS = 400
#: poses of an animated mechanism at most
MOST_FRAMES = 72
#: charts at most (the first ones the check's facts hold)
MOST_CHARTS = 2


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _numbers(values: Any) -> bool:
    """A list of numbers (judged by its first, middle and last items: the check's lists are uniform, and
    looking at every item of every list cost more than the evaluation; None where a value is missing is fine)."""
    if not isinstance(values, list) or len(values) < 2:
        return False
    probe = [v for v in (values[0], values[len(values) // 2], values[-1]) if v is not None]
    return bool(probe) and all(_number(v) for v in probe)


def _pair(value: Any) -> bool:
    return isinstance(value, list) and len(value) == 2 and _number(value[0]) and _number(value[1])


def _thin(xs: list, ys: list) -> tuple[list, list]:
    n = len(xs)
    if n <= MOST_POINTS:
        idx = range(n)
    else:
        idx = sorted({round(i * (n - 1) / (MOST_POINTS - 1)) for i in range(MOST_POINTS)})
    return [_r(xs[i]) for i in idx], [_r(ys[i]) for i in idx]


def _r(v):
    return round(float(v), 3) if _number(v) and math.isfinite(v) else None


#: angles that only say where in the cycle a sample is (never charted against each other)
CLOCKS = {"crank_deg", "cam_angle_deg", "theta_deg"}


def _chart(node: dict, path: str) -> dict | None:
    """Angles over an angle (e.g. steering's outside lock over the inside lock, a follower's pressure angle over
    the crank): the table's first ``*_deg`` list against its other ``*_deg`` lists of the same length (its own,
    and those of the tables in its ``series`` list)."""
    series = [(k, v) for k, v in node.items() if k.endswith("_deg") and _numbers(v)]
    for i, item in enumerate(node.get("series") or []):     # curves listed under "series" (one per gear, ...)
        if isinstance(item, dict):
            series.extend((f"{k}[{i}]", v) for k, v in item.items() if k.endswith("_deg") and _numbers(v))
    if len(series) < 2 or any(len(v) != len(series[0][1]) for _, v in series):
        return None
    (x_name, xs), rest = series[0], [(k, v) for k, v in series[1:] if k not in CLOCKS]
    if not rest:
        return None
    thinned = [_thin(xs, ys) for _, ys in rest]
    return {"name": path or "curve", "x_name": x_name, "x": thinned[0][0],
            "series": [{"name": k, "y": t[1]} for (k, _), t in zip(rest, thinned)]}


def _walk(node: Any, path: str, lines: list, points: list, poses: list, charts: list | None = None) -> None:
    charts = [] if charts is None else charts
    if isinstance(node, dict):
        chart = _chart(node, path)
        if chart is not None and len(charts) < MOST_CHARTS:
            charts.append(chart)
        xs, ys = node.get("x"), node.get("y")
        if _numbers(xs) and _numbers(ys) and len(xs) == len(ys):
            lines.append({"name": path, "x": _thin(xs, ys)[0], "y": _thin(xs, ys)[1]})
        elif isinstance(xs, (int, float)) and isinstance(ys, (int, float)) and not isinstance(xs, bool):
            points.append({"name": path.rsplit(".", 1)[-1], "x": _r(xs), "y": _r(ys)})
        for key, value in node.items():
            if key.endswith("_x") and _numbers(value):
                other = node.get(key[:-2] + "_y")
                if _numbers(other) and len(other) == len(value):
                    tx, ty = _thin(value, other)
                    lines.append({"name": f"{path}.{key[:-2]}" if path else key[:-2], "x": tx, "y": ty})
            if key == "positions" and isinstance(value, list) and value and isinstance(value[0], dict):
                poses.extend(value)
                continue
            if key == "joints" and isinstance(value, dict) and value and all(_pair(p) for p in value.values()):
                poses.append(value)            # one pose (e.g. a crank-rocker's extreme positions)
                continue
            if key in ("x", "y") or key == "machine":
                continue
            _walk(value, f"{path}.{key}" if path else key, lines, points, poses, charts)
    elif isinstance(node, list) and node:
        if "target" in path and all(_pair(v) for v in node):
            points.extend({"name": f"{path.rsplit('.', 1)[-1]}[{i}]", "x": _r(v[0]), "y": _r(v[1])}
                          for i, v in enumerate(node))
            return
        for i, value in enumerate(node[:50]):
            if isinstance(value, (dict, list)):
                _walk(value, f"{path}[{i}]", lines, points, poses, charts)


def _pose(item: dict) -> dict[str, list] | None:
    joints = item.get("joints", item)
    out = {name: [_r(p[0]), _r(p[1])] for name, p in joints.items() if _pair(p)}
    return out or None


def drawing(result: Result) -> dict[str, Any]:
    """Panels of polylines and points and the mechanism's poses, in the check's own frames and units (mm), and
    charts of angles over an angle."""
    lines: list = []
    points: list = []
    poses: list = []
    charts: list = []
    _walk(result.extra, "", lines, points, poses, charts)
    ground = None
    traj = result.trajectory
    if traj and _numbers(traj.get("x")) and _numbers(traj.get("y")):
        tx, ty = _thin(traj["x"], traj["y"])
        machine = traj.get("machine")
        if isinstance(machine, dict) and _numbers(machine.get("x")):          # two frames: a panel each
            mx, my = _thin(machine["x"], machine["y"])
            lines.insert(0, {"name": "path (machine frame)", "x": mx, "y": my, "main": True})
            ground = {"lines": [{"name": "path (ground frame)", "x": tx, "y": ty, "main": True}], "points": []}
        elif traj.get("frame") == "ground" and lines:   # a moving machine whose check draws machine-frame curves
            ground = {"lines": [{"name": "traced point (ground frame)", "x": tx, "y": ty, "main": True}], "points": []}
        else:                                           # one frame (a machine that stands, or no other curve)
            lines.insert(0, {"name": f"traced point ({traj.get('frame', 'machine')} frame)", "x": tx, "y": ty,
                             "main": True})
    if ground is not None:          # key points in the ground frame where the check gives them (x_ground)
        for name, p in (result.extra.get("precision_points") or {}).items():
            if isinstance(p, dict) and p.get("found") and isinstance(p.get("x_ground"), (int, float)):
                ground["points"].append({"name": name, "x": _r(p["x_ground"]), "y": _r(p["y"])})
    kind_poses = _kind_poses(result.kind)
    shapes: dict = {}
    if kind_poses is not None:
        frames, bars = kind_poses.frames(result, MOST_FRAMES), kind_poses.bars
        shapes = kind_poses.shapes(result) if kind_poses.shapes is not None and frames else {}
    else:
        frames = [f for f in (_pose(p) for p in poses) if f]
        step = max(1, -(-len(frames) // MOST_FRAMES))
        frames, bars = frames[::step], None
    return {"main": {"lines": lines, "points": points}, "ground": ground,
            "mechanism": {"frames": frames, "bars": bars, "shapes": shapes},
            "charts": _dynamics_charts(result.extra.get("dynamics")) + charts}


def _dynamics_charts(dyn: Any) -> list[dict]:
    """A result with ``facts.dynamics`` (docs/ARCHITECTURE.md "Dynamics"): the input torque and shaking moment (N m)
    and the shaking force (N) over the crank angle, as the sliders move them."""
    if not isinstance(dyn, dict) or not _numbers(dyn.get("crank_deg")) or not _numbers(dyn.get("input_torque_Nm")):
        return []
    crank = dyn["crank_deg"]
    force = dyn.get("shaking_force_N") or []
    magnitude = [math.hypot(*f) if _pair(f) else None for f in force]
    moments = {"input torque": dyn["input_torque_Nm"], "shaking moment": dyn.get("shaking_moment_Nm")}
    charts = [{"name": "drive", "x_name": "crank_deg", "unit": "N m", "x": _thin(crank, crank)[0],
               "series": [{"name": k, "y": _thin(crank, v)[1]} for k, v in moments.items()
                          if _numbers(v) and len(v) == len(crank)]}]
    if len(magnitude) == len(crank):
        charts.append({"name": "frame", "x_name": "crank_deg", "unit": "N", "x": _thin(crank, crank)[0],
                       "series": [{"name": "|shaking force|", "y": _thin(crank, magnitude)[1]}]})
    return charts


def _kind_poses(kind: str):
    """The kind's own poses (``Kind.poses``) where its check's facts give none, else None."""
    return kinds.get(kind).poses()
