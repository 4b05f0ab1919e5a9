"""``agrisynth check`` for kind clamp_cam: evaluate the given cam against every rule and describe it.

The result carries what a workshop and a reviewer need: the rule table, the extreme values of
the pressure angle, curvature and follower acceleration (refined between samples with scipy), the
follower motion over a turn, and the pitch curve and working profile in the cam frame.
"""

from __future__ import annotations

from typing import cast

import numpy as np
from scipy.optimize import minimize_scalar

from synthesis.kinds.clamp_cam.motion import SEGMENT_NAMES
from synthesis.kinds.clamp_cam.scene import (CamScene, evaluate, law_warning, stroke_unit, to_report_units,
                                       window_degrees)
from synthesis.kinds.clamp_cam.kinematics import cam_follower as cf
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
        "crank_speed_rpm": spec.operation.crank_speed,
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


def follower_motion(scene: CamScene) -> tuple[dict, dict]:
    """(trajectory, follower): roller centre in the ground frame and s, v, a, j, pressure angle over a turn."""
    spec, w = scene.spec, scene.omega
    starts = scene.motion.timing.starts()
    crank = np.unique(np.concatenate([np.arange(0.0, 360.0 + 1e-9, MOTION_STEP_DEG),
                                      [float(v) % 360.0 for v in starts.values()]]))
    smp = scene.motion.at(crank)
    c = cf.roller_centre(scene.follower, smp.s, smp.ds, smp.dds)
    t = crank / 360.0 * 60.0 / spec.operation.crank_speed
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


def describe(scene: CamScene) -> tuple[dict, dict]:
    """(the kind-specific part of result.json, the trajectory)."""
    trajectory, follower = follower_motion(scene)
    warning = law_warning(scene)
    return {"source": scene.spec.source, "cam": cam_facts(scene), "follower": follower, "profile": profile(scene),
            **({"warnings": [warning]} if warning else {})}, trajectory


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
    return [f"pressure angle max: {angles}" if angles else "pressure angle: -",
            f"smallest working radius {figure_text(cam.get('min_working_radius_mm'), 'mm')} (roller "
            f"{figure_text(cam.get('roller_radius_mm'), 'mm')}){', undercut' if cam.get('undercut') else ''}; "
            f"{cam.get('law', '')} law, stroke {figure_text(cam.get('stroke'), cam.get('stroke_unit', ''))}"]
