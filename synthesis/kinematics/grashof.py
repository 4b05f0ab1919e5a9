"""NLP coordinates of a Grashof four-bar, shared by the kinds that solve one (the crank-rocker, the picker's double
crank): coordinates in which the linkage's loop closes at every iterate.

A kind declares its :class:`~synthesis.core.problem.Problem` in these coordinates; the design is an affine function
of them, so exact derivatives pass through unchanged.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from synthesis.kinematics.fourbar import crank_rotation_slacks


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

    def affine(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(d0, J) with design(z) = d0 + J z for a decision vector of ``n`` entries (the tolerance box's map)."""
        z = ca.SX.sym("z", n)
        d = self.design(z)
        d0, J = ca.Function("design", [z], [d, ca.jacobian(d, z)])(np.zeros(n))
        return np.asarray(d0, float).ravel(), np.asarray(J, float)
