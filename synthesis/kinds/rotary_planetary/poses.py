"""The mechanism's poses for the studio's drawing: the carrier, idler and planet centres and the claw tip on the
facts' carrier angles, from the design (closed form)."""

from __future__ import annotations

import math

import numpy as np

from synthesis.core.kind import Poses, pose_mm
from synthesis.kinds.rotary_planetary.kinematics import idler_centre, planet_centre, tip, train_from_design


def frames(result, most: int) -> list[dict]:
    curves = ((result.extra.get("motion") or {}).get("curves")) or {}
    carrier = curves.get("carrier_deg")
    if not isinstance(carrier, list) or len(carrier) < 2:
        return []
    train = train_from_design(result.design)
    samples = carrier[:-1] if abs(carrier[-1] - carrier[0] - 360.0) < 1e-9 else carrier
    step = -(-len(samples) // most)
    out = []
    for c in samples[::step]:
        phi = np.radians(float(c))
        ix, iy = idler_centre(train, phi)
        px, py = planet_centre(train, phi)
        tx, ty = tip(train, phi)
        if not all(math.isfinite(float(v)) for v in (tx, ty)):
            continue
        out.append({"O": [0.0, 0.0], "A": [pose_mm(float(ix)), pose_mm(float(iy))],
                    "B": [pose_mm(float(px)), pose_mm(float(py))], "P": [pose_mm(float(tx)), pose_mm(float(ty))]})
    return out


POSES = Poses(frames=frames, bars=[["O", "A"], ["A", "B"], ["B", "P"]])
