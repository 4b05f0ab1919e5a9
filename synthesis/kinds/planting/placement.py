"""Where to put the seedling tray for a given arm: the placement rule behind the library baselines.

Seed 000 prints the linkages of its four production designs (Table 1) but not where their trays
sit.  The baselines place the tray as a designer would: across a ``seedling_height``-long stretch
of the claw's downward path between the top of the loop and soil entry (the claw passes the
seedlings, then the mat), with the tray surface perpendicular to that stretch, because the
seedlings stand perpendicular to the mat and the claw should slide along them.  The tray's lower
edge (P3) must clear the seedlings just planted: P3 at least ``seedling_height - depth`` above the
soil.  Among the stretches that clear, the straightest (smallest turn at P2) is taken; when none
clears, the highest stretch.  The numbers it returns are written into the baseline spec files
(rounded to 0.1 mm / 0.1 deg); a test checks that they still agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from synthesis.kinds.planting.kinematics import ArmDesign, Motion, tip_state


@dataclass(frozen=True)
class TrayPlacement:
    x: float          # mm, P3 (seedbed bottom crossing)
    y: float          # mm
    tilt: float       # deg, direction of the tray surface from +X
    kink: float       # deg, turn of the path at P2 (P1->P2 vs P2->P3)
    crank_deg: float  # crank angle of P3


def suggest_seedbed(design: ArmDesign, motion: Motion, seedling_height: float = 110.0,
                    thickness: float = 22.0, analysis_depth: float = 25.0, grid: int = 7200) -> TrayPlacement:
    theta = np.linspace(0.0, 2 * np.pi, grid, endpoint=False)
    pos = tip_state(design, motion, theta).pos
    k5 = int(np.argmin(pos[1]))
    order = (np.arange(grid) + k5) % grid          # one cycle starting at the lowest point
    y = pos[1, order]
    k_top = int(np.argmax(y))
    soil = y[0] + analysis_depth
    k_entry = grid - 1 - int(np.argmax(y[::-1] >= soil))
    candidates = []
    for k3 in range(k_top + 1, k_entry):
        p3 = pos[:, order[k3]]
        # P1: walking back along the path, the first point seedling_height away from P3
        back = pos[:, order[k_top:k3][::-1]]
        dist = np.hypot(back[0] - p3[0], back[1] - p3[1])
        hit = np.flatnonzero(dist >= seedling_height)
        if hit.size == 0:
            continue
        p1 = back[:, hit[0]]
        # P2: the first point back from P3 that is `thickness` above P3 along the chord P3 -> P1
        u = (p1 - p3) / np.linalg.norm(p1 - p3)
        seg = back[:, : hit[0] + 1]
        along = (seg[0] - p3[0]) * u[0] + (seg[1] - p3[1]) * u[1]
        p2 = seg[:, int(np.argmax(along >= thickness))]
        kink = _turn_deg(p1, p2, p3)
        candidates.append((kink, p3[1], k3, p3, u))
    if not candidates:
        # no stretch of seedling height at all: put the tray surface across the top of the loop
        top = pos[:, order[k_top]]
        return TrayPlacement(float(top[0]), float(top[1]), 0.0, float("nan"), math.degrees(theta[order[k_top]]))
    clear = [c for c in candidates if c[1] >= soil + seedling_height - analysis_depth]
    kink, _, k3, p3, u = min(clear, key=lambda c: c[0]) if clear else max(candidates, key=lambda c: c[1])
    tilt = math.degrees(math.atan2(u[1], u[0])) - 90.0   # tray surface perpendicular to the stretch
    return TrayPlacement(float(p3[0]), float(p3[1]), (tilt + 180.0) % 360.0 - 180.0, float(kink),
                         math.degrees(theta[order[k3]]))


def _turn_deg(p1, p2, p3) -> float:
    """Angle between the directions P1->P2 and P2->P3, deg (0 for collinear points)."""
    a, b = p2 - p1, p3 - p2
    return math.degrees(abs(math.atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])))
