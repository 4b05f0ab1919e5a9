"""Design rules of a disc cam with a roller follower: pressure angle, undercut, timing, acceleration.

Each builder takes samples over a segment or the turn.  On floats it gives the record a user
reads (degrees, millimetres); on CasADi symbols it gives smooth NLP rows (``nlp_rows``): the
pressure angle as its signed value within [-limit, limit], the undercut as a bound on curvature
(smooth through inflection points, where a radius of curvature is infinite).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule

#: the dwells count with the rise: an offset follower leans on its guide there too (tan a = -e / s0)
WHERE = {"rise": "over the rise and the dwells", "return": "over the return"}


def _symbolic(x) -> bool:
    return isinstance(x, (ca.SX, ca.MX))


def pressure_angle_rule(segment: str, alpha_deg, limit_deg: float) -> Rule:
    """|pressure angle| <= limit at every sample of the segment (signed angle, deg)."""
    name = f"pressure_angle_{segment}"
    if _symbolic(alpha_deg):
        return Rule(name, alpha_deg, -limit_deg, limit_deg, "deg", 5.0, WHERE[segment])
    return Rule(name, np.abs(alpha_deg), None, limit_deg, "deg", 5.0, WHERE[segment])


def undercut_rule(kappa, roller_radius, min_working_radius: float, flank: str = "inner") -> Rule:
    """The working profile's smallest radius of curvature >= ``min_working_radius``: what a cutter (or grinding
    wheel) can make and a roller can run on; 0 only forbids the undercut cusp.

    inner flank (the working profile of a spring-loaded disc cam): where the pitch curve is convex
    (kappa > 0), working radius = pitch radius - roller radius; outer flank (groove): where the pitch curve
    is concave, the outer wall's radius = concave pitch radius - roller radius.  kappa = signed pitch
    curvature, 1/mm.  The value is the working radius (mm), the limit ``min_working_radius``.
    """
    name = "no_undercut" if flank == "inner" else "no_undercut_outer"
    sign = 1.0 if flank == "inner" else -1.0
    where = ("convex working profile: radius of curvature (pitch radius - roller radius)" if flank == "inner"
             else "outer groove wall: radius of curvature (concave pitch radius - roller radius)")
    where += f", at least {float(min_working_radius):g} mm (rules.min_working_radius: the smallest a cutter makes)"
    need = roller_radius + min_working_radius
    if _symbolic(kappa) or _symbolic(roller_radius):
        # (r + m) kappa <= 1  <=>  rho >= r + m where the flank bends round the roller; always true elsewhere
        return Rule(name, sign * kappa * need - 1.0, None, 0.0, "1", 1.0, where)
    k = sign * np.asarray(kappa, dtype=float)
    radius = 1.0 / k[k > 0] if np.any(k > 0) else np.array([np.inf])
    note = None
    if np.any(radius < roller_radius):
        note = (f"undercut: the pitch curve bends tighter ({radius.min():.4g} mm) than the roller "
                f"({float(roller_radius):g} mm); the envelope has a cusp and the cam cannot reproduce the motion")
    working = radius - float(roller_radius)
    rule = Rule(name, working, float(min_working_radius), None, "mm", 1.0, where)
    return rule if note is None else Rule(name, working, float(min_working_radius), None, "mm", 1.0, f"{where}; {note}")


def timing_rule(kind: str, index: int, window_deg: tuple, dwell_start, dwell_end,
                shown: tuple[float, float] | None = None) -> Rule:
    """The dwell covers the window: both margins (window start - dwell start, dwell end - window end) >= 0.

    ``window_deg`` is already unwrapped to the turn the dwell is measured on; its ends may be CasADi symbols (a
    window timed in seconds, converted at a symbolic crank speed), and then ``shown`` (its numbers) describes it.
    """
    a, b = window_deg
    sa, sb = (a, b) if shown is None else shown
    name = f"timing_{kind}[{index}]"
    level = "rest (near dwell)" if kind == "hold_near" else "full stroke (far dwell)"
    where = f"follower at {level} through {sa % 360:g}-{sb % 360 if sb % 360 else 360:g} deg"
    margins = (a - dwell_start, dwell_end - b)
    if _symbolic(dwell_start) or _symbolic(dwell_end) or _symbolic(a) or _symbolic(b):
        return Rule(name, ca.vertcat(*margins), 0.0, None, "deg", 1.0, where)
    return Rule(name, np.array(margins, dtype=float), 0.0, None, "deg", 1.0, where)


#: where the dynamics rules are evaluated
_OVER_A_TURN = "over a turn (rise, dwells, return)"


def contact_force_rule(force, minimum: float) -> Rule:
    """Contact force between roller and cam (N, along the common normal) >= ``minimum`` at every sample of the turn
    at the crank speed: the spring keeps the roller on the cam with that margin."""
    where = f"{_OVER_A_TURN} at the crank speed"
    return Rule("contact_force_min", force, minimum, None, "N", max(minimum, 1.0), where)


def hertz_stress_rule(stress, limit: float, force=None, allowed_force=None, reference_force: float = 1.0) -> Rule:
    """Hertz stress between roller and cam (MPa) <= ``limit`` at every sample of the turn.

    On symbols the NLP holds the smooth form ``force <= allowed_force`` (the contact force at which the stress
    reaches the limit, linear in the relative radius of curvature, so smooth through F = 0 where the stress is
    not), scaled by limit / (2 ``reference_force``) so that near the limit a row reads about stress - limit, MPa.
    """
    where = f"{_OVER_A_TURN}, roller on the working profile (line contact)"
    if _symbolic(stress) or _symbolic(force):
        row = (force - allowed_force) * (limit / (2.0 * reference_force))
        return Rule("hertz_stress_max", stress, None, limit, "MPa", limit / 10.0, where,
                    nlp_rows=((row, None, 0.0),))
    return Rule("hertz_stress_max", stress, None, limit, "MPa", limit / 10.0, where)


def jump_speed_rule(speeds_rpm, minimum: float, force_at_minimum=None, rpm_per_newton: float = 1.0,
                    force_at_rest=None) -> Rule:
    """Jump speed (r/min) >= ``minimum``: the follower stays on the cam up to that cam speed.

    ``speeds_rpm``: the speed at which the contact force vanishes at each sample where the spring must decelerate
    the follower (the rule's value is their smallest, the jump speed).  On symbols the NLP holds the contact force
    at the ``minimum`` speed >= 0 at every sample (``force_at_minimum``, N): smooth, and it also holds where no
    sample decelerates (the spring must hold the follower at rest).  ``rpm_per_newton`` scales those rows so that
    near the limit they read about jump speed - minimum, r/min (1 / (2 |dF/d omega^2| omega) at the given design).

    Where the follower accelerates (q'' > 0) inertia presses it on, so the force at the minimum speed can be
    positive while the spring alone cannot hold it against gravity at rest; the value on floats then says 0 r/min
    (it leaves the cam as the cam slows to a stop).  ``force_at_rest`` (N, the contact force at standstill) adds
    those rows, >= 0 at every sample: needed only where gravity's load varies with the follower's position (an
    oscillating arm), since a translating follower's weakest standstill force is at its dwell, already a row."""
    where = "the cam speed at which the contact force first reaches zero over a turn"
    if _symbolic(speeds_rpm) or _symbolic(force_at_minimum):
        rows = [(force_at_minimum * rpm_per_newton, 0.0, None)]
        if force_at_rest is not None:
            rows.append((force_at_rest * rpm_per_newton, 0.0, None))
        return Rule("jump_speed_min", speeds_rpm, minimum, None, "r/min", minimum / 10.0, where,
                    nlp_rows=tuple(rows))
    return Rule("jump_speed_min", speeds_rpm, minimum, None, "r/min", minimum / 10.0, where)


def acceleration_rule(acc_samples, limit: float, unit: str) -> Rule:
    """|follower acceleration| <= limit at every sample of the rise and the return."""
    if _symbolic(acc_samples):
        return Rule("max_acceleration", acc_samples, -limit, limit, unit, limit / 10.0, "over the rise and return")
    return Rule("max_acceleration", np.abs(acc_samples), None, limit, unit, limit / 10.0, "over the rise and return")
