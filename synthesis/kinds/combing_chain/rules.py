"""Stem-combing rules (seed 002 §四.3): the plant angle before the cut inside a window, over a grid of
initial plant angles and machine speeds, and the tine sweeping up against the crop.

Each builder takes the sampled values (floats for check and re-check, CasADi symbols for the NLP) and
returns one :class:`synthesis.constraints.base.Rule`; a sampled rule's record reports its worst sample.
"""

from __future__ import annotations

from typing import Sequence

from synthesis.constraints.base import Rule, stack

#: typical margin of an angle rule, deg (normalised margins, elastic slack units)
ANGLE_SCALE = 1.0
#: typical margin of a speed rule, m/s
SPEED_SCALE = 0.1


def window_top_rule(name: str, deltas: Sequence, upper: float, where: str) -> Rule:
    """Plant angle before the cut delta <= upper (deg) at every sample."""
    return Rule(name, stack(deltas), None, upper, "deg", ANGLE_SCALE, where)


def window_bottom_rule(name: str, deltas: Sequence, lower: float, where: str) -> Rule:
    """Plant angle before the cut delta >= lower (deg) at every sample."""
    return Rule(name, stack(deltas), lower, None, "deg", ANGLE_SCALE, where)


def tine_reaches_plant_rule(name: str, sweeps: Sequence, where: str) -> Rule:
    """V_r - V_s cos(theta) >= 0 (m/s) at every sampled machine speed: the tine moves up the chain relative
    to the crop (K > cos theta); otherwise it slides back from the plant and never reaches it."""
    return Rule(name, stack(sweeps), 0.0, None, "m/s", SPEED_SCALE, where)
