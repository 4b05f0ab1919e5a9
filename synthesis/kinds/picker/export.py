"""Workshop files of the picker kinds, written from result.json alone (nothing re-solved).

picker_double_crank (no speed: over the crank angle only)
  paths.csv    clamp point M over one turn of crank AB: crank angle, x, y (mm, machine frame)
  linkage.dxf  the double crank at the picking position (pivots A, D, joints B, C, clamp point M, links
               with their lengths, coupler triangle B-C-M), the coupler curve (PATH_COUPLER) and the
               stretch the drive uses (PATH_DRIVEN)
picker (crank GF at the spec's speed)
  paths.csv    clamp point M over one turn of GF: time, crank GF angle, crank AB angle, x, y, vx, vy, ax, ay
  linkage.dxf  both linkages at picking (t = 0: pivots A, D, G; coupler triangle B-C-M; rocker arm A-B-E
               as a rigid body) and M's trajectory (PATH_M)
"""

from __future__ import annotations

from pathlib import Path

from synthesis.report import exports
from synthesis.result import Result

DOUBLE_CRANK = (("A", "D"), ("A", "B"), ("B", "C"), ("C", "D"), ("C", "M"), ("B", "M"))
DRIVE = (("A", "G"), ("G", "F"), ("F", "E"), ("A", "E"))


def write_double_crank_csv(result: Result, path: Path) -> None:
    c = result.extra["coupler_curve"]
    exports.write_csv(path, {"crank_deg": c["crank_deg"], "x_mm": c["x"], "y_mm": c["y"]})


def write_double_crank_dxf(result: Result, path: Path) -> None:
    f = result.extra
    pos = f["positions"][0]
    exports.write_linkage_dxf(
        path, {k: tuple(v) for k, v in pos["joints"].items()}, ground=("A", "D"), links=DOUBLE_CRANK,
        couplers=[("B", "C", "M")],
        curves={"PATH_COUPLER": [list(zip(f["coupler_curve"]["x"], f["coupler_curve"]["y"]))],
                "PATH_DRIVEN": [list(zip(f["path"]["x"], f["path"]["y"]))]},
        note=f"{result.name}: double crank at crank AB {pos['crank_deg'] % 360:.2f} deg (picking), machine frame, mm")


def write_picker_csv(result: Result, path: Path) -> None:
    tr = result.trajectory
    assert tr is not None, "a picker result carries its trajectory (combined.run_check writes it)"
    exports.write_csv(path, {"t_s": tr["t"], "crank_gf_deg": tr["crank_deg"], "crank_ab_deg": tr["crank_ab_deg"],
                             "x_mm": tr["x"], "y_mm": tr["y"], "vx_mm_s": tr["vx"], "vy_mm_s": tr["vy"],
                             "ax_mm_s2": tr["ax"], "ay_mm_s2": tr["ay"]})


def write_picker_dxf(result: Result, path: Path) -> None:
    tr, frame = result.trajectory, result.extra["frames"][0]
    assert tr is not None, "a picker result carries its trajectory (combined.run_check writes it)"
    exports.write_linkage_dxf(
        path, {k: tuple(v) for k, v in frame["joints"].items()}, ground=("A", "D", "G"), links=DOUBLE_CRANK + DRIVE,
        couplers=[("B", "C", "M"), ("A", "B", "E")], curves={"PATH_M": [list(zip(tr["x"], tr["y"]))]},
        note=f"{result.name}: picker at t = {frame['t']:.3f} s (picking), machine frame, mm")
