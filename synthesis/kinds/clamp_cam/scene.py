"""A clamp_cam spec made concrete: follower, motion over a turn, timing windows, and its rules.

``CamScene`` holds numbers (a design); ``evaluate`` samples it and builds every rule on floats.
The NLP (synthesis.kinds.clamp_cam.nlp) builds the same rules on CasADi symbols from the same pieces.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule
from synthesis.kinds.clamp_cam.rules import (acceleration_rule, contact_force_rule, hertz_stress_rule, jump_speed_rule,
                                             pressure_angle_rule, timing_rule, undercut_rule)
from synthesis.kinds.clamp_cam.motion import SEGMENT_NAMES, CamMotion, Samples, Timing
from synthesis.errors import AssemblyError
from synthesis.kinds.clamp_cam.kinematics import cam_follower as cf
from synthesis.kinds.clamp_cam.kinematics import follower_dynamics as fd
from synthesis.kinds.clamp_cam.kinematics.motion_laws import law as closed_form_law
from synthesis.kinds.clamp_cam.spec import ClampCamSpec
from synthesis.spec.common import bounds_of, value_of

if TYPE_CHECKING:
    from synthesis.kinds.clamp_cam.spring_shaped_law import SpringShaping

TWO_PI = 2.0 * math.pi


def omega_of(spec: ClampCamSpec) -> float:
    """Cam speed, rad/s."""
    return spec.operation.speed * TWO_PI / 60.0


def stroke_of(spec: ClampCamSpec) -> float:
    """Stroke in model units: mm (translating) or rad (oscillating)."""
    h = spec.motion.stroke
    return h if spec.follower.type == "translating" else math.radians(h)


def stroke_unit(spec: ClampCamSpec) -> str:
    return "mm" if spec.follower.type == "translating" else "deg"


def to_report_units(spec: ClampCamSpec, x):
    """Model displacement units (mm or rad) -> report units (mm or deg)."""
    return x if spec.follower.type == "translating" else np.degrees(x)


def fit_law(spec: ClampCamSpec):
    """The optimised B-spline law of the spec's segments (imports cvxpy), or None for a closed-form law."""
    if spec.motion.law != "optimised":
        return None
    seg = spec.design_values()
    cap = spec.rules.max_acceleration
    if cap is not None and spec.follower.type == "oscillating":
        cap = math.radians(cap)
    b = spec.bspline
    if b.minimise == "spring_force":
        return _spring_shaped_law(stroke_of(spec), seg["rise"], seg["return"], spring_shaping(spec), b.spans,
                                  b.degree, b.samples_per_span, None if cap is None else cap - _margin(
                                      spec, acceleration_rule(np.zeros(1), cap, "")))
    return _fitted_law(stroke_of(spec), seg["rise"], seg["return"], omega_of(spec), b.minimise, b.spans, b.degree,
                       b.samples_per_span, cap)


@lru_cache(maxsize=8)
def _fitted_law(stroke: float, rise_deg: float, return_deg: float, omega: float, minimise: str, spans: int,
                degree: int, samples_per_span: int, cap: float | None):
    """One convex fit per set of inputs and process: a check or a solve, its diagnosis and its baseline
    rule table all use the same law, fitted once (the law is immutable)."""
    from synthesis.kinds.clamp_cam.bspline_law import fit_optimised_law

    return fit_optimised_law(stroke, {"rise": rise_deg, "return": return_deg}, omega, minimise, spans, degree,
                             samples_per_span, cap)


def _margin(spec: ClampCamSpec, rule: Rule) -> float:
    """How much tighter than its limit the NLP holds a sampled rule: the backoff x the rule's scale."""
    return spec.solver.backoff * rule.scale


def spring_shaping(spec: ClampCamSpec) -> SpringShaping:
    """What the spring-shaped law's fit reads of a spec (translating follower, given cam, [dynamics]: validated),
    every limit tightened by the margin the NLP holds it with, so the NLP finds the fitted law within its rows.
    The stiffness is its value, or a free stiffness's lower bound (why: spring_shaped_law's docstring)."""
    from synthesis.kinds.clamp_cam.spring_shaped_law import SpringShaping

    d = spec.dynamics
    assert d is not None and d.mass is not None and d.spring_preload is not None and d.spring_stiffness is not None, \
        "validation asks for a translating follower's [dynamics]"
    lim, rules = d.limits, spec.rules
    jump = None
    if lim.min_jump_speed is not None:
        jump = (lim.min_jump_speed + _margin(spec, jump_speed_rule(np.zeros(1), lim.min_jump_speed))) * TWO_PI / 60.0
    contact = None
    if lim.min_contact_force is not None:
        contact = lim.min_contact_force + _margin(spec, contact_force_rule(np.zeros(1), lim.min_contact_force))
    pressure = tuple(limit - _margin(spec, pressure_angle_rule(segment, np.zeros(1), limit))
                     for segment, limit in (("rise", rules.pressure_angle_rise),
                                            ("return", rules.pressure_angle_return)))
    lo, hi = bounds_of(d.spring_preload)
    return SpringShaping(mass=d.mass, gravity_load=d.mass * d.gravity[0], stiffness=bounds_of(d.spring_stiffness)[0],
                         preload_bounds=(lo, hi), jump_speed=jump, operating_speed=omega_of(spec),
                         min_contact_force=contact, base_radius=value_of(spec.cam.base_radius),
                         offset=0.0 if spec.follower.offset is None else value_of(spec.follower.offset),
                         pressure_angle_deg=(pressure[0], pressure[1]), nlp_samples=spec.solver.samples_per_segment)


@lru_cache(maxsize=8)
def _spring_shaped_law(stroke: float, rise_deg: float, return_deg: float, shaping: SpringShaping, spans: int, degree: int,
                       samples_per_span: int, cap: float | None):
    """One spring-shaped fit per set of inputs and process, as :func:`_fitted_law`."""
    from synthesis.kinds.clamp_cam.spring_shaped_law import fit_spring_shaped_law

    return fit_spring_shaped_law(stroke, {"rise": rise_deg, "return": return_deg}, shaping, spans, degree,
                                 samples_per_span, cap)


def follower_of(spec: ClampCamSpec, v: dict[str, Any]) -> cf.Follower:
    """The follower of design values ``v`` (floats or CasADi symbols), model units."""
    if spec.follower.type == "translating":
        return cf.Translating(v["base_radius"], v["offset"])
    return cf.Oscillating(v["base_radius"], v["pivot_distance"], v["arm_length"], spec.follower.side)


def window_degrees(spec: ClampCamSpec, crank_speed=None) -> dict[str, list[tuple]]:
    """Timing windows in crank degrees (a clock in seconds is converted at the crank speed: the spec's, or
    ``crank_speed``, a CasADi symbol of the tolerance analysis's build)."""
    n = spec.operation.speed if crank_speed is None else crank_speed
    factor = 1.0 if spec.timing.clock == "deg" else 360.0 * n / 60.0
    return {kind: [(lo * factor, hi * factor) for lo, hi in getattr(spec.timing, kind)]
            for kind in ("hold_near", "hold_far")}


def unwrap_window(window: tuple[float, float], dwell: tuple[float, float]) -> tuple[float, float]:
    """Shift the window by whole turns so that its middle is nearest the dwell's middle."""
    mid_w, mid_d = 0.5 * (window[0] + window[1]), 0.5 * (dwell[0] + dwell[1])
    k = round((mid_d - mid_w) / 360.0)
    return window[0] + 360.0 * k, window[1] + 360.0 * k


def timing_rules(spec: ClampCamSpec, timing: Timing, reference: Timing | None = None,
                 crank_speed=None) -> list[Rule]:
    """One rule per window: the near (far) dwell must cover each hold_near (hold_far) window.

    ``reference`` (numbers) decides the unwrapping, so that symbolic timings unwrap like their start;
    ``crank_speed`` (a CasADi symbol, the tolerance analysis's) converts windows timed in seconds, unwrapped by
    the whole turns their nominal values take (a turn count has no derivative).
    """
    ref = reference or timing
    nominal = window_degrees(spec)
    windows = nominal if crank_speed is None else window_degrees(spec, crank_speed)
    rules = []
    for kind, dwell in (("hold_near", "near_dwell"), ("hold_far", "far_dwell")):
        lo, hi = timing.span(dwell)
        ref_start, ref_end = ref.span(dwell)
        ref_span = (float(ref_start), float(ref_end))
        for i, (w, w0) in enumerate(zip(windows[kind], nominal[kind])):
            if crank_speed is None:
                rules.append(timing_rule(kind, i, unwrap_window(w, ref_span), lo, hi))
                continue
            shown = unwrap_window(w0, ref_span)
            turns = shown[0] - w0[0]
            rules.append(timing_rule(kind, i, (w[0] + turns, w[1] + turns), lo, hi, shown=shown))
    return rules


@dataclass(frozen=True)
class CamScene:
    """One design of a spec: numbers only."""

    spec: ClampCamSpec
    design: dict[str, float]
    follower: cf.Follower
    motion: CamMotion
    optimised: Any = None           # OptimisedLaw when motion.law = "optimised"

    @classmethod
    def from_spec(cls, spec: ClampCamSpec, design: dict[str, float] | None = None, optimised=None) -> "CamScene":
        """AssemblyError where the design lies outside the cam's domain (:func:`outside_domain`)."""
        values = dict(spec.design_values())
        if design:
            values.update({k: float(v) for k, v in design.items() if k in values})
        why = outside_domain(spec, values)
        if why is not None:
            raise AssemblyError(f"the design lies outside the cam's domain: {why}")
        if spec.motion.law == "optimised":
            optimised = optimised or fit_law(spec)
            rise_law, return_law = optimised.rise, optimised.return_
        else:
            rise_law = return_law = closed_form_law(spec.motion.law)
        motion = CamMotion(stroke_of(spec), Timing.from_design(values), rise_law, return_law)
        return cls(spec, values, follower_of(spec, values), motion, optimised)

    @property
    def roller_radius(self) -> float:
        return self.design["roller_radius"]

    @property
    def omega(self) -> float:
        return omega_of(self.spec)


def outside_domain(spec: ClampCamSpec, v: dict[str, float]) -> str | None:
    """Why design values ``v`` (numbers) lie where the cam's geometry is not defined, else None: a radius not
    positive, the roller not inside the base circle, the follower line missing it (|offset| >= base radius: no
    sqrt(r0^2 - e^2)), the arm not reaching it, a rise or return not positive.  The spec's validators hold these
    (with margins) for the given design; a tolerance box's samples or a studio drag may step past them, where the
    formulas would read |r0| or NaN as a design."""
    r0, rr = v["base_radius"], v["roller_radius"]
    if not r0 > 0:
        return f"base_radius {r0:g} mm is not > 0"
    if not rr > 0:
        return f"roller_radius {rr:g} mm is not > 0"
    if not rr < r0:
        return f"roller_radius {rr:g} mm is not below base_radius {r0:g} mm"
    if spec.follower.type == "translating":
        e = v.get("offset", 0.0)
        if not abs(e) < r0:
            return f"|offset| {abs(e):g} mm is not below base_radius {r0:g} mm: the follower line misses the base circle"
    else:
        a, l = v["pivot_distance"], v["arm_length"]
        if not abs(a - l) < r0 < a + l:
            return (f"the arm cannot reach the base circle: |pivot_distance - arm_length| = {abs(a - l):g}, "
                    f"base_radius {r0:g}, pivot_distance + arm_length = {a + l:g} mm")
    for name in ("rise", "return"):
        if not v[name] > 0:
            return f"{name} {v[name]:g} deg is not > 0"
    return None


@dataclass(frozen=True)
class Geometry:
    """Samples of the follower motion and the cam geometry at the same cam angles."""

    samples: Samples
    centre: cf.RollerCentre
    alpha_deg: np.ndarray
    kappa: np.ndarray

    def where(self, segment: str) -> np.ndarray:
        return self.samples.segment == SEGMENT_NAMES.index(segment)


def geometry(scene: CamScene, samples: Samples) -> Geometry:
    c = cf.roller_centre(scene.follower, samples.s, samples.ds, samples.dds)
    return Geometry(samples, c, np.degrees(cf.pressure_angle(c)), cf.pitch_curvature(c))


def segment_grid(scene: CamScene, per_motion_segment: int, per_dwell: int = 8) -> Samples:
    """Samples over the turn: ``per_motion_segment`` on the rise and on the return, fewer on the dwells."""
    parts = [scene.motion.segment(name, np.linspace(0.0, 1.0, per_motion_segment if name in ("rise", "return")
                                                    else per_dwell))
             for name in SEGMENT_NAMES]
    return Samples(*(np.concatenate([getattr(p, k) for p in parts])
                     for k in ("phi_deg", "s", "ds", "dds", "ddds", "segment")))


def law_warning(scene: CamScene) -> str | None:
    """The caveat of an optimised law that cvxpy solved only inaccurately, else None."""
    return None if scene.optimised is None else scene.optimised.warning


def cam_rules(scene: CamScene, g: Geometry) -> list[Rule]:
    """Every rule of the spec, evaluated on the samples of ``g``; the rules that follow the motion law carry
    its caveat as a note when the optimised law was solved inaccurately."""
    rules = _cam_rules(scene, g)
    note = law_warning(scene)
    if note is None:
        return rules
    return [r if r.name.startswith("timing_") else dataclasses.replace(r, note=note) for r in rules]


def rules_of(spec: ClampCamSpec, alpha_driven, alpha_return, kappa, roller_radius, timing: Timing, acceleration,
             reference: Timing | None = None, crank_speed=None, dynamics: DynamicsTrace | None = None) -> list[Rule]:
    """Every rule of the spec on a trace of floats or CasADi symbols: the pressure angles (deg) while the
    cam drives (rise and dwells) and on the return, the pitch curvature, the roller radius, the timing,
    and the follower acceleration while it moves (report units per s^2).  Used by check, the NLP and
    the fine-grid re-check; ``reference`` (numbers) unwraps symbolic timing windows like their start;
    ``crank_speed`` (a symbol: the tolerance analysis's, an operating envelope's) converts windows timed in
    seconds; ``dynamics`` (with a [dynamics] table) the follower's loads over the turn, for its limits."""
    lim = spec.rules
    rules = [pressure_angle_rule("rise", alpha_driven, lim.pressure_angle_rise),
             pressure_angle_rule("return", alpha_return, lim.pressure_angle_return),
             undercut_rule(kappa, roller_radius, lim.min_working_radius)]
    if lim.groove:
        rules.append(undercut_rule(kappa, roller_radius, lim.min_working_radius, flank="outer"))
    rules += timing_rules(spec, timing, reference, crank_speed)
    if lim.max_acceleration is not None:
        rules.append(acceleration_rule(acceleration, lim.max_acceleration, f"{stroke_unit(spec)}/s^2"))
    if dynamics is not None:
        rules += dynamics_rules(spec, dynamics)
    return rules


def _cam_rules(scene: CamScene, g: Geometry) -> list[Rule]:
    spec = scene.spec
    driven = g.where("rise") | g.where("far_dwell") | g.where("near_dwell")
    moving = g.where("rise") | g.where("return")
    acc = to_report_units(spec, g.samples.dds[moving]) * scene.omega**2
    return rules_of(spec, g.alpha_deg[driven], g.alpha_deg[g.where("return")], g.kappa, scene.roller_radius,
                    scene.motion.timing, acc, dynamics=dynamics_trace(scene, g))


# ------------------------------------------------------------------ follower dynamics ([dynamics])

def body_of(spec: ClampCamSpec, v: dict[str, Any]) -> fd.FollowerBody | None:
    """The follower's mass, spring and gravity of design values ``v`` (floats or CasADi symbols; the spring's
    preload and stiffness are design variables), or None without a [dynamics] table."""
    d = spec.dynamics
    if d is None:
        return None
    if spec.follower.type == "translating":
        return fd.FollowerBody(d.mass, v["spring_preload"], v["spring_stiffness"], d.gravity, d.mass, 1.0)
    return fd.FollowerBody(d.inertia, v["spring_preload_torque"], v["spring_torsional_stiffness"], d.gravity,
                           d.arm_mass, d.com_distance * fd.MM)


def effective_modulus(spec: ClampCamSpec) -> float:
    """E* of roller and cam, MPa."""
    d = spec.dynamics
    assert d is not None, "only with a [dynamics] table"
    return fd.effective_modulus(d.roller_modulus, d.roller_poisson, d.cam_modulus, d.cam_poisson)


def generalised_unit(spec: ClampCamSpec) -> str:
    """The unit of the follower's generalised loads (spring, inertia, gravity): N (translating) or N m."""
    return "N" if spec.follower.type == "translating" else "N m"


@dataclass(frozen=True)
class DynamicsTrace:
    """The follower's loads at the samples of a turn (floats or CasADi symbols), the cam speed they are read at
    (rad/s, a number or the operating symbol), the pitch curvature and roller radius there (Hertz), and which samples
    the spring must decelerate (``pulled``: q'' < 0, numbers: the motion law's sign, whatever the design)."""

    loads: fd.ContactLoads
    omega: Any
    kappa: Any
    roller_radius: Any
    pulled: np.ndarray
    #: the largest |dF/d omega^2| (N s^2) at the given design, a number: scales the jump speed's NLP rows
    reference_per_omega2: float = 1.0


def dynamics_trace(scene: CamScene, g: Geometry) -> DynamicsTrace | None:
    """The trace of a design's samples (numbers), None without a [dynamics] table."""
    body = body_of(scene.spec, scene.design)
    if body is None:
        return None
    loads = fd.contact_loads(scene.follower, body, g.centre, g.samples.s, g.samples.dds)
    return DynamicsTrace(loads, scene.omega, g.kappa, scene.roller_radius, decelerating(g.samples.dds))


def decelerating(dds) -> np.ndarray:
    """Where the spring must decelerate the follower, q'' < 0 (numbers): beyond round-off of the law's zero
    crossings (a cycloid's 2 pi sin(2 pi u) at u = 1/2 is 1e-16, not 0), whose ratio could never be the least."""
    values = np.asarray(dds, dtype=float)
    return values < -1e-9 * float(np.max(np.abs(values), initial=0.0))


def _select(values, mask: np.ndarray):
    """The entries of a vector (numbers or a CasADi column) where ``mask`` holds."""
    index = [int(i) for i in np.flatnonzero(mask)]
    if isinstance(values, (ca.SX, ca.MX, ca.DM)):
        return values[index]
    return np.asarray(values)[index]


def sample_jump_speeds(trace: DynamicsTrace):
    """At each sample the spring must decelerate, the cam speed (r/min) at which the contact force reaches zero,
    sqrt(held / -(I q'')); on numbers 0 where the spring does not hold the follower at rest, [inf] when no sample
    decelerates (the follower never leaves).  Their smallest is the jump speed (follower_dynamics docstring)."""
    loads = trace.loads
    held = loads.spring - loads.gravity
    to_rpm = 60.0 / TWO_PI
    if fd.is_symbolic(held, loads.inertia_per_omega2):
        pulled = _select(loads.inertia_per_omega2, trace.pulled)
        return to_rpm * ca.sqrt(ca.fmax(_select(held + 0.0 * loads.inertia_per_omega2, trace.pulled), 0.0) / -pulled)
    held_n = np.asarray(held + 0.0 * np.asarray(loads.inertia_per_omega2), dtype=float)
    b = np.asarray(loads.inertia_per_omega2, dtype=float)
    out = [to_rpm * math.sqrt(max(h, 0.0) / -bb) for h, bb, p in zip(held_n, b, trace.pulled) if p]
    if np.any(held_n <= 0.0):
        out.append(0.0)
    return np.array(out or [math.inf])


def dynamics_rules(spec: ClampCamSpec, trace: DynamicsTrace) -> list[Rule]:
    """The [dynamics.limits] rules on a trace (numbers or CasADi symbols): contact force, Hertz stress, jump speed,
    in that order, each only where its limit is given."""
    d = spec.dynamics
    assert d is not None, "only with a [dynamics] table"
    lim, rules = d.limits, []
    force = trace.loads.force(trace.omega)
    if lim.min_contact_force is not None:
        rules.append(contact_force_rule(force, lim.min_contact_force))
    if lim.max_hertz_stress is not None:
        assert d.roller_width is not None, "validation asks for roller_width with a stress limit"
        e_star, width = effective_modulus(spec), d.roller_width
        radius = fd.relative_radius(trace.kappa, trace.roller_radius)
        stress = fd.hertz_stress(force, width, radius, e_star)
        if fd.is_symbolic(force, radius):
            limit = lim.max_hertz_stress
            reference = fd.hertz_force(limit, width, value_of(spec.cam.roller_radius), e_star)
            rules.append(hertz_stress_rule(stress, limit, force, fd.hertz_force(limit, width, radius, e_star),
                                           reference))
        else:
            rules.append(hertz_stress_rule(stress, lim.max_hertz_stress))
    if lim.min_jump_speed is not None:
        speeds = sample_jump_speeds(trace)
        omega_min = lim.min_jump_speed * TWO_PI / 60.0
        at_minimum = trace.loads.force(omega_min)
        if fd.is_symbolic(at_minimum):
            rpm_per_newton = (60.0 / TWO_PI) / (2.0 * trace.reference_per_omega2 * omega_min)
            oscillating_with_gravity = spec.follower.type == "oscillating" and any(g != 0.0 for g in d.gravity)
            at_rest = trace.loads.static if oscillating_with_gravity else None
            rules.append(jump_speed_rule(speeds, lim.min_jump_speed, at_minimum, rpm_per_newton, at_rest))
        else:
            rules.append(jump_speed_rule(speeds, lim.min_jump_speed))
    return rules


def evaluate(scene: CamScene, per_motion_segment: int) -> tuple[list[Rule], Geometry]:
    g = geometry(scene, segment_grid(scene, per_motion_segment))
    return cam_rules(scene, g), g
