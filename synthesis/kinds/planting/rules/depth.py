"""Planting depth, Y(P4) - Y(P5) within [lo, hi] mm (CNS: 2-3 cm, seed 000 §4, the analysis assumptions (3)).

Our reading: seed 000 says P5, the lowest point, sets the depth (§2) and puts the ground 2.5 cm above the path's
lowest point for its analysis; it does not define the depth as Y(P4) - Y(P5).  Where the ground is placed that way
(a check at the analysis depth) the rule equals that depth by construction; it constrains a design only where the
ground is given apart from the path."""

from __future__ import annotations

from synthesis.constraints.base import Rule, not_evaluated


def depth_rule(y4, y5, bounds: tuple[float, float], missing: str | None = None) -> Rule:
    if missing:
        return not_evaluated("planting_depth", *bounds, "mm", "P4 to P5", missing)
    return Rule("planting_depth", y4 - y5, *bounds, "mm", 5.0, "P4 to P5")
