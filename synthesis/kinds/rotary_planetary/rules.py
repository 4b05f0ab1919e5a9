"""Rules of kind rotary_planetary, each a function of a trace (floats for check and re-check, CasADi symbols for
the NLP).  Where a rule's limit comes from and which are our assumptions: problems/rotary_planetary/NOTES.md,
"Rules".

A rule whose value is a maximum or a minimum over the turn is written for the optimiser with auxiliary carrier
angles the NLP owns (the loop's top and bottom, soil entry and exit, each key pose's angle): "there is a bottom
at least this deep" is one smooth row at the bottom's angle, "every point no deeper than that" is a row per
sample.  On floats the caller passes the extremes it found on its grid.  The key poses' rules are the shared ones
(:mod:`synthesis.constraints.poses`).
"""

from __future__ import annotations

import math

import casadi as ca

from synthesis.constraints.base import Rule, not_evaluated

DEG = 180.0 / math.pi
#: the fraction of its tolerance the NLP holds the single-idler gap to on its samples
BACKED_OFF = 0.9


def pair_ratio_rule(ratios, lo: float, hi: float) -> Rule:
    """i = r_driver / r_driven of both pairs over a turn within [lo, hi]: bounded pitch radii (lo > 0 also keeps
    every gear turning one way)."""
    return Rule("pair_ratio", ratios, lo, hi, "-", 0.1, "both pairs over a turn")


def concave_radius_rule(curvatures, min_radius: float) -> Rule:
    """Signed curvature of the four pitch curves >= -1 / min_radius: where a curve is concave, its radius of
    curvature is at least min_radius (a hob or shaper cutter of that radius can cut it); convex parts are free."""
    return Rule("pitch_curve_concavity", curvatures, -1.0 / min_radius, None, "1/mm", 0.01,
                "four pitch curves over a turn")


def normal_angle_rule(angles_deg, max_deg: float) -> Rule:
    """Angle between the pitch curves' common normal at the contact and the line of centres within +-max: the
    working pressure angle of the teeth departs from the tool's by this much."""
    return Rule("pitch_normal_angle", angles_deg, -max_deg, max_deg, "deg", 5.0, "both pairs over a turn")


def trajectory_height_rule(y_top, y_bottom, minimum: float, missing: str | None = None) -> Rule:
    if missing:
        return not_evaluated("trajectory_height", minimum, None, "mm", "top to bottom of the loop", missing)
    return Rule("trajectory_height", y_top - y_bottom, minimum, None, "mm", 10.0, "top to bottom of the loop")


def planting_depth_rules(soil_y, y_bottom, y_samples, depth: tuple[float, float]) -> list[Rule]:
    """The lowest tip point between depth[0] and depth[1] below the soil surface: deep enough at the bottom (one
    row at its angle), not too deep anywhere (a row per sample, ``y_samples`` the turn's samples and the bottom
    itself: the grid's lowest sample is the bottom's height only to the grid's step)."""
    lo, hi = depth
    return [Rule("planting_depth", soil_y - y_bottom, lo, None, "mm", 5.0, "lowest tip point"),
            Rule("planting_depth_max", soil_y - y_samples, None, hi, "mm", 5.0, "over a turn")]


def entry_angle_rule(vx_ground, vy, minimum_deg: float, missing: str | None = None) -> Rule:
    """Direction of the tip's ground-frame velocity at soil entry to the horizontal, atan2(|vy|, |vx|) (as the
    four-bar planting arm's entry angle); the smooth row measures the direction from +x, vy < 0 at entry."""
    where = "at soil entry, ground frame"
    if missing:
        return not_evaluated("entry_angle", minimum_deg, None, "deg", where, missing)
    angle = ca.atan2(ca.fabs(vy), ca.fabs(vx_ground)) * DEG
    rows = ((ca.atan2(-vy, vx_ground) * DEG, minimum_deg, 180.0 - minimum_deg),)
    return Rule("entry_angle", angle, minimum_deg, None, "deg", 10.0, where, nlp_rows=rows)


def hole_width_rule(x_ground_entry, x_ground_exit, maximum: float, missing: str | None = None) -> Rule:
    """Ground-frame distance between the tip's soil entry and exit points: the hole it leaves at the surface."""
    where = "soil surface, ground frame"
    if missing:
        return not_evaluated("hole_width", None, maximum, "mm", where, missing)
    span = x_ground_exit - x_ground_entry
    return Rule("hole_width", ca.fabs(span), None, maximum, "mm", 5.0, where, nlp_rows=((span, -maximum, maximum),))


def in_soil_speed_rule(forward_speeds, maximum: float, missing: str | None = None) -> Rule:
    """The tip's forward speed relative to the ground while in the soil <= maximum (0: it never pushes the soil
    or the seedling forward)."""
    where = "soil entry to exit, ground frame"
    if missing:
        return not_evaluated("in_soil_forward_speed", None, maximum, "mm/s", where, missing)
    return Rule("in_soil_forward_speed", forward_speeds, None, maximum, "mm/s", 50.0, where)


def out_of_soil_rule(heights, missing: str | None = None) -> Rule:
    """The tip goes into the soil once a turn: from soil exit round to the next entry it stays above the surface.
    ``heights``: its height above the surface at s in (0, 1) of that arc (0 at exit, 1 at the next entry) over
    4 s (1 - s) -- zero at the crossings themselves, where the tip crosses the surface, and so finite and positive
    near them (the height grows like s), the height itself in the middle; negative only where the tip dips into the
    soil again, where no hole, entry-angle or speed rule reads it."""
    where = "soil exit round to the next entry"
    if missing:
        return not_evaluated("soil_once", 0.0, None, "mm", where, missing)
    return Rule("soil_once", heights, 0.0, None, "mm", 10.0, where)


def plant_spacing_rule(spacing, limits: tuple[float, float]) -> Rule:
    """Forward travel per plant: two arms plant twice per carrier turn."""
    return Rule("plant_spacing", spacing, limits[0], limits[1], "mm", 10.0, "forward speed, two plants per turn")


def single_idler_rule(radius_gap, tolerance: float) -> Rule:
    """A single idler gear (the common three-gear train) meets the sun and the planet with one pitch curve: at each
    polar angle of the idler, its radius towards the planet equals its radius towards the sun (read half an idler
    turn apart), within ``tolerance``.  The NLP holds it on its samples a tenth inside the tolerance: where the rule
    binds, the gap's extreme falls between samples (by 1 % of the tolerance at 72 and 180 samples a turn)."""
    rows = ((radius_gap, -BACKED_OFF * tolerance, BACKED_OFF * tolerance),)
    return Rule("single_idler", radius_gap, -tolerance, tolerance, "mm", 0.1, "idler's two pitch curves over a turn",
                nlp_rows=rows)
