"""The finite-difference scheme of seed 000 (eq. 8-14), kept to measure it against exact AD values.

The paper estimates speed from the two chords around C_i (eq. 9, read without the OCR's stray
outer root) and the direction as the mean of the two chord angles (eq. 10, tan^-1 of the slopes);
acceleration the same way from the velocity components (eq. 12-14).  ``scheme="atan"`` reproduces
that literally (a tan^-1 of a slope only spans (-90, 90) deg, so directions near vertical flip by
180 deg); ``scheme="atan2"`` is the same chord-average with quadrant-correct angles.
"""

from __future__ import annotations

import numpy as np

from synthesis.kinds.planting.kinematics import ArmDesign, Motion, tip_state


def _chord_average(p_prev, p, p_next, omega: float, dtheta: float, scheme: str):
    """Magnitude = mean chord length * omega / dtheta; direction = mean of the two chord angles."""
    d1, d2 = p - p_prev, p_next - p
    mag = (np.hypot(*d1) + np.hypot(*d2)) * omega / (2.0 * dtheta)
    if scheme == "atan":
        with np.errstate(divide="ignore", invalid="ignore"):
            a1, a2 = np.arctan(d1[1] / d1[0]), np.arctan(d2[1] / d2[0])
        ang = 0.5 * (a1 + a2)
    else:
        a1, a2 = np.arctan2(d1[1], d1[0]), np.arctan2(d2[1], d2[0])
        ang = a1 + 0.5 * np.angle(np.exp(1j * (a2 - a1)))
    return np.vstack([mag * np.cos(ang), mag * np.sin(ang)])


def paper_velocity_acceleration(design: ArmDesign, motion: Motion, theta: np.ndarray, dtheta: float,
                                scheme: str = "atan") -> tuple[np.ndarray, np.ndarray]:
    """(velocity, acceleration), each (2, N), at crank angles theta by the seed's difference scheme."""
    offsets = np.array([-2, -1, 0, 1, 2]) * dtheta
    pos = [tip_state(design, motion, theta + o).pos for o in offsets]
    vel = [_chord_average(pos[i - 1], pos[i], pos[i + 1], motion.omega, dtheta, scheme) for i in (1, 2, 3)]
    acc = _chord_average(vel[0], vel[1], vel[2], motion.omega, dtheta, scheme)
    return vel[1], acc


def mean_relative_errors(design: ArmDesign, motion: Motion, dtheta_deg: float, samples: int = 360,
                         scheme: str = "atan") -> dict[str, float]:
    """Mean over ``samples`` crank angles of |v_fd| vs |v| and |a_fd - a| / |a| (the seed's percentages)."""
    theta = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    exact = tip_state(design, motion, theta)
    v, a = paper_velocity_acceleration(design, motion, theta, np.radians(dtheta_deg), scheme)
    speed = np.hypot(*exact.vel)
    acc = np.hypot(*exact.acc)
    return {
        "speed_magnitude": float(np.mean(np.abs(np.hypot(*v) - speed) / speed)),
        "acceleration_magnitude": float(np.mean(np.abs(np.hypot(*a) - acc) / acc)),
        "acceleration_vector": float(np.mean(np.hypot(*(a - exact.acc)) / acc)),
    }
