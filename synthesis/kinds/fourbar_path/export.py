"""Workshop files of a fourbar_path result, written from result.json alone (nothing re-solved).

paths.csv    the coupler point P over one crank turn: time, crank angle, x, y, vx, vy, ax, ay (fixed frame, mm)
linkage.dxf  the linkage at the first target's crank angle (ground pivots O, O', joints A, B, coupler point P,
             links with their lengths, coupler triangle A-B-P), the coupler curve (layer PATH) and the
             targets (layer TARGETS: a small cross each)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence, cast

import numpy as np

from synthesis.report import exports
from synthesis.result import Result

LINKS = (("O", "O'"), ("O", "A"), ("O'", "B"), ("A", "B"), ("A", "P"), ("B", "P"))


def _trajectory(result: Result) -> dict[str, Any]:
    """The result's trajectory.  A linkage that does not assemble has none: its exports then fail at the first
    look-up, and the report names the file as not written."""
    return cast(dict[str, Any], result.trajectory)


def write_paths_csv(result: Result, path: Path) -> None:
    tr = _trajectory(result)
    exports.write_csv(path, {"t_s": tr["t"], "crank_deg": tr["crank_deg"], "x_mm": tr["x"], "y_mm": tr["y"],
                             "vx_mm_s": tr["vx"], "vy_mm_s": tr["vy"], "ax_mm_s2": tr["ax"], "ay_mm_s2": tr["ay"]})


def write_linkage_dxf(result: Result, path: Path) -> None:
    from synthesis.kinds.fourbar_path.check import result_branch
    from synthesis.kinds.fourbar_path.construction import joint_positions
    from synthesis.kinds.fourbar_path.kinematics import VARIABLES

    tr = _trajectory(result)
    design = {n: result.design[n] for n in VARIABLES}
    branch = result_branch(result)
    given = np.asarray(result.design.get("crank_deg", []) or [], dtype=float).ravel()
    crank = float(given[0]) if given.size else float(tr["crank_deg"][0])
    j = joint_positions(design, np.radians([crank]), branch)
    joints: dict[str, Sequence[float]] = {n: (float(np.real(v[0])), float(np.imag(v[0]))) for n, v in j.items()}
    targets = np.asarray(result.extra.get("targets", []), dtype=float).reshape(-1, 2)
    span = max(np.ptp(tr["x"]), np.ptp(tr["y"]), 1.0)
    h = 0.01 * span
    crosses = [seg for x, y in targets for seg in ([(x - h, y - h), (x + h, y + h)], [(x - h, y + h), (x + h, y - h)])]
    curves: dict[str, Sequence[Sequence[Sequence[float]]]] = {"PATH": [list(zip(tr["x"], tr["y"]))]}
    if crosses:
        curves["TARGETS"] = crosses
    exports.write_linkage_dxf(path, joints, ground=("O", "O'"), links=LINKS, couplers=[("A", "B", "P")],
                              curves=curves, note=f"{result.name}: linkage at crank angle {crank % 360:.2f} deg, mm")
