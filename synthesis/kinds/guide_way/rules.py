"""Design rules of a rotary-arm slide guide way (seed 003): reach, arm direction, undercut, pressure angle,
continuity of the roller-centre line at joints, the fold conditions and (spline path) the key points and tangents.

Each builder takes samples of the trace.  On floats it gives the record a user reads (mm, deg); on
CasADi symbols smooth NLP rows: the undercut as a bound on curvature (smooth through inflections,
where the radius is infinite), the pressure angle through its cosine squared.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


def reach_rule(rho, R: float, d: float, where: str) -> Rule:
    """R - d <= |OM| <= R + d: the arm and claw reach the claw tip (value: the smaller distance to a limit, mm)."""
    if _symbolic(rho):
        return Rule("reach", rho, R - d, R + d, "mm", 1.0, where)
    rho = np.asarray(rho, float)
    return Rule("reach", np.minimum(rho - (R - d), (R + d) - rho), 0.0, None, "mm", 1.0, where)


def turning_rule(dtheta_ds, where: str) -> Rule:
    """The arm turns one way along the controlled path in time order: dtheta/ds >= 0 (deg per mm of claw path)."""
    value = dtheta_ds * (180.0 / math.pi)
    if not _symbolic(dtheta_ds):
        value = np.asarray(value, float)
    return Rule("arm_turns_forward", value, 0.0, None, "deg/mm", 0.1, where)


def undercut_rule(kappa, roller_radius: float, margin: float, where: str) -> Rule:
    """No cusp on either wall: the centre line's radius of curvature >= roller radius + margin everywhere
    (a groove has a wall on both sides, so whichever side is concave must be cut round the roller)."""
    need = roller_radius + margin
    if _symbolic(kappa):
        return Rule("no_undercut", kappa * need, -1.0, 1.0, "1", 1.0, where)
    k = np.abs(np.asarray(kappa, float))
    radius = np.where(k > 0, 1.0 / np.where(k > 0, k, 1.0), np.inf)
    note = None
    if np.any(radius < roller_radius):
        note = (f"undercut: the centre line bends tighter ({radius.min():.4g} mm) than the roller "
                f"({roller_radius:g} mm): the wall on the concave side cannot be cut there")
    return Rule("no_undercut", np.minimum(radius, 1e9), need, None, "mm", 1.0, where, note=note)


def pressure_angle_rule(along_crank, limit_deg: float, where: str) -> Rule:
    """Pressure angle <= limit: cos(mu) = |N' . e_PN| / |N'| >= cos(limit)."""
    if _symbolic(along_crank):
        return Rule("pressure_angle", along_crank**2, math.cos(math.radians(limit_deg)) ** 2, None, "1", 0.1, where)
    a = np.clip(np.abs(np.asarray(along_crank, float)), 0.0, 1.0)
    return Rule("pressure_angle", np.degrees(np.arccos(a)), None, limit_deg, "deg", 5.0, where)


def jump_rule(joint: str, quantity: str, jump: float, limit: float) -> Rule:
    """A jump of the roller-centre line at a joint (position mm, tangent deg, curvature 1/mm) within its limit."""
    unit = {"position": "mm", "tangent": "deg", "curvature": "1/mm"}[quantity]
    return Rule(f"joint_{joint}_{quantity}", float(jump), None, limit, unit, limit,
                f"roller-centre line at {joint}, one side against the other")


def fold_distance_rule(point: str, excess: float, tol: float) -> Rule:
    """|OD| - (R - d) = 0 (within tol): the claw lies folded on the arm at the fold point."""
    return Rule("fold_distance", float(excess), -tol, tol, "mm", tol, f"|O{point}| - (R - d) at {point}")


def fold_angle_rule(point: str, error_deg: float, tol: float) -> Rule:
    """The path's tangent at the fold point is perpendicular to OD (within tol deg)."""
    return Rule("fold_tangent", float(error_deg), -tol, tol, "deg", tol, f"angle(O{point}, tangent) - 90 at {point}")


def key_points_rule(misses: dict[str, float], tol: float) -> Rule:
    """The spline path passes every key point: the distance from each key point to the path at the key's
    parameter, at most ``tol`` mm (value: the largest)."""
    worst = max(misses, key=misses.__getitem__)
    return Rule("key_points", np.array(list(misses.values()), float), None, tol, "mm", tol,
                f"key points {'-'.join(misses)}: path to key point, largest at {worst}")


def key_tangents_rule(misses: dict[str, float], tol: float) -> Rule:
    """The spline path runs along the given tangent at each key point that has one: the angle between its
    direction of motion there and the tangent, at most ``tol`` deg (value: the largest)."""
    worst = max(misses, key=misses.__getitem__)
    return Rule("key_tangents", np.array(list(misses.values()), float), None, tol, "deg", tol,
                f"tangents at {'-'.join(misses)}: path's direction to the given one, largest at {worst}")
