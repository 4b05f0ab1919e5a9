"""Workshop files of a tillage_linkage result, written from result.json alone (nothing re-solved).

paths.csv    the tool tip D over one crank turn: time, crank angle, machine frame x, y (roller pair C at the
             origin), ground frame x, y, vx, vy, ax, ay, and the bar angle
linkage.dxf  the linkage at the first position (flywheel centre A and roller pair C fixed to the machine,
             crank pin B, tool tip D; crank A-B and the bar B-D through C, with their lengths), the tool
             path in the machine frame (PATH_MACHINE) and the ground frame (PATH_GROUND) and the ground line
             (GROUND_LINE)
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from synthesis.report import exports
from synthesis.result import Result


def _same_grid(result: Result) -> tuple[dict, dict]:
    tr, extra = result.trajectory, result.extra
    if tr is None or extra is None:
        raise ValueError("the exports need the result's trajectory and facts")
    c = extra["curve"]
    if len(tr["crank_deg"]) != len(c["crank_deg"]) or any(abs(a - b) > 1e-9 for a, b in
                                                          zip(tr["crank_deg"], c["crank_deg"])):
        raise ValueError("the machine-frame curve and the trajectory are sampled on different crank angles")
    return tr, c


def write_paths_csv(result: Result, path: Path) -> None:
    tr, c = _same_grid(result)
    exports.write_csv(path, {"t_s": tr["t"], "crank_deg": tr["crank_deg"], "machine_x_mm": c["x"],
                             "machine_y_mm": c["y"], "ground_x_mm": tr["x"], "ground_y_mm": tr["y"],
                             "ground_vx_mm_s": tr["vx"], "ground_vy_mm_s": tr["vy"],
                             "ax_mm_s2": tr["ax"], "ay_mm_s2": tr["ay"], "bar_angle_deg": c["bar_angle_deg"]})


def write_linkage_dxf(result: Result, path: Path) -> None:
    tr, c = _same_grid(result)
    f = result.extra or {}          # _same_grid has made sure it is there
    pos = f["positions"][0]
    joints: dict[str, Sequence[float]] = {k: tuple(pos[k]) for k in ("A", "B", "C", "D")}
    ground = -f["height_c_mm"]
    xs = list(c["x"]) + list(tr["x"])
    exports.write_linkage_dxf(
        path, joints, ground=("A", "C"), links=(("A", "B"), ("B", "D")),
        curves={"PATH_MACHINE": [list(zip(c["x"], c["y"]))], "PATH_GROUND": [list(zip(tr["x"], tr["y"]))],
                "GROUND_LINE": [[(min(xs), ground), (max(xs), ground)]]},
        note=f"{result.name}: crank angle {pos['crank_deg'] % 360:.2f} deg, machine frame (C at the origin), mm")
