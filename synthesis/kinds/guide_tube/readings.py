"""Which reading of seed 001 §2.4 gives its delta2 = 41 deg?  A study, not part of any run.

For each reading: calibrate mu on tube I (delta1 = 45 deg, L3 = 105 mm, h5 = 40, h6 = 210 mm) to the
published t_z = 0.445 s where the reading has a free mu, then find every wall angle of tube II
(L3 = 35 mm) with the same landing time.  ``python -m synthesis.kinds.guide_tube.readings`` prints the
table quoted in problems/guide_tube/GUIDE_TUBE.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from synthesis.kinds.guide_tube.calibrate import roots_in
from synthesis.kinds.guide_tube.drop import Physics, SeedlingSticks, Tube, landing
from synthesis.kinds.guide_tube.printed import printed_landing_time

PUBLISHED_TZ = 0.445
TUBE_I = Tube("I", 0.105, 0.040, 0.210)
TUBE_II = Tube("II", 0.035, 0.040, 0.210)
PHYSICS = Physics(0.6, 9.8, 17.5, 0.0)

LandingTime = Callable[[float, Tube, Physics], float]


@dataclass(frozen=True)
class Reading:
    name: str
    mu: float | None            # calibrated (None: the reading fixes mu itself)
    t_z_tube_I: float           # s, at delta1 = 45 deg
    delta2: list[float]         # deg, every angle of tube II landing at the same time


def _exact(delta: float, tube: Tube, physics: Physics) -> float:
    return landing(delta, tube, physics).landing_time


def _same_impact_height(delta: float, tube: Tube, physics: Physics) -> float:
    """Every tube's wall starts at tube I's impact height; the straight part below takes up the rest."""
    h1 = physics.height - TUBE_I.below_wall - TUBE_I.l3 * math.tan(math.radians(45.0))
    below = physics.height - h1 - tube.l3 * math.tan(math.radians(delta))
    return landing(delta, Tube(tube.name, tube.l3, 0.0, below), physics).landing_time


def _longer_wall(extra: float) -> LandingTime:
    """The wall runs ``extra`` (m) past the tube centre (L3 read as the distance to the centre, the
    wall ending at the far side of a tube of radius ``extra``)."""
    return lambda d, tube, physics: _exact(d, Tube(tube.name, tube.l3 + extra, tube.h5, tube.h6), physics)


def _printed(h3: float | None) -> LandingTime:
    return lambda d, tube, physics: printed_landing_time(d, tube, physics, h3)


def _defined(f: LandingTime) -> Callable[[float, Tube, Physics], float | None]:
    def g(d: float, tube: Tube, physics: Physics) -> float | None:
        try:
            return f(d, tube, physics)
        except (SeedlingSticks, ValueError):
            return None
    return g


def study(t_of: LandingTime, physics: Physics, name: str, calibrate: bool = True) -> Reading:
    f = _defined(t_of)
    mu = None
    if calibrate:
        roots = roots_in(lambda m: None if (t := f(45.0, TUBE_I, physics.with_(mu=m))) is None
                         else t - PUBLISHED_TZ, 0.0, 1.5)
        if len(roots) != 1:
            raise ValueError(f"{name}: {len(roots)} friction coefficients give t_z = {PUBLISHED_TZ} s")
        mu = roots[0]
        physics = physics.with_(mu=mu)
    target = f(45.0, TUBE_I, physics)
    delta2 = roots_in(lambda d: None if (t := f(d, TUBE_II, physics)) is None else t - target, 5.0, 80.0, 301)
    return Reading(name, mu, target, delta2)


def readings() -> list[Reading]:
    free_fall = PHYSICS.with_(terminal_speed=math.inf)
    return [
        study(_exact, PHYSICS, "exact solutions of eq 13, 16, 18 (ours)"),
        study(_printed(None), PHYSICS, "eq 17/19/21 as printed, one phase over h5 + h6"),
        study(_printed(0.040), PHYSICS, "eq 17/19/21 as printed, vertical wall met after h3 = h5"),
        study(_same_impact_height, PHYSICS, "same impact height h1 for every tube"),
        study(_longer_wall(0.020), PHYSICS, "wall 20 mm longer than L3 (tube radius)"),
        study(_longer_wall(0.050), PHYSICS, "wall 50 mm longer than L3"),
        study(_exact, PHYSICS, "no friction (mu = 0), equal times", calibrate=False),
        study(_exact, free_fall, "no friction, no drag, equal times", calibrate=False),
    ]


def main() -> None:
    print(f"{'reading':60s} {'mu':>8s} {'t_z(I) s':>9s}  delta2 (deg; published 41)")
    for r in readings():
        mu = "-" if r.mu is None else f"{r.mu:.4f}"
        print(f"{r.name:60s} {mu:>8s} {r.t_z_tube_I:9.4f}  {', '.join(f'{d:.2f}' for d in r.delta2) or 'none'}")


if __name__ == "__main__":
    main()
