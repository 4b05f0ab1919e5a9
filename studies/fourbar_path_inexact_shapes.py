"""How the inexact target sets of fourbar_path were drawn.  A study, not part of the installed tool.

The ten target sets the bench and the tests read are data: problems/fourbar_path/inexact.json (read by
synthesis.kinds.fourbar_path.inexact).  This script is how they were made, so the data can be checked or remade::

    python studies/fourbar_path_inexact_shapes.py            # check: the file's points are these shapes' (exit 1 if not)
    python studies/fourbar_path_inexact_shapes.py --write    # rewrite the file's points from the shapes

Each shape is sampled evenly by arc length, scaled to SIZE, turned, centred on CENTRE and, where it is
hand-drawn, every point moved by a seeded random offset (a designer's hand, not a coupler curve); the
points are rounded to 0.001 mm, so the file holds them exactly.  ``--write`` keeps the rest of the file
(the rules of each set, the best known objectives) as it is.
"""

from __future__ import annotations

import json
import math
import os
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

from synthesis.kinds.fourbar_path.construction import joint_positions

DATA = Path(__file__).resolve().parents[1] / "problems" / "fourbar_path" / "inexact.json"
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


def drawn() -> dict[str, dict]:
    """name -> {"closed", "grashof", "order", "points"} as the shapes draw them (points a list of [x, y] mm)."""
    return {name: {"closed": closed, "grashof": grashof, "order": order, "points": points.tolist()}
            for name, (closed, grashof, order, points) in _problems().items()}


def differences(stored: dict) -> list[str]:
    """The sets whose stored name, rules or points differ from the drawn ones (empty: the file is the shapes')."""
    ours = drawn()
    if list(stored) != list(ours):
        return [f"names: the file has {list(stored)}, the shapes {list(ours)}"]
    return [name for name, problem in ours.items()
            if {k: stored[name][k] for k in problem} != problem]


def dumps(data: dict) -> str:
    """The file's text: indented JSON with each point [x, y] on one line."""
    text = json.dumps(data, indent=1)
    return re.sub(r"\[\s+(-?[0-9.e+-]+),\s+(-?[0-9.e+-]+)\s+\]", r"[\1, \2]", text) + "\n"


def write(data: dict) -> None:
    """The file rewritten atomically (a temporary file in its folder, then renamed over it)."""
    fd, tmp = tempfile.mkstemp(dir=DATA.parent, prefix=".inexact.", suffix=".json")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(dumps(data))
        os.replace(tmp, DATA)
    except BaseException:
        os.unlink(tmp)
        raise


def main(argv: list[str]) -> int:
    data = json.loads(DATA.read_text())
    if "--write" in argv:
        for name, problem in drawn().items():
            data["problems"].setdefault(name, {}).update(problem)
        write(data)
        print(f"wrote {DATA}")
        return 0
    wrong = differences(data["problems"])
    for line in wrong:
        print(f"differs: {line}", file=sys.stderr)
    print("the file's target sets are the shapes'" if not wrong else f"{len(wrong)} sets differ")
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
