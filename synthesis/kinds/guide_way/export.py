"""Workshop files of a guide way, written from result.json alone (its ``facts.curves``).

centre_line.csv  stretch, arm angle, roller centre x, y (mm), in time order
walls.csv        stretch, arm angle, left wall x, y, right wall x, y (mm): the two offsets of the centre
                 line by the roller radius (left/right of the claw's direction of motion)
guide_way.dxf    layer CENTRE: the roller-centre line (one open polyline per stretch: the paper's conics
                 meet with jumps); layers LEFT_WALL, RIGHT_WALL: the walls; layer GROOVE: the closed outline
                 of each stretch (left wall, round end, right wall back, round end); layer CLAW: the claw
                 path.  Millimetres ($INSUNITS = 4).  ezdxf is imported only when a DXF is written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from synthesis.result import Result


def write_centre_csv(result: Result, path: Path) -> None:
    lines = ["stretch,theta_deg,x_mm,y_mm"]
    for c in result.extra["curves"]:
        for th, x, y in zip(c["theta_deg"], c["centre_x"], c["centre_y"]):
            lines.append(f"{c['name']},{th % 360.0:.6f},{x:.6f},{y:.6f}")
    path.write_text("\n".join(lines) + "\n")


def write_walls_csv(result: Result, path: Path) -> None:
    lines = ["stretch,theta_deg,left_x_mm,left_y_mm,right_x_mm,right_y_mm"]
    for c in result.extra["curves"]:
        for th, lx, ly, rx, ry in zip(c["theta_deg"], c["left_x"], c["left_y"], c["right_x"], c["right_y"]):
            lines.append(f"{c['name']},{th % 360.0:.6f},{lx:.6f},{ly:.6f},{rx:.6f},{ry:.6f}")
    path.write_text("\n".join(lines) + "\n")


def _cap(centre, start, end, n: int = 16) -> list:
    """Half circle about ``centre`` from ``start`` to ``end`` (both on it), clockwise: from the left wall to the
    right one round the front of the last point, from the right to the left round the back of the first."""
    cx, cy = centre
    a0 = np.arctan2(start[1] - cy, start[0] - cx)
    r = float(np.hypot(start[0] - cx, start[1] - cy))
    a1 = np.arctan2(end[1] - cy, end[0] - cx)
    sweep = (a0 - a1) % (2 * np.pi)
    a = a0 - np.linspace(0.0, sweep, n)[1:-1]
    return list(zip(cx + r * np.cos(a), cy + r * np.sin(a)))


def write_dxf(result: Result, path: Path) -> None:
    import ezdxf

    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = 4            # millimetres
    doc.header["$MEASUREMENT"] = 1         # metric
    for layer, colour in (("CENTRE", 1), ("LEFT_WALL", 5), ("RIGHT_WALL", 3), ("GROOVE", 7), ("CLAW", 8)):
        doc.layers.add(layer, color=colour)
    msp = doc.modelspace()
    for c in result.extra["curves"]:
        pts = {k: list(zip(c[f"{k}_x"], c[f"{k}_y"])) for k in ("centre", "left", "right", "claw")}
        msp.add_lwpolyline(pts["centre"], dxfattribs={"layer": "CENTRE"})
        msp.add_lwpolyline(pts["left"], dxfattribs={"layer": "LEFT_WALL"})
        msp.add_lwpolyline(pts["right"], dxfattribs={"layer": "RIGHT_WALL"})
        msp.add_lwpolyline(pts["claw"], dxfattribs={"layer": "CLAW"})
        # the groove of one stretch as one closed outline: left wall, round end about the last centre point,
        # right wall backwards, round end about the first
        outline = (pts["left"] + _cap(pts["centre"][-1], pts["left"][-1], pts["right"][-1])
                   + pts["right"][::-1] + _cap(pts["centre"][0], pts["right"][0], pts["left"][0]))
        msp.add_lwpolyline(outline, close=True, dxfattribs={"layer": "GROOVE"})
    doc.saveas(path)
