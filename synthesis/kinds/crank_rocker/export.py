"""Workshop files of a crank_rocker result, written from result.json alone (nothing re-solved).

The kind has no speed (the crank turns at any rate): the paths are given over the crank angle only.

paths.csv    over one crank turn: crank angle (from G -> A, counter-clockwise), rocker angle, transmission
             angle, crank pin F and rocker pin E (x, y, mm; crank pivot G at the origin, rocker pivot A on +x)
linkage.dxf  the linkage at the folded extreme (pivots G, A, joints F, E, links with their lengths), the crank
             pin's circle (PATH_F) and the rocker pin's arc (PATH_E); the extended extreme on layer EXTENDED
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from synthesis.report import exports
from synthesis.result import Result

LINKS = (("G", "A"), ("G", "F"), ("F", "E"), ("A", "E"))


def _crank_pin(result: Result, crank_deg) -> tuple[np.ndarray, np.ndarray]:
    t = np.radians(np.asarray(crank_deg, dtype=float))
    return result.design["l7"] * np.cos(t), result.design["l7"] * np.sin(t)


def write_paths_csv(result: Result, path: Path) -> None:
    c = result.extra["motion"]["curve"]
    fx, fy = _crank_pin(result, c["crank_deg"])
    # as lists, the column type write_csv takes: the same float64 values, written alike
    exports.write_csv(path, {"crank_deg": c["crank_deg"], "rocker_deg": c["rocker_deg"],
                             "transmission_deg": c["transmission_deg"], "F_x_mm": fx.tolist(), "F_y_mm": fy.tolist(),
                             "E_x_mm": c["E_x"], "E_y_mm": c["E_y"]})


def write_linkage_dxf(result: Result, path: Path) -> None:
    m = result.extra["motion"]
    c = m["curve"]
    fx, fy = _crank_pin(result, c["crank_deg"])
    folded, extended = m["extremes"]["folded"], m["extremes"]["extended"]
    ext = extended["joints"]
    exports.write_linkage_dxf(
        path, {k: tuple(v) for k, v in folded["joints"].items()}, ground=("G", "A"), links=LINKS,
        curves={"PATH_F": [list(zip(fx, fy))], "PATH_E": [list(zip(c["E_x"], c["E_y"]))],
                "EXTENDED": [[ext["G"], ext["F"], ext["E"], ext["A"]]]},
        note=(f"{result.name}: folded extreme (crank {folded['crank_deg'] % 360:.2f} deg), extended on layer "
              f"EXTENDED (crank {extended['crank_deg'] % 360:.2f} deg), mm"))
