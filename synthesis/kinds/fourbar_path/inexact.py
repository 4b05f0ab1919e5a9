"""Path-synthesis problems no four-bar fits exactly: shapes a designer would draw.

Ten target sets of 12-25 points, closed loops and open arcs, about 60 mm across, with the wide bounds
of the free-timing study (every link in [0.05, 6] x the loop's diameter D, coupler point within +-5 D of A, input
pivot within +-6 D of the loop's centre), free timing, grashof "any" or "crank_rocker".  Each shape
is sampled evenly by arc length and, where it says "hand-drawn", every point is moved by a seeded
random offset (a designer's hand, not a coupler curve): no target set here lies on a four-bar's
coupler curve, so the optimum has a positive error and many local optima.

Everything is a function of the problem's name; ``inexact_spec(name)`` is what ``agrisynth solve``
would see.  The bench (``agrisynth bench fourbar_path``) runs them with the library specs; the best
known objective of each is in BEST_KNOWN (see problems/fourbar_path/INEXACT.md).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.library import LIBRARY
from synthesis.spec import LoadedSpec
from synthesis.spec.common import validate
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

CENTRE = (100.0, 50.0)     # mm: every shape is centred here
SIZE = 60.0                # mm: its largest extent


# ---------------------------------------------------------------------------- shapes (unit size, closed or open)

def _ellipse(t):
    return np.cos(t), 0.5 * np.sin(t)


def _egg(t):
    return np.cos(t) * (1.0 + 0.25 * np.sin(t)), 0.75 * np.sin(t)


def _rounded_triangle(t):
    r = 1.0 + 0.18 * np.cos(3.0 * t)
    return r * np.cos(t), r * np.sin(t)


def _kidney(t):
    r = 1.0 - 0.35 * np.cos(2.0 * t) + 0.15 * np.cos(t)
    return r * np.cos(t), 0.8 * r * np.sin(t)


def _d_shape(t):
    # a half disc (the round side) closed by a straight chord: superellipse-rounded corners
    x, y = np.cos(t), np.sin(t)
    x = np.where(x < -0.2, -0.2 - 0.08 * (1.0 - np.abs(y)) ** 4, x)    # flat left side
    return x, 0.9 * y


def _rounded_square(t):
    c, s = np.cos(t), np.sin(t)
    p = 6.0
    r = (np.abs(c) ** p + np.abs(s) ** p) ** (-1.0 / p)
    return r * c, r * s


def _s_curve(t):
    return t, 0.35 * np.sin(math.pi * t)


def _straight_then_lift(t):
    # a straight stroke followed by a lift (a planting claw's push and return-free exit)
    return t, np.where(t < 0.5, 0.0, 0.6 * (t - 0.5) ** 2)


def _by_arc_length(shape, n: int, closed: bool, lo: float = 0.0, hi: float = 2.0 * math.pi,
                   dense: int = 4000) -> np.ndarray:
    """n points of the parametric shape evenly spaced by arc length (a closed shape: n over the loop)."""
    t = np.linspace(lo, hi, dense)
    x, y = shape(t)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    at = np.linspace(0.0, s[-1], n, endpoint=not closed)
    return np.column_stack([np.interp(at, s, x), np.interp(at, s, y)])


def _dwell_arc(n: int) -> np.ndarray:
    """An open arc of 150 deg: evenly spaced points, but the middle fifth of them crowded on 10 deg."""
    k = np.arange(n) / (n - 1)
    u = np.where(k < 0.4, k / 0.4 * 0.45, np.where(k > 0.6, 0.55 + (k - 0.6) / 0.4 * 0.45,
                                                    0.45 + (k - 0.4) / 0.2 * 0.1))
    a = np.radians(15.0 + 150.0 * u)
    return np.column_stack([np.cos(a), np.sin(a)])


def _placed(points: np.ndarray, turn_deg: float, jitter: float, seed: int) -> np.ndarray:
    """The unit shape scaled to SIZE, turned, centred on CENTRE, each point moved by a seeded offset
    (jitter x SIZE, uniform in a disc: a hand-drawn target)."""
    p = np.asarray(points, float)
    p = p - 0.5 * (p.min(axis=0) + p.max(axis=0))
    p = p * (SIZE / max(np.ptp(p[:, 0]), np.ptp(p[:, 1])))
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    p = p @ np.array([[c, s], [-s, c]])
    if jitter > 0:
        rng = np.random.default_rng(seed)
        r = jitter * SIZE * np.sqrt(rng.random(len(p)))
        a = rng.uniform(0.0, 2.0 * math.pi, len(p))
        p = p + np.column_stack([r * np.cos(a), r * np.sin(a)])
    return np.round(p + np.array(CENTRE), 3)


def _noisy_coupler(n: int, seed: int, closed: bool) -> np.ndarray:
    """n points of a crank-rocker's coupler curve (over a turn, or 150 deg of crank) moved 1.5 % of SIZE."""
    design = {"r1": 40.0, "r2": 12.0, "r3": 38.0, "r4": 30.0, "rcx": 25.0, "rcy": 18.0, "x0": 0.0, "y0": 0.0,
              "theta0": 10.0}
    crank = np.linspace(0.0, 360.0, n, endpoint=False) if closed else np.linspace(40.0, 190.0, n)
    z = joint_positions(design, np.radians(crank), branch=1)["P"]
    return _placed(np.column_stack([z.real, z.imag]), 0.0, 0.015, seed)


#: name -> (closed, grashof, order, points)
def _problems() -> dict[str, tuple[bool, str, bool, np.ndarray]]:
    return {
        "ellipse20": (True, "any", False, _placed(_by_arc_length(_ellipse, 20, True), 20.0, 0.01, 1)),
        "egg16": (True, "crank_rocker", False, _placed(_by_arc_length(_egg, 16, True), -30.0, 0.01, 2)),
        "triangle18": (True, "any", False, _placed(_by_arc_length(_rounded_triangle, 18, True), 0.0, 0.01, 3)),
        "d_shape22": (True, "crank_rocker", False, _placed(_by_arc_length(_d_shape, 22, True), 90.0, 0.005, 4)),
        "kidney25": (True, "any", False, _placed(_by_arc_length(_kidney, 25, True), 0.0, 0.005, 5)),
        "square24": (True, "crank_rocker", True, _placed(_by_arc_length(_rounded_square, 24, True), 15.0, 0.0, 6)),
        "noisy_loop20": (True, "any", False, _noisy_coupler(20, 7, closed=True)),
        "dwell_arc15": (False, "any", True, _placed(_dwell_arc(15), 0.0, 0.005, 8)),
        "s_curve12": (False, "crank_rocker", True,
                      _placed(_by_arc_length(_s_curve, 12, False, -1.0, 1.0), 10.0, 0.005, 9)),
        "stroke_lift14": (False, "any", False,
                          _placed(_by_arc_length(_straight_then_lift, 14, False, 0.0, 1.2), 0.0, 0.005, 10)),
    }


NAMES = tuple(_problems())


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


#: best objective known for each problem (mm^2): the lowest any run found with every rule holding on the fine grid --
#: the runs of problems/fourbar_path/INEXACT.md (64 and 16 starts, seed 0, before and after the free-timing changes, and
#: of an earlier attempt) and the 2,000-start cross-check the study asked for (seed 7, 2 workers;
#: fourth and fifth pass), which ran on all ten: it found d_shape22's (start 1715), dwell_arc15's (start 1165) and
#: stroke_lift14's (start 333) below every 64-start run, and agreed with the others.  Later passes lowered
#: dwell_arc15's and stroke_lift14's again (the notes in the dict below), stroke_lift14's by basin hopping from its
#: recorded design (eighth pass), triangle18's and stroke_lift14's last by runs whose every start is a screened shape
#: (ninth pass): the production starts had not proposed those basins.
BEST_KNOWN: dict[str, float] = {
    "ellipse20": 1.0486382171183883, "egg16": 0.46122510610392164,
    # triangle18 (12.4805 -> 3.89328) and stroke_lift14 (0.202531 -> 0.147114) lowered by the ninth pass's runs with
    # every start from the screen (starts.STRATEGY = "screen", a study switch; 512 starts seed 9, 64 starts seed 1): a
    # self-crossing three-lobed coupler curve of a double-crank, and a rocking crank whose one sweep meets the targets
    # out of their drawn order, ending at its dead position (order = false allows both)
    "triangle18": 3.8932754809803853,
    # kidney25: lowered on 2026-11-25 by a run of the study's fourth pass; d_shape22, dwell_arc15 and stroke_lift14 by
    # the 2,000-start cross-check (seed 7; d_shape22 start 1715, a change-point kite, crank 239 mm; dwell_arc15 start
    # 1165, a non-Grashof linkage, at IPOPT's max_iter; stroke_lift14 start 333); every rule holding on the fine grid
    # (INEXACT.md; the designs: BEST_DESIGNS).  dwell_arc15 lowered again (0.0591035 -> 0.0566724) by the
    # configuration form (natural.py, sixth pass) from that design: both end targets at the crank's dead positions;
    # stroke_lift14 lowered again (0.258968 -> 0.235265) by the sixth pass's 2,000-start cross-check (seed 7, start
    # 39: a screened linkage whose crank only rocks), which agreed on dwell_arc15; stroke_lift14 lowered once more
    # (0.235265 -> 0.202531) by basin hopping from that design (eighth pass: jittered shapes laid by the rocking screen;
    # the same hopping from dwell_arc15's best found nothing lower), and to 0.147114 by the ninth pass (above)
    "d_shape22": 10.050598691214857, "kidney25": 11.854077742761099, "square24": 137.6917138934006,
    "noisy_loop20": 2.3719628395676278, "dwell_arc15": 0.0566724090275194, "s_curve12": 2.183892490339011,
    "stroke_lift14": 0.14711361512869858,
}

#: the designs behind BEST_KNOWN that a run found below the earlier best known (design, crank angles, direction)
BEST_DESIGNS = LIBRARY / "fourbar_path" / "inexact_best_designs.json"


def best_known_designs() -> dict[str, dict]:
    """name -> {"objective_mm2", "found_by", "return_status", "design", "crank_deg", "direction"} (BEST_DESIGNS)."""
    return json.loads(BEST_DESIGNS.read_text())["designs"]
