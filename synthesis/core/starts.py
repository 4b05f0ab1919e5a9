"""Start points: moving a drawn start into the region where a kind's kinematics is defined."""

from __future__ import annotations

from typing import Callable

import numpy as np


def pull_inside(start: np.ndarray, anchor: np.ndarray, slacks: Callable[[np.ndarray], np.ndarray],
                margin: float) -> np.ndarray:
    """The point nearest ``start`` on the segment anchor -> start where every slack >= margin.

    ``slacks`` must be affine in the point (e.g. Grashof inequalities in the link lengths) and the
    anchor inside; then each slack is linear along the segment and the cut-off is exact.  Used to
    move random starts into the region where the linkage assembles, so IPOPT never starts on NaNs.
    """
    g0, g1 = slacks(anchor) - margin, slacks(start) - margin
    if np.any(g0 < 0.0):
        return start          # no feasible anchor: leave the start as drawn
    t = 1.0
    for a, b in zip(g0, g1):
        if b < 0.0:
            t = min(t, a / (a - b))
    return anchor + t * (start - anchor)
