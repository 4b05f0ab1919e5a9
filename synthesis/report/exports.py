"""Workshop files of a linkage, shared by the kinds' ``export`` modules: a CSV of traced paths and a DXF
of the linkage (pivots, links, coupler triangle, joint letters) with the traced curves.

Written from result data only (each kind's ``export`` module picks the joints and curves out of its
result); nothing is re-solved.  Millimetres ($INSUNITS = 4), one layer per kind of entity:

    GROUND    ground pivots: a circle and a cross each
    JOINTS    moving joints: a circle each
    LINKS     one LINE per binary link
    COUPLER   one closed LWPOLYLINE per coupler triangle (a rigid body with three joints)
    LABELS    the joint letters (TEXT) and a note of the position drawn
    PATH_*    one open LWPOLYLINE per traced curve (e.g. PATH_MACHINE, PATH_GROUND)

ezdxf is imported only when a DXF is written.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

LINKAGE_LAYERS = (("GROUND", 7), ("JOINTS", 7), ("LINKS", 5), ("COUPLER", 1), ("LABELS", 8))
PATH_COLOURS = (3, 4, 6, 30, 140)


def write_csv(path: Path, columns: dict[str, Sequence], digits: int = 6) -> None:
    """One column per entry, every column as long as the first; floats with ``digits`` decimals."""
    names = list(columns)
    n = len(columns[names[0]])
    for name in names:
        if len(columns[name]) != n:
            raise ValueError(f"CSV column {name!r} has {len(columns[name])} rows, {names[0]!r} {n}")

    def cell(v) -> str:
        if isinstance(v, str):
            return v
        if v is None:
            return ""
        return f"{float(v):.{digits}f}"

    lines = [",".join(names)] + [",".join(cell(columns[c][i]) for c in names) for i in range(n)]
    path.write_text("\n".join(lines) + "\n")


def write_linkage_dxf(path: Path, joints: dict[str, Sequence[float]], *, ground: Iterable[str],
                      links: Iterable[tuple[str, str]], couplers: Iterable[tuple[str, ...]] = (),
                      curves: dict[str, Sequence[Sequence[Sequence[float]]]] | None = None,
                      note: str = "", closed: Iterable[str] = ()) -> None:
    """The linkage at one position (``joints``: name -> (x, y) mm) and the traced ``curves``
    (layer -> list of polylines, each a list of (x, y)); ``closed`` names curve layers to close."""
    import ezdxf

    curves = curves or {}
    closed = set(closed)
    ground = [g for g in ground if g in joints]
    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = 4            # millimetres
    doc.header["$MEASUREMENT"] = 1         # metric
    links, couplers = list(links), list(couplers)
    used = {"GROUND": bool(ground), "JOINTS": any(n not in ground for n in joints), "LINKS": bool(links),
            "COUPLER": bool(couplers), "LABELS": True}
    for layer, colour in LINKAGE_LAYERS:   # only layers that hold something: no empty layer in the drawing
        if used[layer]:
            doc.layers.add(layer, color=colour)
    for k, layer in enumerate(curves):
        doc.layers.add(layer, color=PATH_COLOURS[k % len(PATH_COLOURS)])
    msp = doc.modelspace()
    pts = np.array([joints[n] for n in joints], dtype=float).reshape(-1, 2)
    everything = [pts] + [np.asarray(p, float).reshape(-1, 2) for polys in curves.values() for p in polys]
    allpts = np.vstack([p for p in everything if p.size])
    span = float(max(np.ptp(allpts[:, 0]), np.ptp(allpts[:, 1]), 1.0))
    r = max(0.012 * span, 0.5)             # joint circle radius, mm: visible at the drawing's scale
    for name, (x, y) in joints.items():
        x, y = float(x), float(y)
        if name in ground:
            msp.add_circle((x, y), 1.5 * r, dxfattribs={"layer": "GROUND"})
            msp.add_line((x - 2.5 * r, y), (x + 2.5 * r, y), dxfattribs={"layer": "GROUND"})
            msp.add_line((x, y - 2.5 * r), (x, y + 2.5 * r), dxfattribs={"layer": "GROUND"})
        else:
            msp.add_circle((x, y), r, dxfattribs={"layer": "JOINTS"})
        msp.add_text(name, height=2.0 * r, dxfattribs={"layer": "LABELS", "insert": (x + 1.8 * r, y + 1.8 * r)})
    for a, b in links:
        pa, pb = joints[a], joints[b]
        length = math.dist(pa, pb)
        msp.add_line(tuple(map(float, pa)), tuple(map(float, pb)), dxfattribs={"layer": "LINKS"})
        mid = ((pa[0] + pb[0]) / 2 + 1.2 * r, (pa[1] + pb[1]) / 2 - 1.2 * r)
        msp.add_text(f"{a}-{b} {length:.2f}", height=1.4 * r,
                     dxfattribs={"layer": "LABELS", "insert": tuple(map(float, mid))})
    for tri in couplers:
        msp.add_lwpolyline([tuple(map(float, joints[n])) for n in tri], close=True, dxfattribs={"layer": "COUPLER"})
    for layer, polys in curves.items():
        for poly in polys:
            p = np.asarray(poly, float).reshape(-1, 2)
            p = p[np.all(np.isfinite(p), axis=1)]
            if len(p) >= 2:
                msp.add_lwpolyline(p.tolist(), close=layer in closed, dxfattribs={"layer": layer})
    if note:
        msp.add_text(note, height=1.6 * r, dxfattribs={"layer": "LABELS",
                                                       "insert": (float(allpts[:, 0].min()),
                                                                  float(allpts[:, 1].min()) - 5 * r)})
    doc.saveas(path)
