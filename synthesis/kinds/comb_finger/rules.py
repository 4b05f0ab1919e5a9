"""Comb-finger rules (seed 002 §四.3, eq 17-22): root-zone clearance, room between the two units, the
finger against the other unit over its turn, the unit within its row, the finger hiding in and reaching
out of its drum, the tip reaching the ground line, and an optional tip-speed limit.

Each builder takes values on floats (check, re-check) or CasADi symbols (the NLP) and returns one
:class:`synthesis.constraints.base.Rule`.
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca

from synthesis.constraints.base import Rule, stack, symbolic

#: typical margin of a length rule, mm
LENGTH_SCALE = 10.0


def root_clearance_rule(pd, minimum: float) -> Rule:
    """PD (eq 17) >= minimum, mm."""
    return Rule("root_clearance", pd, minimum, None, "mm", LENGTH_SCALE,
                "root D to the tip circle along D -> R (eq 17)")


def units_gap_rule(gap, minimum: float) -> Rule:
    """Clear width between the left and right drums (cone distance a - 2 rho) >= minimum, mm."""
    return Rule("units_gap", gap, minimum, None, "mm", LENGTH_SCALE, "between the left and right drums")


def finger_clear_rule(distances: Sequence, exact, minimum: float) -> Rule:
    """Distance of a finger tip from the other unit's drum surface >= minimum at every sampled turn angle, mm.
    The optimiser's row is the exact smallest distance over the turn, |R S'| - r - rho (the finger sweeps the
    disc of radius r about its hub R; S' the other drum's axis): no minimum falls between samples."""
    return Rule("finger_clear_of_other_unit", stack(distances), minimum, None, "mm", LENGTH_SCALE,
                "tip to the other unit's drum, over a turn", nlp_rows=((exact, minimum, None),),
                rows_are_the_rule=True)


def unit_within_row_rule(reaches: Sequence, half_spacing: float) -> Rule:
    """Outermost reach of the tip circle and of the drum from the row's centre line <= half the row spacing, mm."""
    return Rule("unit_within_row", stack(reaches), None, half_spacing, "mm", LENGTH_SCALE,
                "outermost tip and drum from the row centre line")


def finger_hides_rule(r, e, rho, hub_inset: float) -> Rule:
    """The finger's innermost tip point (r - e from the drum axis) lies inside the drum and its hub (e from the
    axis) at least ``hub_inset`` inside the drum wall: max(r - e, e + hub_inset) - rho <= 0, mm (smooth rows
    for the optimiser)."""
    on_symbols = symbolic([r, e, rho])
    worst = (ca.fmax(r - e, e + hub_inset) if on_symbols else max(r - e, e + hub_inset)) - rho
    return Rule("finger_hides_in_drum", worst, None, 0.0, "mm", LENGTH_SCALE,
                "innermost tip inside the drum, hub inset from its wall",
                nlp_rows=((r - e - rho, None, 0.0), (e + hub_inset - rho, None, 0.0)), rows_are_the_rule=True)


def finger_protrudes_rule(reach, minimum: float) -> Rule:
    """r + e - rho (how far the finger reaches beyond its drum at full extension, at E) >= minimum, mm."""
    return Rule("finger_protrudes", reach, minimum, None, "mm", LENGTH_SCALE, "at full extension (E)")


def drum_above_ground_rule(b, rho) -> Rule:
    """The drum's lowest point (b - rho: the axis height less the drum radius) on or above the ground line MN: a
    drum below it would plough.  The tip rule does not imply it: the tip reaches lowest below the hub R, which
    sits e sin(alpha) under the drum axis, and the drum radius is free up to r + e - protrusion."""
    return Rule("drum_above_ground", b - rho, 0.0, None, "mm", LENGTH_SCALE, "the drum's lowest point, b - rho")


def tip_reaches_ground_rule(lowest, tolerance: float) -> Rule:
    """0 <= lowest tip height <= tolerance, mm: the finger sweeps the ground line without digging in."""
    return Rule("tip_reaches_ground", lowest, 0.0, tolerance, "mm", max(tolerance, 1.0), "lowest point of the turn")


def tip_speed_rule(speed, maximum: float) -> Rule:
    """Finger tip speed r omega <= maximum, m/s."""
    return Rule("tip_speed", speed, None, maximum, "m/s", 0.1, "r omega")
