"""Workshop files of a cam, written from result.json alone (its ``profile``), one row per 0.1 deg of cam angle.

profile.csv  cam angle (0 = start of the rise), crank angle, working profile x, y, pitch curve x, y (cam frame,
             cam centre at the origin), their distances from the cam centre, the radii of curvature of the
             pitch curve and the working profile (signed: negative where concave; empty where straight), the
             follower's s, v, a (stroke unit: mm or deg, per s, per s^2) and the pressure angle; the last row
             repeats the first at cam angle 360, closing the curve
profile.dxf  the working profile as a closed LWPOLYLINE on layer PROFILE, the pitch curve (PITCH), the base
             circle (BASE_CIRCLE), a centre mark at the cam centre (CENTRE: a cross and a small circle) and,
             for a groove cam only, the outer flank (OUTER); millimetres ($INSUNITS = 4).  ezdxf is imported
             only when a DXF is written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from synthesis.result import Result


def _closed(xy: dict) -> np.ndarray:
    pts = np.column_stack([xy["x"], xy["y"]])
    return np.vstack([pts, pts[:1]])


def write_csv(result: Result, path: Path) -> None:
    from synthesis.report.exports import write_csv as write_columns

    prof = result.extra["profile"]
    rr = float(prof["roller_radius"])
    n = len(prof["cam_angle_deg"])
    close = list(range(n)) + [0]
    kappa = np.asarray(prof["pitch_curvature_1_mm"], dtype=float)
    straight = np.abs(kappa) < 1e-12
    rho = np.where(straight, np.nan, 1.0 / np.where(straight, 1.0, kappa))
    rho_w = rho - rr                          # the working profile lies the roller radius inside the pitch curve
    fol = prof["follower"]
    unit = fol["unit"]
    px, py = np.asarray(prof["pitch"]["x"]), np.asarray(prof["pitch"]["y"])
    wx, wy = np.asarray(prof["working"]["x"]), np.asarray(prof["working"]["y"])
    cols = {"cam_angle_deg": [*prof["cam_angle_deg"], 360.0], "crank_deg": prof["crank_deg"],
            "working_x_mm": wx, "working_y_mm": wy, "pitch_x_mm": px, "pitch_y_mm": py,
            "pitch_r_mm": np.hypot(px, py), "working_r_mm": np.hypot(wx, wy),
            "pitch_radius_of_curvature_mm": rho, "working_radius_of_curvature_mm": rho_w,
            f"s_{unit}": fol["s"], f"v_{unit}_s": fol["v"], f"a_{unit}_s2": fol["a"],
            "pressure_angle_deg": fol["pressure_angle_deg"]}
    out: dict[str, Sequence[Any]] = {}
    for k, v in cols.items():
        v = list(v)
        out[k] = v if k == "cam_angle_deg" else [v[i] for i in close]
    out = {k: [None if isinstance(x, float) and not np.isfinite(x) else x for x in v] for k, v in out.items()}
    write_columns(path, out)


def write_dxf(result: Result, path: Path) -> None:
    import ezdxf

    prof = result.extra["profile"]
    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = 4            # millimetres
    doc.header["$MEASUREMENT"] = 1         # metric
    for layer, colour in (("PROFILE", 7), ("PITCH", 3), ("BASE_CIRCLE", 8), ("CENTRE", 1)):
        doc.layers.add(layer, color=colour)
    msp = doc.modelspace()
    working = np.column_stack([prof["working"]["x"], prof["working"]["y"]])
    msp.add_lwpolyline(working.tolist(), close=True, dxfattribs={"layer": "PROFILE"})
    pitch = np.column_stack([prof["pitch"]["x"], prof["pitch"]["y"]])
    msp.add_lwpolyline(pitch.tolist(), close=True, dxfattribs={"layer": "PITCH"})
    if "outer" in prof:                    # a groove cam: the outer flank (no empty layer otherwise)
        doc.layers.add("OUTER", color=5)
        outer = np.column_stack([prof["outer"]["x"], prof["outer"]["y"]])
        msp.add_lwpolyline(outer.tolist(), close=True, dxfattribs={"layer": "OUTER"})
    msp.add_circle((0.0, 0.0), prof["base_radius"], dxfattribs={"layer": "BASE_CIRCLE"})
    # centre mark: a cross over a fifth of the base radius and a small circle (where the bore is located)
    h = 0.2 * float(prof["base_radius"])
    msp.add_line((-h, 0.0), (h, 0.0), dxfattribs={"layer": "CENTRE"})
    msp.add_line((0.0, -h), (0.0, h), dxfattribs={"layer": "CENTRE"})
    msp.add_circle((0.0, 0.0), 0.25 * h, dxfattribs={"layer": "CENTRE"})
    doc.saveas(path)
