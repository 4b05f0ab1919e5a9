"""Grashof class of a four-bar driven by crank r2 on frame r1, as three linear (smooth) rows.

crank-rocker (r2 turns fully, r4 rocks):  r2 shortest and s + l <= p + q, i.e.
    r2 + r1 <= r3 + r4,  r2 + r3 <= r1 + r4,  r2 + r4 <= r1 + r3
double-crank (drag link, r2 and r4 both turn fully):  r1 shortest and s + l <= p + q, i.e. the same
three with r1 and r2 swapped.
Value: the smallest slack (mm); >= 0 is the class (0 is its change-point limit).
"""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule

CLASSES = {"crank-rocker": "r2 shortest, s + l <= p + q", "double-crank": "r1 shortest, s + l <= p + q"}


def grashof_slacks(grashof: str, r1, r2, r3, r4) -> list:
    """The three slacks (mm) of the class; all >= 0 iff the linkage is of that Grashof class."""
    if grashof == "crank-rocker":
        frame, crank = r1, r2
    elif grashof == "double-crank":
        frame, crank = r2, r1          # the frame takes the crank's place
    else:
        raise ValueError(f"no Grashof rows for class {grashof!r}")
    return [r3 + r4 - crank - frame, frame + r4 - crank - r3, frame + r3 - crank - r4]


def grashof_class_rule(grashof: str, r1, r2, r3, r4) -> Rule:
    s = grashof_slacks(grashof, r1, r2, r3, r4)
    worst = ca.fmin(ca.fmin(s[0], s[1]), s[2])
    return Rule("grashof", worst, 0.0, None, "mm", 10.0, f"{grashof}: {CLASSES[grashof]}",
                nlp_rows=tuple((x, 0.0, None) for x in s))
