"""Workshop files of a planting_fourbar result, written from result.json alone (nothing re-solved).

paths.csv    the claw tip C over one crank turn: time, crank angle, machine frame x, y, vx, vy, ground frame
             x, y, vx, vy and the acceleration (the same in both frames at a constant forward speed)
linkage.dxf  the linkage in the machine frame at the trajectory's first sample (pivots O, O', joints A, B,
             claw tip C, links with their lengths, coupler triangle A-B-C) and the claw-tip path in the
             machine frame (layer PATH_MACHINE) and the ground frame (layer PATH_GROUND)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from synthesis.report import exports
from synthesis.result import Result

LINKS = (("O", "O'"), ("O", "A"), ("O'", "B"), ("A", "B"), ("A", "C"), ("B", "C"))


def _trajectory(result: Result) -> dict[str, Any]:
    """The result's trajectory; a result without one (a linkage that does not assemble over a whole turn) has no
    path to export, which the report notes as the file's reason."""
    if not isinstance(result.trajectory, dict):
        raise ValueError("the result has no trajectory: the linkage does not assemble over a whole crank turn")
    return result.trajectory


def write_paths_csv(result: Result, path: Path) -> None:
    tr = _trajectory(result)
    m = tr["machine"]
    exports.write_csv(path, {"t_s": tr["t"], "crank_deg": tr["crank_deg"],
                     "machine_x_mm": m["x"], "machine_y_mm": m["y"],
                     "machine_vx_mm_s": m["vx"], "machine_vy_mm_s": m["vy"],
                     "ground_x_mm": tr["x"], "ground_y_mm": tr["y"],
                     "ground_vx_mm_s": tr["vx"], "ground_vy_mm_s": tr["vy"],
                     "ax_mm_s2": tr["ax"], "ay_mm_s2": tr["ay"]})


def joints_at(result: Result, crank_deg: float) -> dict[str, Sequence[float]]:
    """Pivots and joints of the result's design at one crank angle (machine frame, mm)."""
    from synthesis.kinds.planting.kinematics import ArmDesign, joint_positions

    d = result.design
    design = ArmDesign.of_result(d)
    j = joint_positions(design, math.radians(crank_deg))
    return {n: (float(j[n][0, 0]), float(j[n][1, 0])) for n in ("O", "O'", "A", "B", "C")}


def write_linkage_dxf(result: Result, path: Path) -> None:
    tr = _trajectory(result)
    crank = float(tr["crank_deg"][0])
    exports.write_linkage_dxf(path, joints_at(result, crank), ground=("O", "O'"), links=LINKS, couplers=[("A", "B", "C")],
                      curves={"PATH_MACHINE": [list(zip(tr["machine"]["x"], tr["machine"]["y"]))],
                              "PATH_GROUND": [list(zip(tr["x"], tr["y"]))]},
                      note=f"{result.name}: linkage at crank angle {crank % 360:.2f} deg (t = 0), machine frame, mm")
