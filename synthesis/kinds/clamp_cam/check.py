"""``agrisynth check`` for kind clamp_cam: evaluate the given cam against every rule and describe it.

The result carries what a workshop and a reviewer need: the rule table, the extreme values of
the pressure angle, curvature and follower acceleration (refined between samples with scipy), the
follower motion over a turn, and the pitch curve and working profile in the cam frame.
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np
from scipy.optimize import minimize_scalar

from synthesis.kinds.clamp_cam.motion import SEGMENT_NAMES
from synthesis.kinds.clamp_cam.scene import (TWO_PI, CamScene, body_of, effective_modulus, evaluate, generalised_unit,
                                             law_warning, stroke_unit, to_report_units, window_degrees)
from synthesis.kinds.clamp_cam.kinematics import cam_follower as cf
from synthesis.kinds.clamp_cam.kinematics import follower_dynamics as fd
from synthesis.kinds.clamp_cam.spec import ClampCamSpec
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec

#: the check (and solve's re-check) samples each motion segment this many times finer than the NLP
FINE = 10
PROFILE_STEP_DEG = 0.1          # working profile export resolution
MOTION_STEP_DEG = 0.25          # follower motion samples in result.json


def _segment_value(scene: CamScene, name: str, quantity: str):
    """f(u) on one motion segment, vectorised: |pressure angle| (deg), convex or concave pitch curvature (1/mm)."""
    def f(u):
        smp = scene.motion.segment(name, np.atleast_1d(np.asarray(u, dtype=float)))
        c = cf.roller_centre(scene.follower, smp.s, smp.ds, smp.dds)
        if quantity == "alpha":
            return np.degrees(np.abs(cf.pressure_angle(c)))
        k = cf.pitch_curvature(c)
        return k if quantity == "convex" else -k
    return f


def _refined_max(f, n: int = 2001) -> tuple[float, float]:
    """(u, max f) on [0, 1]: the best of n samples, polished by a bounded scalar search around it."""
    u = np.linspace(0.0, 1.0, n)
    values = f(u)
    i = int(np.argmax(values))
    lo, hi = u[max(i - 1, 0)], u[min(i + 1, n - 1)]
    res = minimize_scalar(lambda x: -float(f(x)[0]), bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
    if -res.fun > values[i]:
        return float(res.x), float(-res.fun)
    return float(u[i]), float(values[i])


def segment_facts(scene: CamScene, name: str) -> dict:
    """Extremes over one motion segment: pressure angle, pitch and working radius of curvature, kinematics."""
    spec, w, rr = scene.spec, scene.omega, scene.roller_radius
    lo, hi = scene.motion.timing.span(name)
    crank = lambda u: (lo + u * (hi - lo)) % 360.0  # noqa: E731
    u_a, alpha = _refined_max(_segment_value(scene, name, "alpha"))
    u_k, kappa = _refined_max(_segment_value(scene, name, "convex"))
    u_c, kappa_concave = _refined_max(_segment_value(scene, name, "concave"))
    u = np.linspace(0.0, 1.0, 20001)
    smp = scene.motion.segment(name, u)
    unit = stroke_unit(spec)
    law = scene.motion.rise_law if name == "rise" else scene.motion.return_law
    out = {
        "angle_deg": float(hi - lo),
        "max_pressure_angle_deg": alpha, "max_pressure_angle_at_crank_deg": crank(u_a),
        "min_pitch_radius_convex_mm": (1.0 / kappa) if kappa > 0 else None,
        "min_pitch_radius_convex_at_crank_deg": crank(u_k) if kappa > 0 else None,
        "min_working_radius_mm": (1.0 / kappa - rr) if kappa > 0 else None,
        "min_pitch_radius_concave_mm": (1.0 / kappa_concave) if kappa_concave > 0 else None,
        "peak_velocity": float(np.max(np.abs(to_report_units(spec, smp.ds)))) * w,
        "peak_acceleration": float(np.max(np.abs(to_report_units(spec, smp.dds)))) * w**2,
        "peak_jerk": float(np.max(np.abs(to_report_units(spec, smp.ddds)))) * w**3,
        "units": {"velocity": f"{unit}/s", "acceleration": f"{unit}/s^2", "jerk": f"{unit}/s^3"},
        "law": law.name, "law_coefficients": law.peaks,
    }
    return out


def cam_facts(scene: CamScene) -> dict:
    spec = scene.spec
    seg = {name: segment_facts(scene, name) for name in ("rise", "return")}
    rr = scene.roller_radius
    convex = [s["min_pitch_radius_convex_mm"] for s in seg.values() if s["min_pitch_radius_convex_mm"] is not None]
    dwell_radii, dwell_alpha = [], {}
    for name in ("far_dwell", "near_dwell"):          # dwell arcs: circles about the cam centre
        smp = scene.motion.segment(name, np.array([0.5]))
        c = cf.roller_centre(scene.follower, smp.s, smp.ds, smp.dds)
        dwell_radii.append(1.0 / float(cf.pitch_curvature(c)[0]))
        dwell_alpha[name] = float(np.degrees(cf.pressure_angle(c))[0])
    min_convex = min(convex + dwell_radii)
    facts = {
        "segments": seg,
        "dwell_pressure_angle_deg": dwell_alpha,
        "min_pitch_radius_convex_mm": min_convex,
        "min_working_radius_mm": min_convex - rr,
        "roller_radius_mm": rr,
        "undercut": bool(min_convex < rr),
        "crank_speed_rpm": spec.operation.speed,
        "follower_type": spec.follower.type,
        "stroke": spec.motion.stroke, "stroke_unit": stroke_unit(spec),
        "law": spec.motion.law,
        "segment_starts_crank_deg": {k: float(v) % 360.0 for k, v in scene.motion.timing.starts().items()
                                     if k != "end"},
        "timing_windows_deg": {k: [list(w) for w in v] for k, v in window_degrees(spec).items()},
    }
    if scene.optimised is not None:
        facts["optimised_law"] = scene.optimised.to_json()
    return facts


def _turn_grid(scene: CamScene) -> np.ndarray:
    """Crank angles of result.json's samples over a turn: every MOTION_STEP_DEG and each segment start."""
    starts = scene.motion.timing.starts()
    return np.unique(np.concatenate([np.arange(0.0, 360.0 + 1e-9, MOTION_STEP_DEG),
                                     [float(v) % 360.0 for v in starts.values()]]))


def follower_motion(scene: CamScene) -> tuple[dict, dict]:
    """(trajectory, follower): roller centre in the ground frame and s, v, a, j, pressure angle over a turn."""
    spec, w = scene.spec, scene.omega
    crank = _turn_grid(scene)
    smp = scene.motion.at(crank)
    c = cf.roller_centre(scene.follower, smp.s, smp.ds, smp.dds)
    t = crank / 360.0 * 60.0 / spec.operation.speed
    zero = np.zeros_like(crank)
    trajectory = {"frame": "machine", "point": "roller centre (cam centre at the origin, follower along +X)",
                  "t": t.tolist(), "crank_deg": crank.tolist(),
                  "x": (c.x + zero).tolist(), "y": (c.y + zero).tolist(),
                  "vx": (c.dx * w + zero).tolist(), "vy": (c.dy * w + zero).tolist(),
                  "ax": (c.ddx * w**2 + zero).tolist(), "ay": (c.ddy * w**2 + zero).tolist()}
    follower = {"crank_deg": crank.tolist(), "unit": stroke_unit(spec),
                "s": to_report_units(spec, smp.s).tolist(),
                "v": (to_report_units(spec, smp.ds) * w).tolist(),
                "a": (to_report_units(spec, smp.dds) * w**2).tolist(),
                "j": (to_report_units(spec, smp.ddds) * w**3).tolist(),
                "pressure_angle_deg": np.degrees(cf.pressure_angle(c)).tolist(),
                "segment": [SEGMENT_NAMES[k] for k in smp.segment]}
    return trajectory, follower


def profile(scene: CamScene) -> dict:
    """Pitch curve and working profile in the cam frame (mm), one point per 0.1 deg, not closed.

    Cam angle 0 is where the rise begins; the profile is mirrored for a clockwise cam.
    """
    phi_deg = np.arange(0.0, 360.0, PROFILE_STEP_DEG)
    start = float(scene.motion.timing.rise_start)
    smp = scene.motion.at(start + phi_deg)
    c = cf.roller_centre(scene.follower, smp.s, smp.ds, smp.dds)
    phi = np.radians(phi_deg)
    mirror = -1.0 if scene.spec.cam.rotation == "clockwise" else 1.0
    px, py = cf.pitch_curve(c, phi)
    wx, wy = cf.envelope(c, phi, scene.roller_radius, side=-1)
    spec, w = scene.spec, scene.omega
    # result.json keeps its spelling ("counter-clockwise") though the spec's is "counter_clockwise"
    out = {"cam_angle_deg": phi_deg.tolist(), "rotation": scene.spec.cam.rotation.replace("_", "-"),
           "crank_deg": np.round((start + phi_deg) % 360.0, 9).tolist(),
           "pitch": {"x": np.round(px, 7).tolist(), "y": np.round(mirror * py, 7).tolist()},
           "working": {"x": np.round(wx, 7).tolist(), "y": np.round(mirror * wy, 7).tolist()},
           # signed curvature of the pitch curve (1/mm, > 0 convex): radii of curvature of pitch and working
           # profile follow from it and the roller radius (the CSV export writes them)
           "pitch_curvature_1_mm": cf.pitch_curvature(c).tolist(),
           # the follower at each cam angle (stroke unit, per s, per s^2) and the pressure angle
           "follower": {"unit": stroke_unit(spec), "s": to_report_units(spec, smp.s).tolist(),
                        "v": (to_report_units(spec, smp.ds) * w).tolist(),
                        "a": (to_report_units(spec, smp.dds) * w**2).tolist(),
                        "pressure_angle_deg": np.degrees(cf.pressure_angle(c)).tolist()},
           "roller_radius": scene.roller_radius, "base_radius": scene.design["base_radius"]}
    if scene.spec.rules.groove:
        ox, oy = cf.envelope(c, phi, scene.roller_radius, side=+1)
        out["outer"] = {"x": np.round(ox, 7).tolist(), "y": np.round(mirror * oy, 7).tolist()}
    return out


def _loads(scene: CamScene, smp) -> tuple[fd.ContactLoads, np.ndarray]:
    """The follower's loads and the pitch curvature at samples ``smp`` of a design with a [dynamics] table."""
    body = body_of(scene.spec, scene.design)
    assert body is not None, "only with a [dynamics] table"
    c = cf.roller_centre(scene.follower, smp.s, smp.ds, smp.dds)
    return fd.contact_loads(scene.follower, body, c, smp.s, smp.dds), cf.pitch_curvature(c)


def _segment_dynamics(scene: CamScene, name: str, quantity: str):
    """f(u) on one segment, vectorised, for _refined_max: -contact force (N), Hertz stress (MPa), or -omega^2 at
    which the contact force vanishes where the spring decelerates the follower (-inf elsewhere)."""
    d = scene.spec.dynamics
    assert d is not None, "only with a [dynamics] table"

    def f(u):
        loads, kappa = _loads(scene, scene.motion.segment(name, np.atleast_1d(np.asarray(u, dtype=float))))
        if quantity == "force":
            return -np.asarray(loads.force(scene.omega), dtype=float)
        if quantity == "stress":
            assert d.roller_width is not None
            return fd.hertz_stress(loads.force(scene.omega), d.roller_width,
                                   fd.relative_radius(kappa, scene.roller_radius), effective_modulus(scene.spec))
        held = np.asarray(loads.spring - loads.gravity, dtype=float) + 0.0 * kappa
        b = np.asarray(loads.inertia_per_omega2, dtype=float) + 0.0 * kappa
        out = np.full(held.shape, -np.inf)
        pulled = b < 0.0
        out[pulled] = -np.maximum(held[pulled], 0.0) / -b[pulled]
        return out
    return f


def _negated(f):
    return lambda u: -f(u)


def _crank_of(scene: CamScene, name: str, u: float) -> float:
    lo, hi = scene.motion.timing.span(name)
    return float((lo + u * (hi - lo)) % 360.0)


def dynamics_facts(scene: CamScene) -> dict:
    """result.json facts.dynamics of a spec with a [dynamics] table: the follower's loads and the contact force,
    Hertz stress over the turn at the crank speed (the follower facts' crank angles), their extremes refined between
    samples, and the jump speed (follower_dynamics docstring)."""
    spec, w = scene.spec, scene.omega
    d = spec.dynamics
    assert d is not None, "only with a [dynamics] table"
    crank = _turn_grid(scene)
    smp = scene.motion.at(crank)
    loads, kappa = _loads(scene, smp)
    zero = np.zeros_like(crank)
    force = np.asarray(loads.force(w), dtype=float) + zero
    radius = fd.relative_radius(kappa, scene.roller_radius) + zero
    unit = generalised_unit(spec)
    key = "force_N" if unit == "N" else "torque_Nm"
    _, preload, stiffness = d.body_fields(spec.follower.type)
    # extremes: the sampled grid, then each moving segment refined (the dwells are constant)
    lowest = (float(np.min(force)), float(crank[int(np.argmin(force))]))
    highest = (float(np.max(force)), float(crank[int(np.argmax(force))]))
    for name in ("rise", "return"):
        less = _segment_dynamics(scene, name, "force")          # -force
        u, value = _refined_max(less)
        if -value < lowest[0]:
            lowest = (-value, _crank_of(scene, name, u))
        u, value = _refined_max(_negated(less))
        if value > highest[0]:
            highest = (value, _crank_of(scene, name, u))
    # jump speed: the spring must hold the follower at rest on the whole turn, then the smallest omega^2 ratio
    held = np.asarray(loads.spring - loads.gravity, dtype=float) + zero
    omega_jump, k = fd.jump_speed(held, np.asarray(loads.inertia_per_omega2, dtype=float) + zero)
    jump_at = None if k is None else float(crank[k])
    if omega_jump > 0.0:
        for name in ("rise", "return"):
            u, value = _refined_max(_segment_dynamics(scene, name, "jump"))
            if np.isfinite(value) and math.sqrt(-value) < omega_jump:
                omega_jump, jump_at = math.sqrt(-value), _crank_of(scene, name, u)
    to_rpm = 60.0 / TWO_PI
    out: dict = {
        "model": "spring-loaded roller follower at constant cam speed, friction and roller spin neglected "
                 "(synthesis/kinds/clamp_cam/kinematics/follower_dynamics.py)",
        "follower_type": spec.follower.type, "crank_speed_rpm": spec.operation.speed,
        "crank_deg": crank.tolist(),
        "contact_force_N": force.tolist(),
        f"spring_{key}": (np.asarray(loads.spring, dtype=float) + zero).tolist(),
        f"inertia_{key}": (np.asarray(loads.inertia(w), dtype=float) + zero).tolist(),
        f"gravity_{key}": (np.asarray(loads.gravity, dtype=float) + zero).tolist(),
        "cos_pressure_angle": (np.asarray(loads.cos_alpha, dtype=float) + zero).tolist(),
        "relative_radius_mm": radius.tolist(),
        "min_contact_force_N": lowest[0], "min_contact_force_at_crank_deg": lowest[1],
        "max_contact_force_N": highest[0], "max_contact_force_at_crank_deg": highest[1],
        "jump_speed_rpm": None if math.isinf(omega_jump) else omega_jump * to_rpm,
        "jump_at_crank_deg": jump_at,
        "jump_speed_ratio": None if math.isinf(omega_jump) else omega_jump * to_rpm / spec.operation.speed,
        "spring": {"preload": scene.design[preload], "stiffness": scene.design[stiffness],
                   "units": {"preload": unit, "stiffness": "N/mm" if unit == "N" else "N m/rad"}},
        **({"mass_kg": d.mass} if spec.follower.type == "translating" else {"inertia_kgm2": d.inertia}),
        "gravity_mps2": list(d.gravity),
        "conventions": "contact force along the common normal, > 0 the cam pushes the roller; spring, inertia (I q'' "
                       "omega^2) and gravity loads generalised along the follower's motion (N on a translating "
                       "follower, N m about an oscillating follower's pivot): contact x lever x cos(pressure angle) = "
                       "spring + inertia - gravity; jump_speed_rpm null: the follower never leaves the cam, 0: the "
                       "spring does not hold it at rest",
        "assumption": d.assumption,
    }
    if d.roller_width is not None:
        e_star = effective_modulus(spec)
        stress = fd.hertz_stress(force, d.roller_width, radius, e_star)
        k = int(np.argmax(stress))
        peak = (float(stress[k]), float(crank[k]))
        for name in ("rise", "return"):
            u, value = _refined_max(_segment_dynamics(scene, name, "stress"))
            if value > peak[0]:
                peak = (value, _crank_of(scene, name, u))
        out.update({"hertz_stress_MPa": stress.tolist(), "max_hertz_stress_MPa": peak[0],
                    "max_hertz_stress_at_crank_deg": peak[1], "roller_width_mm": d.roller_width,
                    "effective_modulus_MPa": e_star})
    return out


def describe(scene: CamScene) -> tuple[dict, dict]:
    """(the kind-specific part of result.json, the trajectory)."""
    trajectory, follower = follower_motion(scene)
    warning = law_warning(scene)
    dynamics = {"dynamics": dynamics_facts(scene)} if scene.spec.dynamics is not None else {}
    return {"source": scene.spec.source, "cam": cam_facts(scene), "follower": follower, "profile": profile(scene),
            **dynamics, **({"warnings": [warning]} if warning else {})}, trajectory


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(ClampCamSpec, loaded.model)        # load_spec validated it with this kind's model
    scene = CamScene.from_spec(spec)
    rules, _ = evaluate(scene, FINE * spec.solver.samples_per_segment)
    extra, trajectory = describe(scene)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=dict(scene.design), rules=[r.record().to_json() for r in rules],
                  trajectory=trajectory, extra=extra)


def headline(result: Result) -> list[str]:
    """The largest pressure angle of each moving segment, the smallest working radius against the roller, from
    result.json facts."""
    cam = (result.extra or {}).get("cam") or {}
    if not cam:
        return []
    segments = cam.get("segments") or {}
    angles = ", ".join(f"{name} {figure_text(s.get('max_pressure_angle_deg'), 'deg')}" for name, s in segments.items()
                       if isinstance(s, dict))
    lines = [f"pressure angle max: {angles}" if angles else "pressure angle: -",
             f"smallest working radius {figure_text(cam.get('min_working_radius_mm'), 'mm')} (roller "
             f"{figure_text(cam.get('roller_radius_mm'), 'mm')}){', undercut' if cam.get('undercut') else ''}; "
             f"{cam.get('law', '')} law, stroke {figure_text(cam.get('stroke'), cam.get('stroke_unit', ''))}"]
    dyn = (result.extra or {}).get("dynamics")
    if isinstance(dyn, dict) and "contact_force_N" in dyn:
        jump = dyn.get("jump_speed_rpm")
        lines.append(f"contact force min {figure_text(dyn.get('min_contact_force_N'), 'N')} at "
                     f"{figure_text(dyn.get('crank_speed_rpm'), 'r/min')}; jump speed "
                     f"{'never' if jump is None else figure_text(jump, 'r/min')}"
                     + (f"; Hertz stress max {figure_text(dyn.get('max_hertz_stress_MPa'), 'MPa')}"
                        if "max_hertz_stress_MPa" in dyn else ""))
    return lines
