"""Workshop files of a steering_linkage result, written from result.json alone (nothing re-solved).

Plan view: origin mid-way between the kingpins K_L, K_R, x to the right, y forward; a left turn.

paths.csv    over 0 .. the maximum inside lock: inside, outside and Ackermann angles, steering error, and the
             tie-rod ends T_L, T_R (x, y, mm: the straight-ahead steering arms turned with their wheels)
linkage.dxf  the trapezoid straight ahead (kingpins K_L, K_R, tie-rod ends T_L, T_R, arms and tie rod with
             their lengths), at the maximum lock (layer LOCK) and the paths of the tie-rod ends (PATH_T_L,
             PATH_T_R)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from synthesis.report import exports
from synthesis.result import Result


def tie_rod_ends(result: Result) -> dict[str, np.ndarray]:
    """T_L, T_R (2, N) along the curve: each straight-ahead arm K -> T turned by its wheel's steering angle."""
    f = result.extra
    p0, c = f["positions"][0], f["curve"]
    out = {}
    for side, angle in (("L", c["inside_deg"]), ("R", c["outside_deg"])):
        k, t = np.asarray(p0[f"K_{side}"], float), np.asarray(p0[f"T_{side}"], float)
        v = t - k
        a = np.radians(np.asarray(angle, float))
        out[f"T_{side}"] = np.vstack([k[0] + v[0] * np.cos(a) - v[1] * np.sin(a),
                                      k[1] + v[0] * np.sin(a) + v[1] * np.cos(a)])
    return out


def write_paths_csv(result: Result, path: Path) -> None:
    c = result.extra["curve"]
    t = tie_rod_ends(result)
    exports.write_csv(path, {"inside_deg": c["inside_deg"], "outside_deg": c["outside_deg"],
                             "ackermann_deg": c["ackermann_deg"], "error_deg": c["error_deg"],
                             "T_L_x_mm": t["T_L"][0], "T_L_y_mm": t["T_L"][1],
                             "T_R_x_mm": t["T_R"][0], "T_R_y_mm": t["T_R"][1]})


def write_linkage_dxf(result: Result, path: Path) -> None:
    f = result.extra
    p0, lock = f["positions"][0], f["positions"][-1]
    t = tie_rod_ends(result)
    exports.write_linkage_dxf(
        path, {k: tuple(p0[k]) for k in ("K_L", "T_L", "T_R", "K_R")}, ground=("K_L", "K_R"),
        links=(("K_L", "K_R"), ("K_L", "T_L"), ("T_L", "T_R"), ("T_R", "K_R")),
        curves={"LOCK": [[lock[k] for k in ("K_L", "T_L", "T_R", "K_R")]],
                "PATH_T_L": [t["T_L"].T.tolist()], "PATH_T_R": [t["T_R"].T.tolist()]},
        note=(f"{result.name}: straight ahead; layer LOCK at inside {lock['inside_deg']:.1f} deg / outside "
              f"{lock['outside_deg']:.2f} deg; plan view, mm"))
