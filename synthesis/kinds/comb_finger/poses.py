"""The comb finger's poses for the studio's drawing: the finger turning about its hub R inside the drum.

Front view of the check (x across the row, y up, root D at the origin; the left unit): the drum axis S, the
finger hub R offset from it by e, the finger tip T at r from R turning over a whole revolution (its path is the
check's tip circle), and the drum's wall, a circle of radius rho about S, as an outline."""

from __future__ import annotations

import math
from typing import Any, TypeGuard

from synthesis.core.kind import Poses, pose_mm

DRUM_POINTS = 48


def _pair(v: Any) -> TypeGuard[list[float]]:
    return isinstance(v, list) and len(v) == 2 and all(
        isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in v)


def shapes(result) -> dict:
    """The drum's wall about the drum axis (radius rho)."""
    rho = result.design.get("rho")
    if not isinstance(rho, (int, float)) or not math.isfinite(rho):
        return {}
    return {"drum": [[pose_mm(rho * math.cos(t)), pose_mm(rho * math.sin(t))]
                     for t in (2.0 * math.pi * k / DRUM_POINTS for k in range(DRUM_POINTS + 1))]}


def frames(result, most: int) -> list[dict]:
    points = result.extra.get("points_mm") or {}
    s, r_hub = points.get("S"), points.get("R")
    d = result.design
    if not (_pair(s) and _pair(r_hub)) or not isinstance(d.get("r"), (int, float)):
        return []
    r = float(d["r"])
    count = max(2, min(most, 72))
    out = []
    for k in range(count):
        a = 2.0 * math.pi * k / count
        out.append({"S": [pose_mm(s[0]), pose_mm(s[1])], "R": [pose_mm(r_hub[0]), pose_mm(r_hub[1])],
                    "T": [pose_mm(r_hub[0] + r * math.cos(a)), pose_mm(r_hub[1] + r * math.sin(a))],
                    "drum": {"shape": "drum", "at": [pose_mm(s[0]), pose_mm(s[1])], "turn_deg": 0.0}})
    return out


POSES = Poses(frames=frames, bars=[["S", "R"], ["R", "T"]], shapes=shapes)
