"""Grashof crank-rocker rule: the crank l2 turns fully and the rocker swings.

Value: the smallest slack of  l2+l1 <= l3+l4,  l2+l3 <= l1+l4,  l2+l4 <= l1+l3  (mm).  These three
are equivalent to "l2 shortest and s + l <= p + q"; being linear they are smooth NLP rows.
"""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule


def crank_rotation_slacks(l1, l2, l3, l4) -> dict[str, object]:
    """Slacks of the three inequalities that let crank l2 turn fully (Grashof, crank shortest):

    l2 + l1 <= l3 + l4,  l2 + l3 <= l1 + l4,  l2 + l4 <= l1 + l3.  All three >= 0 is equivalent to
    "l2 is the shortest link and s + l <= p + q": a crank-rocker (or its change-point limit) when
    driven by l2 with l1 as frame.  Linear in the lengths, hence smooth constraints for the NLP.
    (The rule's own definition; the kinematics keep theirs, so neither layer imports the other.)
    """
    return {"frame": l3 + l4 - l2 - l1, "coupler": l1 + l4 - l2 - l3, "rocker": l1 + l3 - l2 - l4}


def grashof_rule(l1, l2, l3, l4) -> Rule:
    slacks = crank_rotation_slacks(l1, l2, l3, l4)
    rows = tuple((s, 0.0, None) for s in slacks.values())
    worst = ca.fmin(ca.fmin(slacks["frame"], slacks["coupler"]), slacks["rocker"])
    return Rule("grashof_crank_rocker", worst, 0.0, None, "mm", 10.0, "link lengths", nlp_rows=rows)


def grashof_double_crank_rule(frame, crank, coupler, follower) -> Rule:
    """Grashof double crank: the frame is the shortest link and s + l <= p + q (seed 001 eq 6).

    Value: the smallest slack of  frame + x <= (sum of the other two)  for x = crank, coupler,
    follower (mm); the same three linear rows as the crank-rocker rule with the frame in the
    shortest link's place, so both cranks turn fully.
    """
    slacks = crank_rotation_slacks(crank, frame, coupler, follower)
    rows = tuple((s, 0.0, None) for s in slacks.values())
    worst = ca.fmin(ca.fmin(slacks["frame"], slacks["coupler"]), slacks["rocker"])
    return Rule("grashof_double_crank", worst, 0.0, None, "mm", 10.0, "link lengths, frame shortest", nlp_rows=rows)
