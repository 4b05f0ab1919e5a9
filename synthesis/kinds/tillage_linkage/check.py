"""``agrisynth check`` for kind tillage_linkage: the given linkage over a crank turn.

Rules (one function, :func:`rules_of`, on floats or CasADi symbols): the tool tip's working depth and
lift (exact extremes), its rearward motion relative to the soil while in it (sampled over the in-soil
phase), the bar's angle to the roller slot and its engagement in the rollers (closed forms), and with a
``[dynamics]`` table's limits the peak input torque, shaking force and moment over a turn (dynamics.py).  On floats
the extremes and the soil entry/exit are root-found on the AD derivatives of eq 7.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, cast

import numpy as np
from scipy.optimize import brentq

from synthesis.constraints import Rule
from synthesis.kinds.tillage_linkage.rules import (bar_engagement_rule, bar_slot_angle_rule, lift_height_rule, rearward_in_soil_rule,
                                 working_depth_rule)
from synthesis.core.verdict import FINE
from synthesis.kinds.tillage_linkage.kinematics import (acceleration, bar_angle, direction, joints, path_function, speed)
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.tillage_linkage.spec import TillageSpec

if TYPE_CHECKING:
    from synthesis.kinds.tillage_linkage.dynamics import TillageDynamics

TWO_PI = 2.0 * math.pi
DEG = math.pi / 180.0
#: crank angles of the figures' curves and of the result's trajectory (one turn)
CURVE_SAMPLES = 361


def rules_of(spec: TillageSpec, a, b, c, depth, lift, vx_soil, missing: str | None = None,
             dynamics: list[Rule] | None = None) -> list[Rule]:
    """Every rule of the spec on a trace of floats or symbols: the lengths, the depth and lift of the tool
    tip's extremes (mm), and its ground-frame speed along the travel (m/s) at the sampled in-soil crank
    angles; then the ``[dynamics.limits]`` rules (:func:`dynamics_rules_of`) when given.  Used by check, the NLP
    and the re-check."""
    req = spec.requirements
    return [working_depth_rule(depth, req.depth),
            lift_height_rule(lift, req.lift),
            rearward_in_soil_rule(vx_soil, req.min_rearward_speed, missing),
            bar_slot_angle_rule(a, b, req.max_slot_angle),
            bar_engagement_rule(a, b, c, req.min_engagement),
            *(dynamics or [])]


def linkage_dynamics(spec: TillageSpec, a, b, c, theta_rad, height_c, rate=None, forward=None) -> TillageDynamics:
    """The inverse dynamics' inputs of a design (floats or symbols) at the flywheel speed ``rate`` (rad/s) and the
    forward speed ``forward`` (m/s), by default the spec's ``[operation]``.  Needs a ``[dynamics]`` table."""
    # imported here: a spec without [dynamics] imports nothing of the dynamics (nor its shared rules)
    from synthesis.kinds.tillage_linkage.dynamics import TillageDynamics

    assert spec.dynamics is not None
    return TillageDynamics.of(spec.dynamics, a, b, c, theta_rad, height_c,
                              crank_rate(spec) if rate is None else rate,
                              spec.operation.forward_speed if forward is None else forward)


def dynamics_rules_of(spec: TillageSpec, a, b, c, theta_rad, height_c, samples: int, rate=None, forward=None
                      ) -> list[Rule]:
    """The ``[dynamics.limits]`` rules on ``samples`` crank angles of a turn (floats or symbols); none without a
    ``[dynamics]`` table or without a limit, so such a spec's rules are what they were."""
    if spec.dynamics is None or not spec.dynamics.has_rules():
        return []
    from synthesis.kinds.tillage_linkage.dynamics import dynamics_rules, turn

    return dynamics_rules(linkage_dynamics(spec, a, b, c, theta_rad, height_c, rate, forward), spec.dynamics.limits,
                          turn(samples))


def params(design: dict[str, float]) -> list[float]:
    """[a, b, c, theta (rad)] of a design in spec units."""
    return [design["a"], design["b"], design["c"], design["theta"] * DEG]


def crank_rate(spec: TillageSpec) -> float:
    """omega_dot, rad/s (counter-clockwise)."""
    return spec.operation.crank_speed * TWO_PI / 60.0


def evaluate_path(p: list[float], omega: np.ndarray) -> dict[str, np.ndarray]:
    """x, y, x', y', x'', y'' of D at the crank angles ``omega`` (floats; AD derivatives)."""
    out = path_function().map(omega.size)(omega.reshape(1, -1), p)
    return {k: np.asarray(v, float).ravel() for k, v in zip(("x", "y", "dx", "dy", "ddx", "ddy"), out)}


def _y(p, w) -> float:
    return float(path_function()(w, p)[1])


def _dy(p, w) -> float:
    return float(path_function()(w, p)[3])


@dataclass
class Motion:
    """What the tool tip does over a turn (floats): exact extremes, the in-soil phases and the rule inputs."""

    omega_low: float                      # rad, lowest point
    y_low: float                          # mm (C at the origin)
    omega_top: float
    y_top: float
    ground: float                         # y of the ground, mm (= -height of C)
    windows: list[tuple[float, float]] = field(default_factory=list)   # in-soil phases (entry, exit), rad
    soil_omega: np.ndarray = field(default_factory=lambda: np.zeros(0))
    vx_soil: np.ndarray = field(default_factory=lambda: np.zeros(0))  # m/s, ground frame, at soil_omega

    @property
    def depth(self) -> float:
        return self.ground - self.y_low

    @property
    def lift(self) -> float:
        return self.y_top - self.ground

    @property
    def in_soil(self) -> bool:
        return bool(self.windows)


def _extreme(p, omega: np.ndarray, y: np.ndarray, dy: np.ndarray, lowest: bool) -> tuple[float, float]:
    """The lowest (highest) point: the grid's extreme refined by Brent's method on y' = 0 (AD)."""
    n = omega.size
    k = int(np.argmin(y) if lowest else np.argmax(y))
    lo, hi = omega[k] - TWO_PI / n, omega[k] + TWO_PI / n
    f = lambda w: _dy(p, w)       # noqa: E731
    if f(lo) * f(hi) < 0.0:
        w = brentq(f, lo, hi, xtol=1e-14)
    else:
        w = omega[k]
    return w % TWO_PI, _y(p, w)


def motion(spec: TillageSpec, design: dict[str, float], samples: int, soil_samples: int) -> Motion:
    """The tool tip over a turn on ``samples`` crank angles, extremes and soil entry/exit root-found,
    and its ground-frame speed on ``soil_samples`` + 1 angles over each in-soil phase."""
    p = params(design)
    omega = np.linspace(0.0, TWO_PI, samples, endpoint=False)
    path = evaluate_path(p, omega)
    w_low, y_low = _extreme(p, omega, path["y"], path["dy"], True)
    w_top, y_top = _extreme(p, omega, path["y"], path["dy"], False)
    ground = -design["height_c"]
    m = Motion(w_low, y_low, w_top, y_top, ground)
    g = path["y"] - ground
    if y_top <= ground:                     # always in the soil: one phase over the whole turn
        m.windows = [(0.0, TWO_PI)]
    elif y_low < ground:
        f = lambda w: _y(p, w) - ground     # noqa: E731
        entries: list[float] = []
        exits: list[float] = []
        for k in range(samples):
            g0, g1 = g[k], g[(k + 1) % samples]
            if (g0 > 0.0) != (g1 > 0.0):
                w0 = omega[k]
                if g0 * g1 < 0.0:
                    root = brentq(f, w0, w0 + TWO_PI / samples, xtol=1e-14)
                else:                       # a sample exactly on the ground
                    root = w0 if g0 == 0.0 else w0 + TWO_PI / samples
                (entries if g0 > 0.0 else exits).append(root % TWO_PI)
        for w_in in sorted(entries):
            w_out = min(exits, key=lambda w: (w - w_in) % TWO_PI)
            m.windows.append((w_in, w_in + (w_out - w_in) % TWO_PI))
    if m.windows:
        rate, v = crank_rate(spec), spec.operation.forward_speed
        ws = np.concatenate([np.linspace(w0, w1, soil_samples + 1) for w0, w1 in m.windows])
        m.soil_omega = ws
        m.vx_soil = rate * evaluate_path(p, ws)["dx"] / 1000.0 + v
    return m


def never_in_soil(m: Motion) -> str:
    return f"the tool tip never enters the soil (its lowest point stays {-m.depth:.4g} mm above the ground)"


def evaluate(spec: TillageSpec, design: dict[str, float], samples: int, soil_samples: int
             ) -> tuple[list[Rule], Motion]:
    m = motion(spec, design, samples, soil_samples)
    a, b, c = design["a"], design["b"], design["c"]
    missing = None if m.in_soil else never_in_soil(m)
    dynamics = dynamics_rules_of(spec, a, b, c, design["theta"] * DEG, design["height_c"], samples)
    return rules_of(spec, a, b, c, m.depth, m.lift, m.vx_soil if m.in_soil else None, missing, dynamics), m


def dynamics_of(spec: TillageSpec, design: dict[str, float]) -> dict:
    """``{"dynamics": facts.dynamics}`` over a turn at the table's ``samples`` crank angles, or nothing without a
    ``[dynamics]`` table."""
    if spec.dynamics is None:
        return {}
    from synthesis.kinds.tillage_linkage.dynamics import dynamics_facts

    a, b, c, th = params(design)
    dyn = linkage_dynamics(spec, a, b, c, th, design["height_c"])
    return {"dynamics": dynamics_facts(dyn, spec.dynamics.samples, spec.operation.crank_speed, spec.dynamics)}


def printed_relations(design: dict[str, float], samples: int = 720) -> dict:
    """The largest residual over a turn of every printed relation of eq 3-8 against the constructed
    geometry, and of eq 9-11 from hand-derived derivatives against AD (see printed.py)."""
    from synthesis.kinds.tillage_linkage import printed as pr

    a, b, c, th = params(design)
    worst: dict[str, float] = {}

    def keep(name: str, value: float) -> None:
        worst[name] = max(worst.get(name, 0.0), abs(float(value)))

    omega = np.linspace(0.0, TWO_PI, samples, endpoint=False)
    ad = evaluate_path([a, b, c, th], omega)
    skipped = []
    for k, w in enumerate(omega):
        j = joints(w, a, b, c, th)
        if math.hypot(*j["B"]) <= 1e-6 * b:
            # the crank pin B passes (nearly) through the rollers C, where the printed relations divide by |CB|
            # (a -> b: |CB| = b - a at omega = theta + 180 deg, lost to rounding in a^2 + b^2 - 2ab): not evaluated
            skipped.append(math.degrees(w))
            continue
        (ax, ay), (bx, by), (dx, dy) = j["A"], j["B"], j["D"]
        # phi by construction: the signed angle from CA to CB
        phi = math.atan2(ax * by - ay * bx, ax * bx + ay * by)
        keep("eq3 tan(phi)", pr.eq3_tan(w, a, b, th) - math.tan(phi))
        keep("eq3 Q/P expanded", pr.eq3_tan_expanded(w, a, b, th) - math.tan(phi))
        keep("eq3 P^2+Q^2 ('±' read '+')", (pr.eq3_denominator_squared(w, a, b, th) - (bx * bx + by * by)) / (b * b))
        keep("eq3 sin(phi)", pr.eq3_sin(w, a, b, th) - math.sin(phi))
        keep("eq4 cos(phi)", pr.eq4_cos(w, a, b, th) - math.cos(phi))
        keep("eq5 first line (products)", (pr.eq5_first_line(w, a, b, c, th) - dx) / c)
        keep("eq5", (pr.eq5(w, a, b, c, th) - dx) / c)
        keep("eq6 first line (products)", (pr.eq6_first_line(w, a, b, c, th) - dy) / c)
        keep("eq6", (pr.eq6(w, a, b, c, th) - dy) / c)
        x7, y7 = pr.eq7(w, a, b, c, th)
        keep("eq7", math.hypot(x7 - dx, y7 - dy) / c)
        keep("eq8 Vx - Uy = 0", pr.eq8(w, a, b, c, th) / (c * c))
        keep("eq8 expanded as printed ('+')", pr.eq8_expanded_as_printed(w, a, b, c, th) / (c * c))
        x1, y1, x2, y2 = pr.derivatives(w, a, b, c, th)
        keep("x', y' hand vs AD", max(abs(x1 - ad["dx"][k]), abs(y1 - ad["dy"][k])) / c)
        keep("x'', y'' hand vs AD", max(abs(x2 - ad["ddx"][k]), abs(y2 - ad["ddy"][k])) / c)
        keep("eq9 v", (pr.eq9(x1, y1) - float(speed(ad["dx"][k], ad["dy"][k]))) / c)
        keep("eq10 delta (atan2)", pr.eq10(x1, y1) - float(direction(ad["dx"][k], ad["dy"][k])))
        keep("eq11 acceleration", (pr.eq11(x2, y2) - float(acceleration(ad["ddx"][k], ad["ddy"][k]))) / c)
    return {"max_residual": worst, "scale": "angles and tangents as they are; lengths divided by c, "
                                             f"eq 8 by c^2; over a turn of {samples} crank angles",
            "holds_to_1e-9": {k: bool(v <= 1e-9) for k, v in worst.items()},
            **({"not_evaluated_at_crank_deg": skipped,
                "not_evaluated_why": "the crank pin B lies within 1e-6 b of the rollers C, where eq 3-8 divide by "
                                     "|CB|"} if skipped else {})}


def curves(spec: TillageSpec, design: dict[str, float], m: Motion) -> tuple[dict, dict]:
    """(machine-frame curve for the facts, ground-frame trajectory for result.json) over one turn."""
    p = params(design)
    rate, v = crank_rate(spec), spec.operation.forward_speed * 1000.0      # rad/s, mm/s
    omega = np.linspace(0.0, TWO_PI, CURVE_SAMPLES)
    path = evaluate_path(p, omega)
    t = omega / rate
    phi = np.degrees(np.asarray(bar_angle(omega, p[0], p[1], p[3]), float).ravel())
    machine = {"crank_deg": np.degrees(omega).tolist(), "x": path["x"].tolist(), "y": path["y"].tolist(),
               "speed_mm_per_rad": np.hypot(path["dx"], path["dy"]).tolist(),                   # eq 9
               "direction_deg": np.degrees(np.arctan2(path["dy"], path["dx"])).tolist(),          # eq 10
               "acceleration_mm_per_rad2": np.hypot(path["ddx"], path["ddy"]).tolist(),          # eq 11
               "bar_angle_deg": phi.tolist()}
    trajectory = {"frame": "ground", "t": t.tolist(), "crank_deg": np.degrees(omega).tolist(),
                  "x": (path["x"] + v * t).tolist(), "y": (path["y"] - m.ground).tolist(),
                  "vx": (rate * path["dx"] + v).tolist(), "vy": (rate * path["dy"]).tolist(),
                  "ax": (rate**2 * path["ddx"]).tolist(), "ay": (rate**2 * path["ddy"]).tolist(),
                  "note": "tool tip D: x along the travel from C's position at t = 0, y above the ground; "
                          "constant crank and forward speeds"}
    return machine, trajectory


def facts(spec: TillageSpec, design: dict[str, float], m: Motion) -> dict:
    a, b, c, th = params(design)
    machine, _ = curves(spec, design, m)
    rate = crank_rate(spec)
    return {
        "source": spec.source,
        "frame": "machine frame: roller pair C at the origin, x along the travel (+x forward), y up; flywheel "
                 "centre A at b (cos theta, sin theta); crank angle omega from +x, counter-clockwise",
        "operation": {"crank_speed_r_min": spec.operation.crank_speed, "forward_speed_m_s": spec.operation.forward_speed,
                      "advance_per_turn_mm": spec.operation.forward_speed * 1000.0 * TWO_PI / rate},
        "lowest_point": {"crank_deg": math.degrees(m.omega_low), "y_mm": m.y_low, "depth_mm": m.depth},
        "highest_point": {"crank_deg": math.degrees(m.omega_top), "y_mm": m.y_top, "lift_mm": m.lift},
        "height_c_mm": -m.ground,
        "soil_phases_crank_deg": [[math.degrees(w0), math.degrees(w1)] for w0, w1 in m.windows],
        "max_ground_speed_in_soil_m_s": float(m.vx_soil.max()) if m.in_soil else None,
        "bar_slot_angle_max_deg": math.degrees(math.asin(a / b)),
        "bar_engagement_mm": c - a - b,
        "cb_range_mm": [b - a, b + a],
        "cd_range_mm": [c - a - b, c - b + a],
        "peak_speed_m_s": float(np.max(machine["speed_mm_per_rad"])) * rate / 1000.0,
        "peak_acceleration_m_s2": float(np.max(machine["acceleration_mm_per_rad2"])) * rate**2 / 1000.0,
        "printed_relations": printed_relations(design),
        "curve": machine,
        # A, B, C, D at crank angles 45 deg apart (Fig. 18's positions 1-8)
        "positions": [{"crank_deg": k * 45.0, **{n: list(v) for n, v in joints(k * 45.0 * DEG, a, b, c, th).items()}}
                      for k in range(8)],
        **dynamics_of(spec, design),
    }


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(TillageSpec, loaded.model)          # load_spec validated it with this kind's model
    design = spec.design_values()
    s = spec.solver
    rules, m = evaluate(spec, design, FINE * s.samples, FINE * s.soil_samples)
    _, trajectory = curves(spec, design, m)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], trajectory=trajectory, extra=facts(spec, design, m))


def headline(result: Result) -> list[str]:
    """Working depth and lift, the ground speed in the soil (rearward is negative) and the bar's slot angle, and with
    a [dynamics] table the peak input torque, mean power and peak shaking force, from result.json facts."""
    facts = result.extra or {}
    low, high = facts.get("lowest_point") or {}, facts.get("highest_point") or {}
    if not low:
        return []
    dyn = (facts.get("dynamics") or {}).get("summary") or {}
    drive = []
    if dyn:
        drive = [f"peak input torque {figure_text((dyn.get('input_torque_Nm') or {}).get('peak'), 'N m')}, mean power "
                 f"{figure_text(dyn.get('mean_power_W'), 'W')}, peak shaking force "
                 f"{figure_text((dyn.get('shaking_force_N') or {}).get('peak'), 'N')}"]
    return [f"working depth {figure_text(low.get('depth_mm'), 'mm', 4)}, lift "
            f"{figure_text(high.get('lift_mm'), 'mm', 4)}",
            f"ground speed in the soil at most {figure_text(facts.get('max_ground_speed_in_soil_m_s'), 'm/s')}, bar slot "
            f"angle max {figure_text(facts.get('bar_slot_angle_max_deg'), 'deg')}, peak speed "
            f"{figure_text(facts.get('peak_speed_m_s'), 'm/s')}", *drive]
