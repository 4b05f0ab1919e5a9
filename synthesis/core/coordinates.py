"""NLP reparametrisations: coordinates in which a linkage's kinematics is defined at every iterate.

A kind declares its :class:`~synthesis.core.problem.Problem` in these coordinates; the design is an
affine function of them, so exact derivatives pass through unchanged.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from constraints.grashof import crank_rotation_slacks


class GrashofCoordinates:
    """NLP coordinates in which the loop of a Grashof linkage closes at every iterate.

    A design vector holds four link lengths at the indices ``l1, l2, l3, l4``: their roles in
    :func:`crank_rotation_slacks` (l2 turns fully; l1 is the frame of a crank-rocker, the crank of
    the double crank whose frame is l2).  The coordinates replace l1, l3 and l4 by the three slacks
    (frame, coupler, rocker), bounded below; the lengths are affine in them:

        l1 = l2 + (s_coupler + s_rocker) / 2,  l3 = l2 + (s_frame + s_rocker) / 2,  l4 = l2 + (s_frame + s_coupler) / 2.

    IPOPT keeps every iterate inside its bounds, so with l2 > 0 the linkage assembles at every crank
    angle (|l3 - l4| < |O'A| < l3 + l4) and the kinematics never take the square root of a negative
    number; the rows of the Grashof rule hold as bounds.  The slacks' bound is ``margin`` (mm), not 0:
    at a zero slack the loop reaches a toggle, where the assembly height's square root has an infinite
    derivative and rounding makes its argument negative (such a linkage has a zero transmission angle
    and fails that rule anyway).  The lengths' own bounds become rows.
    """

    def __init__(self, l1: int, l2: int, l3: int, l4: int, margin: float = 1e-6):
        self.l1, self.l2, self.l3, self.l4 = l1, l2, l3, l4
        self.margin = margin

    def design(self, z):
        """The design vector (lengths) of coordinates z (CasADi column or numpy vector)."""
        s = z[self.l2]
        sf, sc, sr = z[self.l1], z[self.l3], z[self.l4]
        lengths = {self.l1: s + 0.5 * (sc + sr), self.l3: s + 0.5 * (sf + sr), self.l4: s + 0.5 * (sf + sc)}
        items = [lengths.get(i, z[i]) for i in range(z.shape[0])]
        return ca.vertcat(*items) if isinstance(z, (ca.SX, ca.MX)) else np.array(items, dtype=float)

    def coordinates(self, x: np.ndarray) -> np.ndarray:
        """Coordinates of a design vector (slacks may be negative: IPOPT moves such a start inside)."""
        z = np.array(x, dtype=float)
        slacks = crank_rotation_slacks(x[self.l1], x[self.l2], x[self.l3], x[self.l4])
        z[self.l1], z[self.l3], z[self.l4] = slacks["frame"], slacks["coupler"], slacks["rocker"]
        return z

    def bounds(self, lbx: np.ndarray, ubx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of the coordinates: l2's own, every slack >= margin."""
        lbz, ubz = np.array(lbx, dtype=float), np.array(ubx, dtype=float)
        for i in (self.l1, self.l3, self.l4):
            lbz[i], ubz[i] = self.margin, np.inf
        return lbz, ubz

    def length_rows(self, x, lbx: np.ndarray, ubx: np.ndarray) -> list[tuple]:
        """The bounds of the three replaced lengths as rows (expr, lb, ub) on the design expressions x."""
        return [(x[i], float(lbx[i]), float(ubx[i])) for i in (self.l1, self.l3, self.l4)]


#: a length held as a row may miss its bounds by IPOPT's constraint tolerance; beyond this (relative to
#: max(1, |bound|)) the design is outside them
BOUND_TOLERANCE = 1e-6


def outside_bounds(names, box: np.ndarray, design: dict) -> str | None:
    """Why ``design`` is not a design of the spec: "l10 = 161.37 lies outside its bounds [140, 140] (...)" for the
    first variable of ``names`` beyond its row of ``box`` (n x 2, spec units), else None.  With these coordinates
    the lengths' bounds are rows, which a start IPOPT stops without meeting (infeasible, iteration limit) may leave:
    its design has then moved even the lengths the spec fixes, and is no candidate."""
    for name, (lo, hi) in zip(names, np.asarray(box, float)):
        value = design.get(name)
        if value is None:
            continue
        if value < lo - BOUND_TOLERANCE * max(1.0, abs(lo)) or value > hi + BOUND_TOLERANCE * max(1.0, abs(hi)):
            where = f"its fixed value {lo:g}" if lo == hi else f"its bounds [{lo:g}, {hi:g}]"
            off = lo - value if value < lo else value - hi        # the digits that show it: 200.0003, not 200
            return (f"{name} = {value:.10g} lies {off:.2g} outside {where}: IPOPT stopped without meeting the rows "
                    f"that hold the link lengths, so this is no design of the spec")
    return None

