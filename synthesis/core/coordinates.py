"""Whether a solved design stays in its spec's bounds when an NLP holds the bounds of some design variables as rows
(a kind whose NLP works in other coordinates than the design, such as :mod:`synthesis.kinematics.grashof`'s)."""

from __future__ import annotations

import numpy as np


#: a length held as a row may miss its bounds by IPOPT's constraint tolerance; beyond this (relative to
#: max(1, |bound|)) the design is outside them
BOUND_TOLERANCE = 1e-6


def outside_bounds(names, box: np.ndarray, design: dict) -> str | None:
    """Why ``design`` is not a design of the spec: "l10 = 161.37 lies outside its bounds [140, 140] (...)" for the
    first variable of ``names`` beyond its row of ``box`` (n x 2, spec units), else None.  With such coordinates
    the lengths' bounds are rows, which a start IPOPT stops without meeting (infeasible, iteration limit) may leave:
    its design has then moved even the lengths the spec fixes, and is no candidate."""
    for name, (lo, hi) in zip(names, np.asarray(box, float)):
        value = design.get(name)
        if value is None:
            continue
        if value < lo - BOUND_TOLERANCE * max(1.0, abs(lo)) or value > hi + BOUND_TOLERANCE * max(1.0, abs(hi)):
            where = f"its fixed value {lo:g}" if lo == hi else f"its bounds [{lo:g}, {hi:g}]"
            off = lo - value if value < lo else value - hi        # the digits that show it: 200.0003, not 200
            return (f"{name} = {value:.10g} lies {off:.2g} outside {where}: IPOPT stopped without meeting the rows "
                    f"that hold the link lengths, so this is no design of the spec")
    return None


#: the rounding of a design map's arithmetic, relative: a few units in the last place of its terms (a length and
#: slacks of up to a few times its size), far below any tolerance IPOPT works to
FIXED_ROUNDING = 1e-13


def fixed_as_given(names, box: np.ndarray, design: dict) -> dict:
    """``design`` with each fixed variable of ``names`` (its row of ``box`` lo = hi, spec units) that lies within
    :data:`FIXED_ROUNDING` of its value set to that value, in place.  A design map through other coordinates (the
    Grashof slacks) gives a fixed length back through a sum, a unit in the last place off: 140 mm as
    139.99999999999997 in a start's row and in solved.toml.  Further off is IPOPT's doing (its rows hold such a
    length to 1e-8 and beyond) and stays, for the verdict (:func:`outside_bounds`) to judge."""
    for name, (lo, hi) in zip(names, np.asarray(box, float)):
        value = design.get(name)
        if lo == hi and isinstance(value, float) and value != lo and abs(value - lo) <= FIXED_ROUNDING * abs(lo):
            design[name] = float(lo)
    return design
