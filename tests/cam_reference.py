"""Independent references for the clamp_cam tests, written without synthesis.kinds.clamp_cam.kinematics.cam_follower.

* ``sampled_roller_envelope``: the cam a cutter leaves when it removes every sampled roller disc;
  its polar radius along a ray is the first hit on any disc (no derivatives, no normals).
* ``pole_pressure_angle_*``: the pressure angle by the instant-centre construction of textbooks:
  the contact normal passes through the relative pole of cam and follower.
* ``three_point_radius``: radius of the circle through three neighbouring points of a curve.
"""

from __future__ import annotations

import numpy as np


def translating_pitch(s: np.ndarray, phi: np.ndarray, r0: float, e: float = 0.0) -> np.ndarray:
    """Roller centre in the cam frame for a translating follower: R(-phi) (s0 + s, -e)."""
    s0 = np.sqrt(r0**2 - e**2)
    x, y = s0 + s, -e + 0.0 * s
    c, sn = np.cos(phi), np.sin(phi)
    return np.column_stack([c * x + sn * y, -sn * x + c * y])


def sampled_roller_envelope(centres: np.ndarray, roller: float, theta: np.ndarray) -> np.ndarray:
    """Polar radius, along each ray theta from the cam centre, of the first hit on any roller disc."""
    ang = np.arctan2(centres[:, 1], centres[:, 0])
    order = np.argsort(ang)
    ang, pts = ang[order], centres[order]
    ang = np.concatenate([ang - 2 * np.pi, ang, ang + 2 * np.pi])
    pts = np.vstack([pts, pts, pts])
    dist = np.hypot(pts[:, 0], pts[:, 1])
    half = np.arcsin(min(1.0, roller / dist.min())) + 1e-3
    out = np.empty_like(theta, dtype=float)
    for k, t in enumerate(theta):
        lo, hi = np.searchsorted(ang, [t - half, t + half])
        p = pts[lo:hi]
        d = np.array([np.cos(t), np.sin(t)])
        along = p @ d
        disc = roller**2 - (np.einsum("ij,ij->i", p, p) - along**2)
        hit = disc >= 0
        out[k] = np.min(along[hit] - np.sqrt(disc[hit]))
    return out


def pole_pressure_angle_translating(s, ds, r0: float, e: float = 0.0) -> np.ndarray:
    """|pressure angle| (deg): the pole of cam and follower lies on the Y axis at y = -ds/dphi."""
    s0 = np.sqrt(r0**2 - e**2)
    cx, cy = s0 + s, -e
    nx, ny = cx - 0.0, cy - (-ds)                 # normal line: roller centre minus pole
    return np.degrees(np.arccos(np.abs(nx) / np.hypot(nx, ny)))


def pole_pressure_angle_oscillating(psi, dpsi, r0: float, a: float, l: float, side: int) -> np.ndarray:
    """|pressure angle| (deg) of an arm pivoting at (a, 0): the pole lies on the line of centres O-Q
    where the cam (omega = 1, counter-clockwise) and the arm (-side * dpsi) have the same velocity."""
    psi0 = np.arccos((a**2 + l**2 - r0**2) / (2 * a * l))
    g = psi0 + psi
    cx, cy = a - l * np.cos(g), side * l * np.sin(g)
    omega_f = -side * dpsi
    xp = -omega_f * a / (1.0 - omega_f)
    n = np.column_stack([cx - xp, cy])                        # normal line: roller centre minus pole
    d = np.column_stack([-cy, cx - a])                        # J (C - Q): perpendicular to the arm
    cosang = np.abs(np.einsum("ij,ij->i", n, d)) / (np.hypot(*n.T) * np.hypot(*d.T))
    return np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))


def three_point_radius(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Signed radius of the circle through three points; > 0 when they turn clockwise (convex here)."""
    a = np.hypot(*(p1 - p0).T)
    b = np.hypot(*(p2 - p1).T)
    c = np.hypot(*(p2 - p0).T)
    cross = (p1 - p0)[:, 0] * (p2 - p0)[:, 1] - (p1 - p0)[:, 1] * (p2 - p0)[:, 0]
    return -a * b * c / (2.0 * cross)
