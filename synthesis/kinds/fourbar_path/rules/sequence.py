"""Sequence of the input angles (path synthesis with free timing): the crank meets the targets in
their given order, turning one way, within one turn.

With s = +1 (counter-clockwise) or -1 (clockwise):  s (theta_{i+1} - theta_i) >= 0 for every i, and
360 - s (theta_N - theta_1) >= 0.  Linear in the angles.  Value: the smallest of these slacks (deg).
"""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule


def sequence_slacks(theta_deg: list, sign) -> list:
    """[s (theta_2 - theta_1), ..., s (theta_N - theta_{N-1}), 360 - s (theta_N - theta_1)] in deg."""
    gaps = [sign * (b - a) for a, b in zip(theta_deg, theta_deg[1:])]
    return gaps + [360.0 - sign * (theta_deg[-1] - theta_deg[0])]


def sequence_rule(theta_deg: list, sign, direction: str) -> Rule:
    slacks = sequence_slacks(theta_deg, sign)
    return Rule("sequence", ca.vertcat(*slacks), 0.0, None, "deg", 10.0,
                f"targets met in order within one turn, crank {direction}")
