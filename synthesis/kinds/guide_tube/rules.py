"""Guide-tube rules (seed 001 §2.4): equal landing times, plant-position error, sliding off the wall.

Built on floats (check) each gives a record; built on CasADi symbols (solve) its ``nlp_rows`` are
smooth: the spread max - min becomes pairwise differences, the exit speed its square.
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca

from synthesis.constraints.base import Rule, stack


def _spread(times: Sequence):
    hi, lo = times[0], times[0]
    for t in times[1:]:
        hi, lo = ca.fmax(hi, t), ca.fmin(lo, t)
    return hi - lo


def landing_time_spread_rule(times: Sequence, limit: float, spacing: float, equalise: bool = True) -> Rule:
    """Latest minus earliest landing time of the tubes (s) <= limit.  With ``equalise`` the optimiser
    is asked for exactly equal times (t_k - t_0 = 0), the paper's design condition, except in a tolerance box
    (``box_rows``); without, for pairwise differences within the limit."""
    within = tuple((times[i] - times[j], -limit, limit) for i in range(len(times)) for j in range(i + 1, len(times)))
    rows = tuple((t - times[0], 0.0, 0.0) for t in times[1:]) if equalise else within
    # in a tolerance box equal times cannot hold at every corner: there the rule's own limit is held
    return Rule("landing_time_spread", _spread(times), None, limit, "s", limit,
                f"at row spacing {spacing:g} mm", nlp_rows=rows, box_rows=within if equalise else ())


def spacing_error_rule(times_by_spacing: Sequence[Sequence], spacings: Sequence[float], forward_mm_s: float,
                       limit: float) -> Rule:
    """Forward speed x landing-time spread (mm): how far apart along the row the plants dropped in
    one cycle land, at every sampled row spacing, <= limit."""
    values = [forward_mm_s * _spread(times) for times in times_by_spacing]
    rows = tuple((forward_mm_s * (times[i] - times[j]), -limit, limit)
                 for times in times_by_spacing for i in range(len(times)) for j in range(i + 1, len(times)))
    return Rule("spacing_error", stack(values), None, limit, "mm", limit,
                f"over row spacings {min(spacings):g}-{max(spacings):g} mm", nlp_rows=rows)


def wall_exit_speed_rule(tube: str, exit_speed_sq: Sequence, minimum: float) -> Rule:
    """Speed along the wall at its lower end (m/s) >= minimum: the seedling slides off, never sticks."""
    speeds = [ca.sqrt(ca.fmax(v, 0.0)) for v in exit_speed_sq]
    rows = tuple((v, minimum * minimum, None) for v in exit_speed_sq)
    return Rule(f"wall_exit_speed_{tube}", stack(speeds), minimum, None, "m/s", max(minimum, 0.1),
                "at the wall end, every sampled row spacing", nlp_rows=rows, row_unit="m^2/s^2")


def free_fall_height_rule(tube: str, heights_mm: Sequence, minimum: float) -> Rule:
    """Free fall h1 from the drop point to the wall (mm) >= minimum (> 0 is required by the model)."""
    return Rule(f"free_fall_height_{tube}", stack(heights_mm), minimum, None, "mm", 10.0,
                "drop point to the wall, every sampled row spacing")
