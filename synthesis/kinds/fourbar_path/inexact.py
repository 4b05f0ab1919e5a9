"""Path-synthesis problems no four-bar fits exactly: shapes a designer would draw.

Ten target sets of 12-25 points, closed loops and open arcs, about 60 mm across, with the wide bounds
of the free-timing study (every link in [0.05, 6] x the loop's diameter D, coupler point within +-5 D of A, input
pivot within +-6 D of the loop's centre), free timing, grashof "any" or "crank_rocker".  The points are data,
problems/fourbar_path/inexact.json (DATA): shapes sampled evenly by arc length and, where hand-drawn, every point
moved by a seeded random offset (a designer's hand, not a coupler curve; studies/fourbar_path_inexact_shapes.py
drew them): no target set here lies on a four-bar's coupler curve, so the optimum has a positive error and many
local optima.

Everything is a function of the problem's name; ``inexact_spec(name)`` is what ``agrisynth solve``
would see.  The bench (``agrisynth bench fourbar_path``) runs them with the library specs; the best
known objective of each is in BEST_KNOWN (see problems/fourbar_path/INEXACT.md).
"""

from __future__ import annotations

import hashlib
import json
from functools import lru_cache
from pathlib import Path

import numpy as np

from synthesis.library import LIBRARY
from synthesis.spec import LoadedSpec
from synthesis.spec.common import validate
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

#: the target sets (their rules and points) and the best known objectives
DATA = LIBRARY / "fourbar_path" / "inexact.json"


@lru_cache(maxsize=1)
def _data() -> dict:
    return json.loads(DATA.read_text())


def _problems() -> dict[str, tuple[bool, str, bool, np.ndarray]]:
    """name -> (closed, grashof, order, (N, 2) points in mm), in the file's order."""
    return {name: (p["closed"], p["grashof"], p["order"], np.array(p["points"], dtype=float))
            for name, p in _data()["problems"].items()}


NAMES = tuple(_data()["problems"])


def inexact_data(name: str, solver: dict | None = None) -> dict:
    """The spec (as TOML-like data) of the named problem: wide bounds around the target's size."""
    closed, grashof, order, points = _problems()[name]
    cx, cy = 0.5 * (points.min(axis=0) + points.max(axis=0))
    d = float(max(np.ptp(points[:, 0]), np.ptp(points[:, 1])))
    link = [round(0.05 * d, 3), round(6.0 * d, 3)]
    bounds = {"r1": link, "r2": link, "r3": link, "r4": link,
              "rcx": [round(-5 * d, 3), round(5 * d, 3)], "rcy": [round(-5 * d, 3), round(5 * d, 3)],
              "x0": [round(cx - 6 * d, 3), round(cx + 6 * d, 3)], "y0": [round(cy - 6 * d, 3), round(cy + 6 * d, 3)],
              "theta0": [0, 360]}
    shape = "closed loop" if closed else "open arc"
    return {"kind": "fourbar_path", "name": f"inexact_{name}",
            "source": f"inexact target: {shape} of {len(points)} points, {d:.0f} mm across "
                      f"(synthesis.kinds.fourbar_path.inexact)",
            "targets": {"points": points.tolist()},
            # every variable free in its box, started at the box's midpoint (the given design, start 0)
            "linkage": {n: {"init": round(0.5 * (lo + hi), 3), "bounds": [lo, hi]} for n, (lo, hi) in bounds.items()},
            "rules": {"grashof": grashof, "order": order}, "solver": dict(solver or {})}


def inexact_spec(name: str, solver: dict | None = None) -> LoadedSpec:
    """The named problem as a loaded spec (what ``agrisynth solve`` would see)."""
    data = inexact_data(name, solver)
    model = validate(FourbarPathSpec, data, prefix="fourbar_path")
    sha = hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()
    return LoadedSpec(model, Path(f"<{data['name']}>"), sha)


#: best objective known for each problem (mm^2): the lowest any recorded run found with every rule holding on the fine
#: grid -- 64-start runs, the 2,000-start cross-check (seed 7) and runs whose every start was a screened shape; how each
#: was found is in DATA ("found_by") and INEXACT.md
BEST_KNOWN: dict[str, float] = {name: float(v["objective_mm2"]) for name, v in _data()["best_known"].items()}

#: the designs behind BEST_KNOWN that a run found below the earlier best known (design, crank angles, direction)
BEST_DESIGNS = LIBRARY / "fourbar_path" / "inexact_best_designs.json"


def best_known_designs() -> dict[str, dict]:
    """name -> {"objective_mm2", "found_by", "return_status", "design", "crank_deg", "direction"} (BEST_DESIGNS)."""
    return json.loads(BEST_DESIGNS.read_text())["designs"]
