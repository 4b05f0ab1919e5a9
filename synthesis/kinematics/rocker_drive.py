"""Crank-rocker AEFG of the seed-001 picker drive (§2.1.3, Fig. 5): rocker motion, extremes, quick return.

Links (seed 001 symbols): crank GF = l7, coupler FE = l8, rocker AE = l9, frame AG = l10.  The
mechanism's own frame puts the crank pivot G at the origin and the rocker pivot A at (l10, 0); the
crank angle phi is measured counter-clockwise from G -> A, so this is :mod:`synthesis.kinematics.fourbar`
with O = G, O' = A, l1..l4 = l10, l7, l8, l9 and zeta = 0.  ``branch`` picks the assembly; the two
branches are mirror images with the same K, swing and transmission angles.

The rocker's extreme positions are where its angle beta(phi) is stationary (d beta / d phi = 0,
exact by AD), found by root finding here and imposed as NLP rows in the solver: never the textbook
dead-centre construction.  With the crank turning at constant speed, the crank angles between the two
extremes give the time ratio K = (slow stroke) / (quick stroke).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np
from scipy.optimize import brentq

from synthesis.kinematics import fourbar

TWO_PI = 2.0 * math.pi
#: order of the parameter vector p (mm)
PARAMETERS = ("l7", "l8", "l9", "l10")


def rocker_tip(phi, p, branch: int) -> fourbar.Point:
    """E: the coupler-rocker joint at crank angle phi; p = (l7, l8, l9, l10)."""
    l7, l8, l9, l10 = (p[i] for i in range(4))
    return fourbar.coupler_joint(phi, l10, l7, l8, l9, 0.0, branch)[1]


@lru_cache(maxsize=4)
def rocker_function(branch: int) -> ca.Function:
    """(phi, p) -> (beta, dbeta, ddbeta, mu, E): rocker angle A -> E and its phi-derivatives (rad),
    transmission angle mu at E between coupler EF and rocker EA (rad, in [0, pi]), and E (mm)."""
    phi = ca.SX.sym("phi")
    p = ca.SX.sym("p", len(PARAMETERS))
    l7, l8, l9, l10 = (p[i] for i in range(4))
    beta = fourbar.rocker_angle(phi, l10, l7, l8, l9, 0.0, branch)
    dbeta = ca.jacobian(beta, phi)
    ddbeta = ca.jacobian(dbeta, phi)
    mu = fourbar.transmission_angle(phi, l10, l7, l8, l9, 0.0, branch)
    tip = ca.vertcat(*rocker_tip(phi, p, branch))
    return ca.Function(f"rocker_drive_{'p' if branch > 0 else 'm'}", [phi, p], [beta, dbeta, ddbeta, mu, tip],
                       ["phi", "p"], ["beta", "dbeta", "ddbeta", "mu", "tip"])


@dataclass(frozen=True)
class CrankRocker:
    """Link lengths in mm (seed 001 symbols) and the assembly branch."""

    l7: float     # crank GF
    l8: float     # coupler FE
    l9: float     # rocker AE
    l10: float    # frame AG
    branch: int = 1

    def parameters(self) -> np.ndarray:
        return np.array([self.l7, self.l8, self.l9, self.l10], dtype=float)

    def grashof_slacks(self) -> dict[str, float]:
        """All >= 0 iff the crank l7 turns fully (crank shortest, s + l <= p + q)."""
        return {k: float(v) for k, v in fourbar.crank_rotation_slacks(self.l10, self.l7, self.l8, self.l9).items()}

    def crank_turns(self) -> bool:
        return min(self.grashof_slacks().values()) > 0.0


def rocker_curve(cr: CrankRocker, phi) -> dict[str, np.ndarray]:
    """beta, dbeta/dphi (rad, rad/rad), mu (rad) and E (2, N) at crank angles phi (rad)."""
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    f = rocker_function(cr.branch).map(phi.size)
    beta, dbeta, ddbeta, mu, tip = (np.asarray(v) for v in f(phi.reshape(1, -1), cr.parameters()))
    return {"beta": beta.ravel(), "dbeta": dbeta.ravel(), "ddbeta": ddbeta.ravel(), "mu": mu.ravel(),
            "tip": tip.reshape(2, -1)}


def joints(cr: CrankRocker, phi: float) -> dict[str, list[float]]:
    """G, A, F, E (mm, the mechanism's own frame) at crank angle phi (rad)."""
    tip = rocker_curve(cr, np.array([phi]))["tip"][:, 0]
    return {"G": [0.0, 0.0], "A": [cr.l10, 0.0], "F": [cr.l7 * math.cos(phi), cr.l7 * math.sin(phi)],
            "E": [float(tip[0]), float(tip[1])]}


def turn_grid(samples: int) -> np.ndarray:
    """``samples`` crank angles evenly over a turn from 0 (the crank along G -> A).

    An even count contains phi = 0 and pi, the crank collinear with the frame, where the
    transmission angle of a crank-rocker takes its extreme values; the sampled minimum is then exact.
    """
    return np.linspace(0.0, TWO_PI, samples, endpoint=False)


def acute(mu_deg):
    """Transmission angle as an acute angle: min(mu, 180 - mu) (deg)."""
    return np.minimum(mu_deg, 180.0 - np.asarray(mu_deg))


@dataclass(frozen=True)
class Extremes:
    """The rocker's two extreme positions: crank angles (rad, in [0, 2 pi)) and rocker angles (rad)."""

    phi_folded: float       # crank and coupler overlap: |GE| = l8 - l7
    phi_extended: float     # crank and coupler in line:  |GE| = l8 + l7
    beta_folded: float
    beta_extended: float


def extreme_positions(cr: CrankRocker, grid: int = 720) -> Extremes:
    """The crank angles where d beta / d phi = 0 (scipy brentq on the AD derivative).

    Requires a crank that turns fully (``cr.crank_turns()``): then beta has exactly two stationary
    points per turn.  Which is the folded one is read from |GE| at each, not assumed.
    """
    f = rocker_function(cr.branch)
    p = cr.parameters()

    def dbeta(phi: float) -> float:
        return float(f(phi, p)[1])

    phis = np.linspace(0.0, TWO_PI, grid + 1)
    values = rocker_curve(cr, phis)["dbeta"]
    roots = []
    for k in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:])):
        roots.append(brentq(dbeta, phis[k], phis[k + 1], xtol=1e-14, rtol=4 * np.finfo(float).eps) % TWO_PI)
    roots = sorted({round(r, 12) for r in roots})
    if len(roots) != 2:
        raise ValueError(f"expected 2 rocker extremes per crank turn, found {len(roots)} (is it a crank-rocker?)")
    state = rocker_curve(cr, np.array(roots))
    gap = np.hypot(state["tip"][0], state["tip"][1])     # |GE| at each extreme (G at the origin)
    i_fold, i_ext = (0, 1) if gap[0] < gap[1] else (1, 0)
    return Extremes(roots[i_fold], roots[i_ext], float(state["beta"][i_fold]), float(state["beta"][i_ext]))


@dataclass(frozen=True)
class QuickReturn:
    """What the simulated crank-rocker does, the crank turning counter-clockwise (phi increasing)."""

    extremes: Extremes
    stroke_fold_to_ext: float    # crank angle turned from the folded to the extended extreme (rad)
    stroke_ext_to_fold: float
    time_ratio: float            # K = slow stroke / quick stroke
    swing: float                 # rocker swing psi (rad)
    extreme_crank_angle: float   # theta = |stroke - pi| (rad), seed 001 eq (8)
    frame_rocker_angle: float    # angle G-A-E at the folded extreme (rad): seed 001 eq (9) theta_1


def quick_return(cr: CrankRocker) -> QuickReturn:
    ex = extreme_positions(cr)
    fe = (ex.phi_extended - ex.phi_folded) % TWO_PI
    ef = TWO_PI - fe
    swing = abs(math.remainder(ex.beta_extended - ex.beta_folded, TWO_PI))
    tip = rocker_curve(cr, np.array([ex.phi_folded]))["tip"][:, 0]
    a = np.array([cr.l10, 0.0])
    to_g, to_e = -a, tip - a
    theta1 = math.atan2(abs(to_g[0] * to_e[1] - to_g[1] * to_e[0]), float(to_g @ to_e))
    return QuickReturn(ex, fe, ef, max(fe, ef) / min(fe, ef), swing, abs(fe - math.pi), theta1)


def transmission_angles_deg(cr: CrankRocker, samples: int) -> np.ndarray:
    """mu (deg) on :func:`turn_grid` (samples crank angles over a turn)."""
    return np.degrees(rocker_curve(cr, turn_grid(samples))["mu"])
