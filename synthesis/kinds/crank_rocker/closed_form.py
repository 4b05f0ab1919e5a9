"""The textbook synthesis of seed 001 §2.1.3: eq (8)-(10) solved as a square system (no optimisation).

    theta = 180 (K - 1) / (K + 1)                                              (8)
    (l7 + l8)^2 = l9^2 + l10^2 - 2 l9 l10 cos(theta1 + psi)                       (9a) extended extreme
    (l8 - l7)^2 = l9^2 + l10^2 - 2 l9 l10 cos(theta1)                             (9b) folded extreme
    (2 l9 sin(psi/2))^2 = (l7 + l8)^2 + (l8 - l7)^2 - 2 (l7 + l8)(l8 - l7) cos(theta)  (9c) triangle E E' G
    cos(gamma_min) = (l8^2 + l9^2 - (l10 - l7)^2) / (2 l8 l9)                     (10)

With l10 given these are four equations in l7, l8, l9 and theta1 (the angle G-A-E at the folded
extreme).  They have several roots; each is returned with what the *simulated* mechanism does
(:mod:`synthesis.kinematics.rocker_drive`), because eq (10) is only one of the two candidate
minima of the transmission angle (crank along the frame; the other is the crank against it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import root

from synthesis.kinematics.rocker_drive import CrankRocker, acute, quick_return, transmission_angles_deg


def extreme_crank_angle(time_ratio: float) -> float:
    """Eq (8), rad."""
    return math.pi * (time_ratio - 1.0) / (time_ratio + 1.0)


def residuals(z, time_ratio: float, swing: float, gamma_min: float, l10: float) -> np.ndarray:
    """Eq (9a), (9b), (9c) in mm^2 / l10^2 and eq (10) as cos - cos; z = (l7, l8, l9, theta1), angles rad."""
    l7, l8, l9, t1 = z
    th = extreme_crank_angle(time_ratio)
    s, d = l7 + l8, l8 - l7
    scale = l10 * l10
    return np.array([
        (s * s - (l9 * l9 + l10 * l10 - 2 * l9 * l10 * math.cos(t1 + swing))) / scale,
        (d * d - (l9 * l9 + l10 * l10 - 2 * l9 * l10 * math.cos(t1))) / scale,
        ((2 * l9 * math.sin(swing / 2)) ** 2 - (s * s + d * d - 2 * s * d * math.cos(th))) / scale,
        (l8 * l8 + l9 * l9 - (l10 - l7) ** 2) / (2 * l8 * l9) - math.cos(gamma_min),
    ])


@dataclass(frozen=True)
class ClassicalDesign:
    l7: float
    l8: float
    l9: float
    theta1_deg: float
    # what the simulated mechanism does (None when its crank cannot turn fully)
    time_ratio: float | None
    swing_deg: float | None
    min_transmission_deg: float | None

    @property
    def total_length(self) -> float:
        return self.l7 + self.l8 + self.l9

    def to_json(self) -> dict:
        return {"l7": self.l7, "l8": self.l8, "l9": self.l9, "theta1_deg": self.theta1_deg,
                "total_length": self.total_length, "simulated_time_ratio": self.time_ratio,
                "simulated_swing_deg": self.swing_deg, "simulated_min_transmission_deg": self.min_transmission_deg}


def _start_points(swing: float, l10: float):
    for t1 in np.radians(np.arange(2.0, 178.0 - math.degrees(swing), 4.0)):
        for ratio in (0.4, 0.7, 1.0, 1.4, 2.0):
            l9 = ratio * l10
            s2 = l9 * l9 + l10 * l10 - 2 * l9 * l10 * math.cos(t1 + swing)
            d2 = l9 * l9 + l10 * l10 - 2 * l9 * l10 * math.cos(t1)
            s, d = math.sqrt(max(s2, 1e-6)), math.sqrt(max(d2, 1e-6))
            yield np.array([(s - d) / 2, (s + d) / 2, l9, t1])


def solve_paper_equations(time_ratio: float, swing_deg: float, gamma_min_deg: float, l10: float,
                          branch: int = 1) -> list[ClassicalDesign]:
    """Every root of eq (8)-(10) with positive lengths, shortest first, each simulated."""
    swing, gamma = math.radians(swing_deg), math.radians(gamma_min_deg)
    found: dict[tuple, np.ndarray] = {}
    for z0 in _start_points(swing, l10):
        sol = root(residuals, z0, args=(time_ratio, swing, gamma, l10), method="hybr", options={"xtol": 1e-13})
        l7, l8, l9, t1 = sol.x
        if not sol.success or np.max(np.abs(sol.fun)) > 1e-10:
            continue
        if min(l7, l8, l9) <= 0 or not 0.0 < t1 < math.pi:
            continue
        found.setdefault(tuple(np.round(sol.x, 6)), sol.x)
    designs = []
    for l7, l8, l9, t1 in found.values():
        cr = CrankRocker(l7, l8, l9, l10, branch)
        k = psi = gmin = None
        if cr.crank_turns():
            q = quick_return(cr)
            k, psi = q.time_ratio, math.degrees(q.swing)
            gmin = float(acute(transmission_angles_deg(cr, 720)).min())
        designs.append(ClassicalDesign(float(l7), float(l8), float(l9), math.degrees(t1), k, psi, gmin))
    return sorted(designs, key=lambda d: d.total_length)
