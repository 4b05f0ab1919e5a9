"""The crank-rocker's poses for the studio's drawing over a whole turn: its check's facts hold the two extreme
positions only (as joints) and the rocker tip E over a turn (``motion.curve``); the crank pin F follows from the
crank angle (G at the origin, A on +x: the check's frame)."""

from __future__ import annotations

import math

from synthesis.core.kind import Poses, pose_mm


def frames(result, most: int) -> list[dict]:
    curve = ((result.extra.get("motion") or {}).get("curve")) or {}
    crank, ex, ey = curve.get("crank_deg"), curve.get("E_x"), curve.get("E_y")
    if not (isinstance(crank, list) and isinstance(ex, list) and isinstance(ey, list)) or len(crank) < 2 \
            or not len(crank) == len(ex) == len(ey):
        return []
    l7, l10 = float(result.design["l7"]), float(result.design["l10"])
    samples = list(zip(crank, ex, ey))
    if len(samples) > 2 and abs(samples[-1][0] - samples[0][0] - 360.0) < 1e-9:
        samples = samples[:-1]            # 0 .. 360 deg with both ends: one pose, not two frames of it
    step = -(-len(samples) // most)
    out = []
    for c, x, y in samples[::step]:
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in (c, x, y)):
            continue                      # the loop does not close there (a crank that cannot turn)
        a = math.radians(c)
        out.append({"G": [0.0, 0.0], "F": [pose_mm(l7 * math.cos(a)), pose_mm(l7 * math.sin(a))],
                    "E": [pose_mm(x), pose_mm(y)], "A": [pose_mm(l10), 0.0]})
    return out


POSES = Poses(frames=frames, bars=[["G", "F"], ["F", "E"], ["E", "A"], ["A", "G"]])
