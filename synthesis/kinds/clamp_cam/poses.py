"""The clamp cam's poses for the studio's drawing: the cam turning and its roller follower moving with it.

The check computes in a counter-clockwise model frame (cam centre at the origin, follower along +X): the roller
centre C over a turn (the trajectory) and the profile in the cam frame (cam angle 0 where the rise begins), which
it mirrors (y -> -y) for a clockwise cam, as it is exported and made.  At crank angle c the cam has turned by
phi = c - rise_start and the pitch point of cam angle phi sits at C (cam_follower.pitch_curve is R(-phi) C), so a
counter-clockwise cam is drawn turned by +phi.  A clockwise cam is drawn as made: the whole scene mirrored --
R(-phi) M P = M R(phi) P -- the exported profile turned by -phi, the roller at M C, the follower mirrored (the page's
traced-point line stays the check's trajectory, in the model frame).  Each pose: the cam centre O, the roller
centre C, the follower's far end (a translating stem along +X, or the arm pivot of an oscillating follower), the
cam's working profile and the roller, both rigid shapes sent once and placed per pose."""

from __future__ import annotations

import math

from synthesis.core.kind import Poses, pose_mm

PROFILE_POINTS = 720     # points of the drawn cam outline (0.5 deg: a chord sits < 0.01 mm off a steep return)
ROLLER_POINTS = 24


def _finite(*values) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values)


def _rise_start(prof: dict):
    """The crank angle of cam angle 0 (where the rise begins): the profile's first sample."""
    return (prof.get("crank_deg") or [None])[0]


def shapes(result) -> dict:
    """The cam's working profile in its own frame, as the check exports it, and the roller, both about their own
    centre."""
    import numpy as np

    prof = result.extra.get("profile") or {}
    working = prof.get("working") or {}
    wx = np.asarray(working.get("x") or [], float)
    wy = np.asarray(working.get("y") or [], float)            # as exported (mirrored for a clockwise cam)
    if wx.size < 2 or not _finite(prof.get("roller_radius")):
        return {}
    keep = np.linspace(0, wx.size, PROFILE_POINTS, endpoint=False).astype(int)
    rr = float(prof["roller_radius"])
    ring = np.linspace(0.0, 2.0 * math.pi, ROLLER_POINTS + 1)
    return {"cam": [[pose_mm(wx[i]), pose_mm(wy[i])] for i in keep] + [[pose_mm(wx[0]), pose_mm(wy[0])]],
            "roller": [[pose_mm(rr * math.cos(t)), pose_mm(rr * math.sin(t))] for t in ring]}


def frames(result, most: int) -> list[dict]:
    prof = result.extra.get("profile") or {}
    traj = result.trajectory or {}
    crank, rise_start = traj.get("crank_deg"), _rise_start(prof)
    if not (isinstance(crank, list) and len(crank) > 1 and _finite(rise_start)):
        return []
    pivot = result.design.get("pivot_distance")
    stem = 0.6 * float(result.design.get("base_radius", 50.0))
    sense = -1.0 if prof.get("rotation") == "clockwise" else 1.0      # a clockwise cam: the scene mirrored
    count = len(crank) - 1 if len(crank) > 2 and abs(crank[-1] - crank[0] - 360.0) < 1e-9 else len(crank)
    step = -(-count // most)
    out = []
    for k in range(0, count, step):
        c, cx, cy = crank[k], traj["x"][k], traj["y"][k]
        if not _finite(c, cx, cy):
            continue
        cy = sense * cy
        end = [float(pivot), 0.0] if _finite(pivot) else [cx + stem, cy]
        out.append({
            "O": [0.0, 0.0], "C": [pose_mm(cx), pose_mm(cy)],
            "pivot" if _finite(pivot) else "stem": [pose_mm(end[0]), pose_mm(end[1])],
            # the cam turned by its cam angle: the pitch point of cam angle phi then sits at C
            "cam": {"shape": "cam", "at": [0.0, 0.0], "turn_deg": pose_mm(sense * ((c - rise_start) % 360.0))},
            "roller": {"shape": "roller", "at": [pose_mm(cx), pose_mm(cy)], "turn_deg": 0.0},
        })
    return out


POSES = Poses(frames=frames, bars=[["C", "stem"], ["C", "pivot"]], shapes=shapes)
