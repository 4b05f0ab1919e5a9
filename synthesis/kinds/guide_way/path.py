"""The claw-tip path of a guide_way spec as sampled stretches in time order.

Conic path: one stretch per ``[[conic]]`` segment, uniform in the conic's own parameter, end points
the key points projected onto the conic (a key point farther than ``rules.joint_gap`` from a conic it
ends is bad input: the conics do not meet there).  Spline path: one stretch per pair of consecutive
key points of the controlled part; the stretches meeting at the fold stop ``FOLD_OFFSET`` short of it
(the inverse kinematics is singular exactly there: |OM| = R - d).

Inverse-kinematics branch: a conic segment says its own (``branch``); on a spline the claw is on
the "plus" elbow before the fold and the "minus" one (the paper's eq 7) after it, as on the paper's
DE and CD/BC/AB.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from synthesis.errors import SpecError
from synthesis.kinds.guide_way import conics as cn
from synthesis.kinds.guide_way import spline as sp
from synthesis.kinds.guide_way.trace import Stretch

if TYPE_CHECKING:
    import casadi as ca

#: the inverse-kinematics branch's sign by its name (theta = gamma + sign * phi); a conic's spec writes the sign
BRANCH = {"minus": -1.0, "plus": 1.0}
#: spline stretches stop this far (in u) short of the fold on either side
FOLD_OFFSET = 1e-3


@dataclass
class ConicPiece:
    """A conic segment prepared for sampling."""

    name: str
    conic: cn.CentralConic
    t0: float
    t1: float
    branch: float
    form: str | None
    start: str
    end: str
    gaps: dict = field(default_factory=dict)       # key point -> distance from the conic, mm

    def stretch(self, n: int) -> Stretch:
        """Samples uniform in s in [0, 1], t = t0 + s (t1 - t0): derivatives by s follow the claw in time order."""
        return self.stretch_at(np.linspace(0.0, 1.0, n))

    def stretch_at(self, s: np.ndarray) -> Stretch:
        """The samples at the parameters ``s`` in [0, 1] (time order)."""
        t, w = self.t0 + s * (self.t1 - self.t0), self.t1 - self.t0
        m = np.column_stack(self.conic.at(t, 0))
        m1 = np.column_stack(self.conic.at(t, 1)) * w
        m2 = np.column_stack(self.conic.at(t, 2)) * w * w
        return Stretch(self.name, self.branch, s, m, m1, m2)


def conic_pieces(spec) -> list[ConicPiece]:
    """The spec's conic segments; SpecError when one is not a central conic or misses its key points."""
    pieces = []
    for k, seg in enumerate(spec.conic):
        where = f"conic[{k}] ({seg.name})"
        try:
            conic = cn.CentralConic.of(seg.coefficients)
        except ValueError as exc:
            raise SpecError(f"{where}: {exc}") from None
        start, end = spec.points[seg.start], spec.points[seg.end]
        if conic.hyperbola:
            conic = conic.with_branch(conic.branch_of(*start))
            if conic.branch_of(*end) != conic.branch:
                raise SpecError(f"{where}: {seg.start} and {seg.end} lie on different branches of the hyperbola")
        gaps = {}
        for name, p in ((seg.start, start), (seg.end, end)):
            _, gap = conic.parameter(*p)
            gaps[name] = gap
            if gap > spec.rules.joint_gap:
                raise SpecError(f"{where}: point {name} ({p[0]:g}, {p[1]:g}) lies {gap:.4g} mm from the conic "
                                f"(rules.joint_gap = {spec.rules.joint_gap:g} mm): the conics do not meet at {name}")
        t0, t1 = cn.span(conic, start, end, seg.via)
        pieces.append(ConicPiece(seg.name, conic, t0, t1, float(seg.branch), seg.form, seg.start, seg.end, gaps))
    return pieces


@dataclass
class SplinePath:
    """A periodic spline path: its keys and control points (numbers or an SX n x 2 matrix; None in a path made
    for its keys alone, which has no stretches)."""

    keys: sp.Keys
    control: np.ndarray | ca.SX | None
    n: int

    def stretches(self, samples: int) -> list[Stretch]:
        """The controlled stretches in time order, ``samples`` each (numeric or symbolic with the control points)."""
        keys, out = self.keys, []
        fold_u = keys.u[keys.index(keys.fold)]
        passed = False
        for i in range(len(keys.names) - 1):
            a, b = keys.u[i], keys.u[i + 1]
            if keys.names[i] == keys.fold:
                a += FOLD_OFFSET
                passed = True
            if keys.names[i + 1] == keys.fold:
                b -= FOLD_OFFSET
            u = np.linspace(a, b, samples)
            out.append(self.stretch_at(f"{keys.names[i]}{keys.names[i + 1]}", BRANCH["minus" if passed else "plus"], u))
        assert fold_u > 0
        return out

    def closing(self, samples: int) -> np.ndarray:
        """The uncontrolled stretch (last key -> first key) as claw-tip points (numeric paths only)."""
        u = np.linspace(self.keys.u[-1], 1.0, samples)
        return sp.basis(self.n, u) @ np.asarray(self.control, float)

    def stretch_at(self, name: str, branch: float, u: np.ndarray) -> Stretch:
        ms = [sp.basis(self.n, u, k) for k in range(3)]
        c = self.control
        if isinstance(c, np.ndarray):
            return Stretch(name, branch, u, *(b @ c for b in ms))
        import casadi as ca

        assert c is not None, "a spline path made for its keys alone has no stretches"
        return Stretch(name, branch, u, *((ca.DM(b) @ c).T for b in ms))

    def near_fold(self, side: int, delta: float) -> Stretch:
        """Two samples at u_fold -/+ delta, 2 delta (side -1: before the fold, +1: after) for one-sided limits."""
        fold_u = self.keys.u[self.keys.index(self.keys.fold)]
        u = fold_u + side * np.array([delta, 2 * delta])
        return self.stretch_at("fold", BRANCH["plus" if side < 0 else "minus"], u)


def key_parameters_ok(keys: sp.Keys) -> None:
    if any(b <= a for a, b in zip(keys.u, keys.u[1:])):
        raise SpecError("spline.keys: two consecutive key points coincide")


def loop_length(points: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(points, axis=0).T)))


def unwrap_deg(theta: np.ndarray) -> np.ndarray:
    return np.degrees(np.unwrap(np.asarray(theta, float)))


def angle_deg(v) -> float:
    return math.degrees(math.atan2(v[1], v[0]))
