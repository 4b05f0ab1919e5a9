"""The path four-bar's poses for the studio's drawing: its check gives none, so they come from the joint positions
of the kind's own construction (:mod:`synthesis.kinds.fourbar_path.construction`), on the trajectory's crank angles;
none where the loop does not close."""

from __future__ import annotations

from synthesis.core.kind import Poses, pose_mm


def frames(result, most: int) -> list[dict]:
    import numpy as np

    from synthesis.kinds.fourbar_path.check import result_branch
    from synthesis.kinds.fourbar_path.construction import joint_positions
    from synthesis.kinds.fourbar_path.kinematics import VARIABLES

    traj = result.trajectory
    crank = traj.get("crank_deg") if traj else None
    # a list of numbers, judged by its first, middle and last items as the studio's drawing judges lists
    if not isinstance(crank, list) or len(crank) < 2 or not all(
            isinstance(c, (int, float)) and not isinstance(c, bool) for c in (crank[0], crank[len(crank) // 2], crank[-1])):
        return []
    design = {n: float(result.design[n]) for n in VARIABLES}
    theta = np.radians(crank[::-(-len(crank) // most)])
    joints = joint_positions(design, theta, result_branch(result))
    poses = [{name: [pose_mm(z[k].real), pose_mm(z[k].imag)] for name, z in joints.items()} for k in range(theta.size)]
    return [p for p in poses if all(None not in xy for xy in p.values())]


POSES = Poses(frames=frames, bars=[["O", "A"], ["A", "B"], ["B", "O'"], ["O", "O'"], ["A", "P"], ["B", "P"]])
