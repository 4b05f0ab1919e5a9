"""The friction coefficient mu from a measured landing time (seed 001 prints t_z, not mu).

Every mu in ``mu_range`` whose closed-form landing time equals the target is returned: the range
is scanned on a grid, and each sign change of t_z(mu) - target is refined with Brent's method.
Where the seedling sticks, t_z(mu) does not exist, and no root is looked for across that gap.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.optimize import brentq

from synthesis.kinds.guide_tube.drop import Physics, SeedlingSticks, Tube, landing

SCAN_POINTS = 121


def roots_in(f: Callable[[float], float | None], lo: float, hi: float, points: int = SCAN_POINTS) -> list[float]:
    """All roots of ``f`` on [lo, hi] found between grid neighbours where f is defined and changes
    sign (f returns None where it is undefined); sorted, to Brent's full precision."""
    grid = np.linspace(lo, hi, points)
    values = [f(float(x)) for x in grid]
    roots: list[float] = []
    for (a, fa), (b, fb) in zip(zip(grid, values), zip(grid[1:], values[1:])):
        if fa is None or fb is None:
            continue
        if fa == 0.0:
            roots.append(float(a))
        elif fa * fb < 0:
            roots.append(float(brentq(f, a, b, xtol=1e-14, rtol=4 * np.finfo(float).eps)))
    if values[-1] == 0.0:
        roots.append(float(grid[-1]))
    return roots


@dataclass(frozen=True)
class MuCalibration:
    target: float                       # s
    tube: str
    delta_deg: float
    mu_range: tuple[float, float]
    roots: list[float]
    landing_time_range: tuple[float, float] | None     # t_z over the sliding part of mu_range
    sticks_above: float | None          # smallest scanned mu at which the seedling sticks


def calibrate_mu(target: float, delta_deg: float, tube: Tube, physics: Physics,
                 mu_range: tuple[float, float]) -> MuCalibration:
    """Every mu in ``mu_range`` for which ``tube`` at ``delta_deg`` lands after ``target`` s."""
    @functools.lru_cache(maxsize=None)     # the scan, the roots and the span share the grid points
    def t_z(mu: float) -> float | None:
        try:
            return landing(delta_deg, tube, physics.with_(mu=mu)).landing_time
        except SeedlingSticks:
            return None

    lo, hi = mu_range
    roots = roots_in(lambda mu: None if (t := t_z(mu)) is None else t - target, lo, hi)
    grid = np.linspace(lo, hi, SCAN_POINTS)
    defined = [(float(m), t) for m in grid if (t := t_z(float(m))) is not None]
    sticking = [float(m) for m in grid if t_z(float(m)) is None]
    span = (min(t for _, t in defined), max(t for _, t in defined)) if defined else None
    return MuCalibration(target, tube.name, delta_deg, mu_range, roots, span, min(sticking) if sticking else None)
