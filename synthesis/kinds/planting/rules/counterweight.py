"""Counterweight clearance: the lowest point of a counterweight over a turn at least a clearance above the soil surface.

A counterweight is a point mass at -radius along its link (``[dynamics] counterweight`` on the crank OA, opposite the
pin A; ``rocker_counterweight`` on the rocker O'B, opposite B).  It turns with the link, so it must pass above the
soil the claw plants in (the ``[soil]`` surface: its ``level``, or ``analysis_depth`` above the lowest claw point P5,
as the soil law reads it): a design whose counterweight ploughs through the soil cannot be built, whatever it does to
the shaking force.  The value is the height of the counterweight's centre above the surface at its lowest (mm,
negative: below the surface), the limit ``[dynamics] counterweight_clearance``.

The crank's counterweight circles the crank pivot O (the origin) at its radius, so its lowest point is exactly
-radius, on floats and in the NLP alike.  The rocker's swings with the rocker: the check takes the lowest point of a
fine grid of the turn refined by a bounded minimisation
(:func:`synthesis.kinds.planting.kinematics.lowest_rocker_counterweight_y`), the NLP one row per sample of its turn
(:func:`synthesis.kinds.planting.kinematics.rocker_counterweight_y_function`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from synthesis.constraints.base import Rule, not_evaluated

#: the typical size of a clearance margin, mm (normalised margins; the NLP's back-off is a fraction of it)
CLEARANCE_SCALE = 10.0
#: the rule's name per counterweight field of [dynamics], and the link it rides on
COUNTERWEIGHTS = {"counterweight": ("crank", "l2"), "rocker_counterweight": ("rocker", "l4")}


@dataclass
class CounterweightReading:
    """One counterweight as the clearance rule reads it: its [dynamics] field (``counterweight`` or
    ``rocker_counterweight``), its heights above the soil surface (mm; a float at its lowest point in the check, one
    per sample of a turn in the NLP), the clearance asked (mm), a caveat on the design (or None), and why it could
    not be read (then ``heights`` is None)."""

    field: str
    heights: Any
    clearance: float
    note: str | None = None
    missing: str | None = None


def counterweight_clearance_rule(reading: CounterweightReading) -> Rule:
    """``<field>_clearance``: the counterweight's lowest height above the soil surface >= the clearance (mm)."""
    link = COUNTERWEIGHTS[reading.field][0]
    name, where = f"{reading.field}_clearance", f"lowest point over a turn ({link}), above the soil surface"
    if reading.missing is not None:
        return not_evaluated(name, reading.clearance, None, "mm", where, reading.missing)
    return Rule(name, reading.heights, reading.clearance, None, "mm", CLEARANCE_SCALE, where, note=reading.note)


def declared(weight, free: bool) -> bool:
    """Whether a counterweight (mass, radius) -- numbers, or the NLP's symbols when ``free`` -- takes the rule: a free
    mass always (the solve may give it any), a given one when it is not zero (a weight of nothing needs no room)."""
    return weight is not None and (free or float(weight[0]) > 0.0)


def longer_than_link(field: str, radius: float, length: float) -> str | None:
    """The caveat on a counterweight further from its pivot than the link is long (allowed: an arm of its own)."""
    if radius <= length:
        return None
    link = COUNTERWEIGHTS[field][0]
    return (f"radius {radius:.4g} mm is longer than the {link} itself ({length:.4g} mm): the counterweight needs an "
            f"arm of its own beyond the {link}'s length")
