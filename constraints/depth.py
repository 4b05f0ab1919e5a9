"""Planting depth (seed 000 §6.2 (2), CNS: 2-3 cm): Y(P4) - Y(P5) within [lo, hi] mm."""

from __future__ import annotations

from constraints.base import Rule, not_evaluated


def depth_rule(y4, y5, bounds: tuple, missing: str | None = None) -> Rule:
    if missing:
        return not_evaluated("planting_depth", *bounds, "mm", "P4 to P5", missing)
    return Rule("planting_depth", y4 - y5, *bounds, "mm", 5.0, "P4 to P5")
