"""One turn of follower motion: rise, far dwell, return, near dwell, placed on the picker's clock.

The rise and the return each follow a normalised law (synthesis.kinds.clamp_cam.kinematics.motion_laws, or the
fitted B-spline law); the return runs the law backwards: s = h (1 - law(u)).  Angles in degrees
at the edges, radians inside: derivatives are taken with respect to the cam angle in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

SEGMENT_NAMES = ("rise", "far_dwell", "return", "near_dwell")


class NormalisedLaw(Protocol):
    name: str

    def s(self, u): ...
    def v(self, u): ...
    def a(self, u): ...
    def j(self, u): ...
    @property
    def peaks(self) -> dict[str, float]: ...


@dataclass(frozen=True)
class Timing:
    """Segment angles and where the rise begins, deg (values, floats or CasADi symbols)."""

    rise_start: Any
    rise: Any
    far_dwell: Any
    return_: Any
    near_dwell: Any

    @classmethod
    def from_design(cls, design: dict) -> "Timing":
        return cls(design["rise_start"], design["rise"], design["far_dwell"], design["return"], design["near_dwell"])

    def starts(self) -> dict[str, Any]:
        """Crank angle (deg, unwrapped from rise_start) at which each segment begins, and the turn's end."""
        r = self.rise_start
        far = r + self.rise
        ret = far + self.far_dwell
        near = ret + self.return_
        return {"rise": r, "far_dwell": far, "return": ret, "near_dwell": near, "end": r + 360.0}

    def span(self, name: str) -> tuple:
        st = self.starts()
        following = {"rise": "far_dwell", "far_dwell": "return", "return": "near_dwell", "near_dwell": "end"}
        return st[name], st[following[name]]


@dataclass(frozen=True)
class Samples:
    """Follower displacement and its derivatives with respect to the cam angle (rad) at given angles."""

    phi_deg: np.ndarray
    s: np.ndarray
    ds: np.ndarray
    dds: np.ndarray
    ddds: np.ndarray
    segment: np.ndarray          # index into SEGMENT_NAMES


@dataclass(frozen=True)
class CamMotion:
    """Follower motion over a turn; stroke in mm (translating) or rad (oscillating)."""

    stroke: float
    timing: Timing
    rise_law: NormalisedLaw
    return_law: NormalisedLaw

    def segment(self, name: str, u: np.ndarray) -> Samples:
        """Samples at fractions u in [0, 1] of one segment."""
        u = np.asarray(u, dtype=float)
        t = self.timing
        beta = math.radians({"rise": t.rise, "far_dwell": t.far_dwell, "return": t.return_,
                             "near_dwell": t.near_dwell}[name])
        lo, hi = t.span(name)
        phi = lo + u * (hi - lo)
        h, zero = self.stroke, np.zeros_like(u)
        k = SEGMENT_NAMES.index(name)
        if name == "rise":
            law = self.rise_law
            return Samples(phi, h * law.s(u), h * law.v(u) / beta, h * law.a(u) / beta**2, h * law.j(u) / beta**3,
                           np.full(u.shape, k))
        if name == "return":
            law = self.return_law
            return Samples(phi, h * (1.0 - law.s(u)), -h * law.v(u) / beta, -h * law.a(u) / beta**2,
                           -h * law.j(u) / beta**3, np.full(u.shape, k))
        level = h if name == "far_dwell" else 0.0
        return Samples(phi, zero + level, zero, zero, zero, np.full(u.shape, k))

    def at(self, phi_deg) -> Samples:
        """Samples at any crank angles (deg on the picker's clock)."""
        phi = np.atleast_1d(np.asarray(phi_deg, dtype=float))
        t = self.timing
        tau = np.mod(phi - t.rise_start, 360.0)
        bounds = np.cumsum([0.0, t.rise, t.far_dwell, t.return_])
        seg = np.clip(np.searchsorted(bounds, tau, side="right") - 1, 0, 3)
        out = {k: np.zeros_like(phi) for k in ("s", "ds", "dds", "ddds")}
        for k, name in enumerate(SEGMENT_NAMES):
            mask = seg == k
            if not mask.any():
                continue
            width = (t.rise, t.far_dwell, t.return_, t.near_dwell)[k]
            u = (tau[mask] - bounds[k]) / width if width > 0 else np.zeros(mask.sum())
            smp = self.segment(name, np.clip(u, 0.0, 1.0))
            for key in out:
                out[key][mask] = getattr(smp, key)
        return Samples(phi, out["s"], out["ds"], out["dds"], out["ddds"], seg)
