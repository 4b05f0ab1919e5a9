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

