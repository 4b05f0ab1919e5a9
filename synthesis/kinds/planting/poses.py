"""The planting arm's poses for the studio's drawing: its check gives none, so they come from the joint positions
the kind's figures draw the linkage with (:mod:`synthesis.kinds.planting.kinematics`), on the trajectory's crank
angles."""

from __future__ import annotations

import math

from synthesis.core.kind import Poses, pose_mm


def frames(result, most: int) -> list[dict]:
    import numpy as np

    from synthesis.kinds.planting.kinematics import ArmDesign, joint_positions

    traj = result.trajectory
    if not traj:
        return []
    d = result.design
    design = ArmDesign.of_result(d)
    crank = traj["crank_deg"]
    step = -(-len(crank) // most)
    theta = [math.radians(c) for c in crank[::step]]
    joints = joint_positions(design, np.array(theta))
    return [{name: [pose_mm(xy[0, k]), pose_mm(xy[1, k])] for name, xy in joints.items()}      # None: not finite
            for k in range(len(theta))]


POSES = Poses(frames=frames, bars=[["O", "A"], ["A", "B"], ["B", "O'"], ["O", "O'"], ["A", "C"], ["B", "C"]])
