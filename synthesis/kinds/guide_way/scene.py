"""A guide way evaluated: the claw path sampled, the arm solved at every sample, joints, fold and rules.

``scene_of(spec, samples, control)`` works on numbers (check, re-check); ``symbolic_rules`` builds the
same sampled rules on the spline's control points as CasADi symbols (the NLP).  ``rules_of`` is the
one rules function: a trace (the arms of every stretch) in, rules out, floats or symbols.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import overload

import casadi as ca
import numpy as np

from synthesis.kinds.guide_way import rules as gw
from synthesis.errors import SpecError
from synthesis.kinds.guide_way import path as pth
from synthesis.kinds.guide_way import spline as sp
from synthesis.kinds.guide_way.trace import Arm, Stretch, arm_vector, evaluate
from synthesis.kinds.guide_way import kinematics as ra
from synthesis.kinds.guide_way.spec import GuideWaySpec


def arm_of(spec) -> list[float]:
    a = spec.arm
    return arm_vector(a.radius, a.claw, a.crank, a.beta)


def _cat(parts):
    if isinstance(parts[0], (ca.SX, ca.MX)):
        return ca.vertcat(*parts)
    return np.concatenate([np.asarray(p, float) for p in parts])


def controlled_keys(spec) -> list[str]:
    """The key points of the controlled path in time order."""
    if spec.conic is not None:
        return [spec.conic[0].start] + [s.end for s in spec.conic]
    return list(spec.spline.keys)


def fold_stretches(spec) -> tuple[int, int]:
    """Indices of the stretches ending and starting at the fold (-1, -1 when there is no fold)."""
    keys = controlled_keys(spec)
    fold = spec.fold if spec.conic is not None else spec.spline.fold
    if fold is None:
        return -1, -1
    k = keys.index(fold)
    return k - 1, k


def pressure_masks(spec, arms: list[Arm], fold_theta: tuple[float, float] | None = None) -> list[np.ndarray]:
    """Per stretch (numeric arms): the samples the pressure-angle rule holds at, i.e. all but those within
    ``rules.fold_window`` deg of arm angle of the fold (the dead point, where it is 90 deg by geometry).
    ``fold_theta``: the arm angle (rad) at the fold itself, arriving and leaving (:attr:`Scene.fold_theta`); a
    spline's stretches stop short of the fold, where the arm turns fast (0.37 deg in 1e-3 of u), so the window is
    measured from the fold's own angle, not from the stretches' last samples (None: the path has no fold)."""
    w = spec.rules.fold_window
    masks = [np.ones(np.asarray(a.theta).size, bool) for a in arms]
    before, after = fold_stretches(spec)
    if w > 0 and before >= 0:
        assert fold_theta is not None           # a path with a fold has its arm angles there
        for side, (k, i) in enumerate(((before, -1), (after, 0))):
            th = np.degrees(np.unwrap(np.asarray(arms[k].theta, float)))
            masks[k] = np.abs(th - nearest_turn(math.degrees(fold_theta[side]), th[i])) >= w - EDGE_TOLERANCE
    return masks


#: a sample this close (deg) to the window's edge counts as outside: the edge samples :func:`with_edge_samples`
#: adds lie on it to the root finder's tolerance
EDGE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class WindowEdge:
    """An exact edge of the fold window on stretch ``k``: the parameter ``u`` where the arm angle is ``centre_deg``
    + ``sign`` x the window (deg; ``centre_deg`` the fold's own arm angle, the turn nearest the stretch's)."""

    k: int
    u: float
    centre_deg: float
    sign: float


def window_edges(spec, stretches: list, arms: list[Arm], fold_theta: tuple[float, float] | None,
                 remake) -> list[WindowEdge]:
    """The exact edges of the fold window on the fold's stretches (numeric paths): the roots of |theta(u) - centre|
    = window between the samples where that changes sign.  ``remake(k, params)`` samples stretch ``k`` at other
    parameters."""
    w = spec.rules.fold_window
    before, after = fold_stretches(spec)
    if w <= 0 or before < 0 or fold_theta is None:
        return []
    from scipy.optimize import brentq

    vector = arm_of(spec)
    edges = []
    for side, (k, i) in enumerate(((before, -1), (after, 0))):
        st = stretches[k]
        th = np.degrees(np.unwrap(np.asarray(arms[k].theta, float)))
        centre = nearest_turn(math.degrees(fold_theta[side]), th[i])
        outside = np.abs(th - centre) - w
        crossings = np.flatnonzero(np.sign(outside[:-1]) * np.sign(outside[1:]) < 0)

        def beyond_edge(u: float, near: float) -> float:
            theta = math.degrees(float(evaluate(remake(k, np.array([u])), vector).theta[0]))
            return abs(nearest_turn(theta, near) - centre) - w

        for j in crossings:
            try:
                u = brentq(beyond_edge, st.u[j], st.u[j + 1], args=(th[j],), xtol=1e-15,
                           rtol=4 * np.finfo(float).eps)
            except ValueError:    # a sample within rounding of the edge: one evaluation disagrees with the batch's
                continue
            out = j if outside[j] > 0 else j + 1          # the sample of the pair outside the window: its side
            edges.append(WindowEdge(k, float(u), centre, float(np.sign(th[out] - centre))))
    return edges


def with_edge_samples(spec, stretches: list, arms: list[Arm], edges: list[WindowEdge], remake) -> list[Arm]:
    """The arms of the fold's stretches with one more sample at each exact edge of the fold window (numeric
    paths; ``edges`` from :func:`window_edges`).  The pressure angle climbs towards 90 deg at the fold, so its
    largest value outside the window is at the window's edge: between two samples it is missed (81.76 deg at a
    sample 0.16 deg inside the allowed side against 81.80 deg at the edge)."""
    arms, vector = list(arms), arm_of(spec)
    for k in sorted({e.k for e in edges}):
        arms[k] = evaluate(remake(k, np.union1d(stretches[k].u, [e.u for e in edges if e.k == k])), vector)
    return arms


def nearest_turn(deg: float, near: float) -> float:
    """``deg`` plus the whole turns that bring it nearest to ``near``."""
    return deg + 360.0 * round((near - deg) / 360.0)


def fold_arm_angles(m: tuple[float, float], R: float, d: float) -> tuple[float, float]:
    """The arm angle (rad) with the claw tip at the fold point ``m``, on the branch arriving there and on the one
    leaving (a spline's before and after the fold: plus, then minus; theta = gamma + branch * phi).  The fold point
    lies on |OM| = R - d, where phi = 0 and both are gamma; its cos phi may round an ulp past 1, so it is clipped."""
    x, y = m
    gamma = math.atan2(-x, -y)
    phi = math.acos(min(1.0, max(-1.0, ra.fold_cosine(R, d, x, y))))
    return gamma + pth.BRANCH["plus"] * phi, gamma + pth.BRANCH["minus"] * phi


@overload
def fold_direction(m: Sequence[float]) -> float: ...


@overload
def fold_direction(m: ca.SX) -> ca.SX: ...


def fold_direction(m: Sequence[float] | ca.SX) -> float | ca.SX:
    """The arm angle (rad) with the claw tip at a spline's fold point ``m`` on |OM| = R - d, where the arriving and
    leaving arm angles meet (phi = 0 in :func:`fold_arm_angles`): the fold window's centre.  Off that circle the
    two part by +-phi, a square root of the distance to it, with no derivative on the circle where every drivable
    fold lies (a tolerance analysis perturbs the fold off it); the direction of OM is smooth there, and on the
    circle it is both angles.  Floats or CasADi symbols."""
    x, y = m[0], m[1]
    return ca.atan2(-x, -y) if isinstance(x, (ca.SX, ca.MX)) else math.atan2(-x, -y)


def rules_of(spec, arms: list[Arm], masks: list[np.ndarray], edge_arms: Sequence[Arm] = ()) -> list:
    """The sampled rules over the controlled path (floats or symbols): reach, arm direction, undercut, pressure
    angle (at the samples ``masks`` keep: :attr:`Scene.pressure_masks` of the numeric path, and at the fold
    window's edges ``edge_arms``: the NLP's, where the edge moves with the design)."""
    a, lim = spec.arm, spec.rules
    where = "controlled path " + "-".join(controlled_keys(spec))
    along = [e.along_crank for e in edge_arms]
    for s, keep in zip(arms, masks):
        idx = [int(i) for i in np.flatnonzero(keep)]
        along.append(s.along_crank[idx] if isinstance(s.along_crank, (ca.SX, ca.MX)) else
                     np.asarray(s.along_crank, float)[idx])
    pa_where = where + (f", outside {lim.fold_window:g} deg of arm angle about the fold" if lim.fold_window else "")
    return [gw.reach_rule(_cat([s.rho for s in arms]), a.radius, a.claw, where),
            gw.turning_rule(_cat([s.turning for s in arms]), where),
            gw.undercut_rule(_cat([s.kappa for s in arms]), a.roller_radius, lim.roller_margin, where),
            gw.pressure_angle_rule(_cat(along), lim.max_pressure_angle, pa_where)]


@dataclass
class End:
    """The roller-centre line at one end of a stretch (a one-sided limit at a joint)."""

    theta_deg: float
    n: tuple[float, float]
    tangent_deg: float
    kappa: float
    m: tuple[float, float]
    m_tangent_deg: float

    def to_json(self) -> dict:
        return {"theta_deg": self.theta_deg % 360.0, "roller_centre": list(self.n), "tangent_deg": self.tangent_deg,
                "curvature_per_mm": self.kappa, "claw_tip": list(self.m), "claw_tangent_deg": self.m_tangent_deg}


def _end(arm: Arm, i: int) -> End:
    return End(math.degrees(float(arm.theta[i])), (float(arm.n[0][i]), float(arm.n[1][i])),
               math.degrees(math.atan2(arm.n1[1][i], arm.n1[0][i])), float(arm.kappa[i]),
               (float(arm.m[0][i]), float(arm.m[1][i])), math.degrees(math.atan2(arm.m1[1][i], arm.m1[0][i])))


def _extrapolated(arm: Arm) -> End:
    """The one-sided limit at the fold of a spline path from samples at delta and 2 delta (linear extrapolation)."""
    e1, e2 = _end(arm, 0), _end(arm, 1)
    lin = lambda a, b: 2 * a - b  # noqa: E731
    return End(lin(e1.theta_deg, e2.theta_deg), (lin(e1.n[0], e2.n[0]), lin(e1.n[1], e2.n[1])),
               lin(e1.tangent_deg, e2.tangent_deg), lin(e1.kappa, e2.kappa), (lin(e1.m[0], e2.m[0]), lin(e1.m[1], e2.m[1])),
               lin(e1.m_tangent_deg, e2.m_tangent_deg))


def _wrap(deg: float) -> float:
    return (deg + 180.0) % 360.0 - 180.0


@dataclass
class Joint:
    name: str
    before: End
    after: End

    @property
    def position_jump(self) -> float:
        return math.dist(self.before.n, self.after.n)

    @property
    def tangent_jump(self) -> float:
        return abs(_wrap(self.after.tangent_deg - self.before.tangent_deg))

    @property
    def curvature_jump(self) -> float:
        return abs(self.after.kappa - self.before.kappa)

    def to_json(self) -> dict:
        return {"before": self.before.to_json(), "after": self.after.to_json(),
                "theta_jump_deg": _wrap(self.after.theta_deg - self.before.theta_deg),
                "position_jump_mm": self.position_jump, "tangent_jump_deg": self.tangent_jump,
                "curvature_jump_per_mm": self.curvature_jump,
                "claw_tip_gap_mm": math.dist(self.before.m, self.after.m)}


@dataclass
class Scene:
    spec: GuideWaySpec
    arms: list[Arm]
    joints: list[Joint]
    fold: dict | None                    # {point, excess_mm, tangent_error_deg, ...}
    pieces: list | None = None           # conic path: ConicPiece per segment
    spline: pth.SplinePath | None = None
    closing: np.ndarray | None = None    # spline path: the uncontrolled stretch's claw-tip points
    notes: list[str] = field(default_factory=list)
    #: the arm angle (rad) at the fold, arriving and leaving (None without a fold)
    fold_theta: tuple[float, float] | None = None
    #: the fold window's exact edges on the path (:func:`window_edges`)
    edges: list = field(default_factory=list)
    #: the arm angle (rad) the fold window is measured from, before and after the fold, when not ``fold_theta``
    #: (a spline: :func:`fold_direction`)
    window_centre: tuple[float, float] | None = None

    @property
    def pressure_masks(self) -> list[np.ndarray]:
        return pressure_masks(self.spec, self.arms, self.window_centre or self.fold_theta)

    @property
    def rules(self) -> list:
        lim = self.spec.rules
        rules = rules_of(self.spec, self.arms, self.pressure_masks)
        for j in self.joints:
            rules += [gw.jump_rule(j.name, "position", j.position_jump, lim.joint_position),
                      gw.jump_rule(j.name, "tangent", j.tangent_jump, lim.joint_tangent),
                      gw.jump_rule(j.name, "curvature", j.curvature_jump, lim.joint_curvature)]
        if self.fold is not None:
            rules += [gw.fold_distance_rule(self.fold["point"], self.fold["excess_mm"], lim.fold_distance),
                      gw.fold_angle_rule(self.fold["point"], self.fold["tangent_error_deg"], lim.fold_angle)]
        if self.spline is not None:          # the NLP holds these as equality rows; a given control polygon may not
            met = key_misses(self.spline)
            rules.append(gw.key_points_rule({k: e["miss_mm"] for k, e in met.items()}, lim.key_point))
            tangents = {k: e["tangent_miss_deg"] for k, e in met.items() if "tangent_miss_deg" in e}
            if tangents:
                rules.append(gw.key_tangents_rule(tangents, lim.key_tangent))
        return rules


def key_misses(path: pth.SplinePath) -> dict[str, dict]:
    """Per key point of a spline path: its parameter u, the target (the fold moved onto |OM| = R - d), where the
    path is at u and the distance between them (mm); with a tangent, the path's direction there, the given one
    and the angle between them (deg)."""
    c = np.asarray(path.control, float)
    keys = path.keys
    met = {}
    for name, u, p in zip(keys.names, keys.u, keys.points):
        m = (sp.basis(path.n, u) @ c)[0]
        entry = {"u": u, "target": [float(p[0]), float(p[1])], "point": [float(m[0]), float(m[1])],
                 "miss_mm": math.dist(m, p)}
        if name in keys.tangents:
            t = (sp.basis(path.n, u, 1) @ c)[0]
            want = math.degrees(math.atan2(keys.tangents[name][1], keys.tangents[name][0]))
            got = math.degrees(math.atan2(t[1], t[0]))
            entry.update(tangent_target_deg=want, tangent_deg=got, tangent_miss_deg=abs(_wrap(got - want)))
        met[name] = entry
    return met


def _unreachable(spec, stretch_name: str, arm: Arm) -> None:
    """SpecError naming the stretch and the first claw-tip point the arm cannot reach."""
    c = np.asarray(arm.cos_phi, float)
    bad = np.flatnonzero(~(np.abs(c) <= 1.0))
    if bad.size:
        i = int(bad[0])
        a = spec.arm
        x, y = float(arm.m[0][i]), float(arm.m[1][i])
        reach, lo, hi = math.hypot(x, y), a.radius - a.claw, a.radius + a.claw
        # as many digits as tell the reach from the bound it passes (20.3 "outside" 20.32 read as a contradiction)
        digits = 4
        while digits < 12 and float(f"{reach:.{digits}g}") in (float(f"{lo:.{digits}g}"), float(f"{hi:.{digits}g}")):
            digits += 1
        raise SpecError(f"segment {stretch_name}: the arm cannot reach the claw tip at ({x:.4g}, {y:.4g}) mm: "
                        f"|OM| = {reach:.{digits}g} mm lies outside [R - d, R + d] = "
                        f"[{lo:.{digits}g}, {hi:.{digits}g}] mm")


def _fold_of(point: str, m: tuple[float, float], tangents_deg: list[float], R: float, d: float) -> dict:
    radial = math.degrees(math.atan2(m[1], m[0]))
    errors = [_wrap(t - radial) for t in tangents_deg]
    errors = [abs(e) - 90.0 for e in errors]
    worst = max(errors, key=abs)
    return {"point": point, "claw_tip": list(m), "distance_mm": math.hypot(*m), "fold_radius_mm": R - d,
            "excess_mm": math.hypot(*m) - (R - d), "tangent_deg": tangents_deg, "tangent_error_deg": worst}


def conic_scene(spec, samples: int) -> Scene:
    pieces = pth.conic_pieces(spec)
    arm = arm_of(spec)
    arms, stretches = [], [piece.stretch(samples) for piece in pieces]
    for piece, st in zip(pieces, stretches):
        a = evaluate(st, arm)
        _unreachable(spec, piece.name, a)
        arms.append(a)
    joints = [Joint(p.end, _end(a, -1), _end(b, 0)) for p, a, b in zip(pieces, arms, arms[1:])]
    fold = None
    if spec.fold is not None:
        k = [p.end for p in pieces].index(spec.fold)
        m = spec.points[spec.fold]
        tangents = [_end(arms[k], -1).m_tangent_deg, _end(arms[k + 1], 0).m_tangent_deg]
        fold = _fold_of(spec.fold, (float(m[0]), float(m[1])), tangents, spec.arm.radius, spec.arm.claw)
    # a conic piece ends on its key point: the arm angles there are its end samples'
    fold_theta = None if fold is None else (float(arms[k].theta[-1]), float(arms[k + 1].theta[0]))
    remake = lambda k, s: pieces[k].stretch_at(s)      # noqa: E731
    edges = window_edges(spec, stretches, arms, fold_theta, remake)
    arms = with_edge_samples(spec, stretches, arms, edges, remake)
    return Scene(spec, arms, joints, fold, pieces=pieces, fold_theta=fold_theta, edges=edges)


def spline_path(spec, control) -> pth.SplinePath:
    s = spec.spline
    keys = sp.keys_of(s.keys, spec.points, s.tangents, s.fold, spec.arm.radius, spec.arm.claw)
    pth.key_parameters_ok(keys)
    return pth.SplinePath(keys, control, s.control_points)


def spline_scene(spec, samples: int, control: np.ndarray, edge_samples: bool = True) -> Scene:
    """``edge_samples``: the fold window's exact edges (:attr:`Scene.edges`) added to the samples (the check and
    re-check); the NLP's masks need the uniform samples its symbolic path has."""
    path = spline_path(spec, np.asarray(control, float))
    arm = arm_of(spec)
    arms, stretches = [], path.stretches(samples)
    for st in stretches:
        a = evaluate(st, arm)
        _unreachable(spec, st.name, a)
        arms.append(a)
    keys = path.keys
    fold_u = keys.u[keys.index(keys.fold)]
    fold_point = (sp.basis(path.n, fold_u) @ path.control)[0]
    m = (float(fold_point[0]), float(fold_point[1]))
    t = (sp.basis(path.n, fold_u, 1) @ path.control)[0]
    fold = _fold_of(keys.fold, m, [math.degrees(math.atan2(t[1], t[0]))], spec.arm.radius, spec.arm.claw)
    before = evaluate(path.near_fold(-1, pth.FOLD_OFFSET), arm)
    after = evaluate(path.near_fold(+1, pth.FOLD_OFFSET), arm)
    joints = [Joint(keys.fold, _extrapolated(before), _extrapolated(after))]
    fold_theta = fold_arm_angles(m, spec.arm.radius, spec.arm.claw)
    window = (fold_direction(m),) * 2
    remake = lambda k, u: path.stretch_at(stretches[k].name, stretches[k].branch, u)      # noqa: E731
    edges = window_edges(spec, stretches, arms, window, remake)
    if edge_samples:
        arms = with_edge_samples(spec, stretches, arms, edges, remake)
    return Scene(spec, arms, joints, fold, spline=path, closing=path.closing(samples * 2), fold_theta=fold_theta,
                 edges=edges, window_centre=window)


def symbolic_edge_arm(spec, control: ca.SX, stretch, u: ca.SX) -> Arm:
    """The arm at one symbolic parameter ``u`` of a (numeric) stretch of the spline path: the knot spans the
    stretch covers give its basis (:func:`synthesis.kinds.guide_way.spline.basis_at`)."""
    n = spec.spline.control_points
    lo, hi = (min(int(math.floor(v * n)), n - 1) for v in (stretch.u[0], stretch.u[-1]))
    m = [(sp.basis_at(n, u, order, range(lo, hi + 1)) @ control).T for order in range(3)]
    return evaluate(Stretch(stretch.name, stretch.branch, np.zeros(1), *m), arm_of(spec))


def symbolic_arms(spec, control: ca.SX, samples: int) -> list[Arm]:
    path = spline_path(spec, control)
    return [evaluate(st, arm_of(spec)) for st in path.stretches(samples)]
