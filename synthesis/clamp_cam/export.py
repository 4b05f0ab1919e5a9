"""Workshop files of a cam: the working profile as CSV (x, y in mm, closed) and as a DXF polyline.

Both are written from result.json alone (its ``profile``), one point per 0.1 deg of cam angle.
The DXF holds the working profile as a closed LWPOLYLINE on layer PROFILE, the pitch curve and the
base circle for reference on their own layers, in millimetres ($INSUNITS = 4).  ezdxf is imported
only when a DXF is written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from synthesis.result import Result


def _closed(xy: dict) -> np.ndarray:
    pts = np.column_stack([xy["x"], xy["y"]])
    return np.vstack([pts, pts[:1]])


def write_csv(result: Result, path: Path) -> None:
    """x_mm,y_mm of the working profile in the cam frame (cam centre at the origin); the last row repeats
    the first, closing the curve."""
    pts = _closed(result.extra["profile"]["working"])
    lines = ["x_mm,y_mm"] + [f"{x:.6f},{y:.6f}" for x, y in pts]
    path.write_text("\n".join(lines) + "\n")


def write_dxf(result: Result, path: Path) -> None:
    import ezdxf

    prof = result.extra["profile"]
    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = 4            # millimetres
    doc.header["$MEASUREMENT"] = 1         # metric
    for layer, colour in (("PROFILE", 7), ("PITCH", 3), ("BASE_CIRCLE", 8), ("OUTER", 5)):
        doc.layers.add(layer, color=colour)
    msp = doc.modelspace()
    working = np.column_stack([prof["working"]["x"], prof["working"]["y"]])
    msp.add_lwpolyline(working.tolist(), close=True, dxfattribs={"layer": "PROFILE"})
    pitch = np.column_stack([prof["pitch"]["x"], prof["pitch"]["y"]])
    msp.add_lwpolyline(pitch.tolist(), close=True, dxfattribs={"layer": "PITCH"})
    if "outer" in prof:
        outer = np.column_stack([prof["outer"]["x"], prof["outer"]["y"]])
        msp.add_lwpolyline(outer.tolist(), close=True, dxfattribs={"layer": "OUTER"})
    msp.add_circle((0.0, 0.0), prof["base_radius"], dxfattribs={"layer": "BASE_CIRCLE"})
    doc.saveas(path)
