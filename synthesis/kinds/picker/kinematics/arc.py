"""Circular arcs given by two end points and the tangent at the first: the picking arc of seed 001.

Seed 001 §2.1.2 fixes the picking point M1, the drop point M2 and the angle θ5 between the arc's
tangent at M1 and the vertical.  Our reading (problems/picker/PICKER.md): y is up, the tangent at M1
leans from the vertical towards M2 (the minor arc), so the arc turns counter-clockwise from M1 to M2.
"""

from __future__ import annotations

import numpy as np


def arc_through(m1, m2, tangent_from_vertical_deg: float, toward_negative_x: bool = True):
    """(centre, radius, start angle, signed sweep) of the arc from m1 to m2 with the given tangent at m1.

    The tangent at m1 is the unit vector at ``tangent_from_vertical_deg`` from +y, leaning to -x
    when ``toward_negative_x`` (seed 001: M2 lies up and to the left of M1).
    """
    m1, m2 = np.asarray(m1, float), np.asarray(m2, float)
    a = np.radians(tangent_from_vertical_deg)
    t = np.array([-np.sin(a) if toward_negative_x else np.sin(a), np.cos(a)])
    chord = m2 - m1
    normal = np.array([-t[1], t[0]])            # tangent turned +90°: the centre lies on m1 + r*normal
    # |m1 + r n - m2|^2 = r^2  ->  r = |chord|^2 / (2 n.chord); a negative r puts the centre on the other side
    r_signed = chord @ chord / (2.0 * normal @ chord)
    centre = m1 + r_signed * normal
    start = np.arctan2(*(m1 - centre)[::-1])
    end = np.arctan2(*(m2 - centre)[::-1])
    sweep = (end - start + np.pi) % (2 * np.pi) - np.pi     # the arc that leaves m1 along t
    if np.sign(sweep) != np.sign(r_signed):
        sweep = sweep - np.sign(sweep) * 2 * np.pi
    return centre, abs(r_signed), start, sweep


def points_on_arc(m1, m2, tangent_from_vertical_deg: float, n: int, toward_negative_x: bool = True) -> np.ndarray:
    """(n, 2) points evenly spaced by arc length from m1 to m2, both ends included."""
    centre, radius, start, sweep = arc_through(m1, m2, tangent_from_vertical_deg, toward_negative_x)
    ang = start + sweep * np.linspace(0.0, 1.0, n)
    return centre + radius * np.column_stack([np.cos(ang), np.sin(ang)])


#: seed 001 §2.1.2: picking point M1, drop point M2 (mm, origin at the PTO bar, y up), θ5 = 28°
PICKING_M1 = (376.0, 123.7)
PICKING_M2 = (205.0, 258.0)
PICKING_THETA5_DEG = 28.0


def picking_arc(n: int = 10) -> np.ndarray:
    """The seed-001 picking arc M1 -> M2 sampled at n points evenly by arc length."""
    return points_on_arc(PICKING_M1, PICKING_M2, PICKING_THETA5_DEG, n)
