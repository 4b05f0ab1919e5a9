"""Rules on a linkage's dynamics over a turn: peak input torque, peak shaking force and peak shaking moment
(docs/ARCHITECTURE.md "Dynamics").  Functions of sampled values, floats or CasADi symbols alike, like every rule."""

from __future__ import annotations

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated


def peak_input_torque_rule(torque_samples, limit: float, where: str = "over a turn",
                           missing: str | None = None) -> Rule:
    """max |torque| <= limit (N m).  Value: the worst |torque|; NLP rows: -limit <= torque <= limit at every sample
    (smooth: the epigraph of the absolute value)."""
    if missing:
        return not_evaluated("peak_input_torque", None, limit, "N m", where, missing)
    return Rule("peak_input_torque", ca.fabs(torque_samples), None, limit, "N m", limit, where,
                nlp_rows=((torque_samples, -limit, limit),))


def peak_shaking_force_rule(force_x, force_y, limit: float, where: str = "over a turn",
                            missing: str | None = None) -> Rule:
    """max |shaking force| <= limit (N).  Value: the largest magnitude; NLP rows: fx^2 + fy^2 <= limit^2 at every
    sample (smooth where the force vanishes, unlike its magnitude)."""
    if missing:
        return not_evaluated("peak_shaking_force", None, limit, "N", where, missing)
    squared = force_x * force_x + force_y * force_y
    return Rule("peak_shaking_force", ca.sqrt(squared), None, limit, "N", limit, where,
                nlp_rows=((squared, None, limit * limit),), row_unit="N^2")


def peak_shaking_moment_rule(moment_samples, limit: float, where: str = "over a turn, about the crank pivot",
                             missing: str | None = None) -> Rule:
    """max |shaking moment| <= limit (N m, the moment the frame feels about the crank pivot).  Value: the worst
    |moment|; NLP rows: -limit <= moment <= limit at every sample."""
    if missing:
        return not_evaluated("peak_shaking_moment", None, limit, "N m", where, missing)
    return Rule("peak_shaking_moment", ca.fabs(moment_samples), None, limit, "N m", limit, where,
                nlp_rows=((moment_samples, -limit, limit),))
