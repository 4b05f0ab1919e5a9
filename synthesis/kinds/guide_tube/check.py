"""``agrisynth check`` for kind guide_tube: the given wall angles against every rule, with the facts
the report draws (phase breakdown, row-spacing sweep, mu / v_L sensitivity, closed form vs ODE)."""

from __future__ import annotations

import math
from typing import cast

import numpy as np

from synthesis.constraints import Rule, not_evaluated
from synthesis.kinds.guide_tube.rules import (free_fall_height_rule, landing_time_spread_rule, spacing_error_rule,
                                    wall_exit_speed_rule)
from synthesis.kinds.guide_tube.drop import DropPhases, Physics, SeedlingSticks, landing, slide
from synthesis.kinds.guide_tube.ode import simulate
from synthesis.kinds.guide_tube.scene import MM, GuideTubeScene
from synthesis.kinds.guide_tube.slope import landing_time_slope
from synthesis.kinds.guide_tube.spec import GuideTubeSpec
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec

#: the check grid is this many times finer than the solver's row-spacing samples (docs/ARCHITECTURE.md, "Verdicts")
FINE = 10
#: relative changes of mu and v_L in the sensitivity study
SENSITIVITY = np.round(np.linspace(0.8, 1.2, 9), 10).tolist()


def drops(scene: GuideTubeScene, angles: dict[str, float], spacing: float,
          physics: Physics | None = None) -> list[DropPhases]:
    """The drop through every tube at row spacing ``spacing`` (mm); raises if one sticks."""
    physics = physics or scene.physics
    return [landing(angles[t.name], scene.tube(i, spacing), physics) for i, t in enumerate(scene.tubes)]


def rules_of(scene: GuideTubeScene, angles: dict, grid: list[float], limits, drop=landing,
             equalise: bool = True) -> list[Rule]:
    """Every rule of the wall ``angles`` (deg); the row-spacing rules on the spacings ``grid`` (mm).
    ``drop(delta_deg, tube, physics)`` is ``landing`` (floats, raises if a seedling sticks) or ``symbolic_drop``
    (solve); ``equalise`` asks the optimiser for exactly equal landing times at the design row spacing."""
    def at(spacing: float) -> list[DropPhases]:
        return [drop(angles[t.name], scene.tube(i, spacing), scene.physics) for i, t in enumerate(scene.tubes)]

    return _rules(scene, at(scene.rows.design_spacing), [at(w) for w in grid], grid, limits, equalise)


def rules_even_if_stuck(scene: GuideTubeScene, angles: dict[str, float], grid: list[float],
                        limits) -> tuple[list[Rule], str | None]:
    """The rules of :func:`rules_of` on floats, for a design whose seedling may stick on a wall.  A tube whose
    seedling sticks at some row spacing fails its wall-exit rule as not evaluated (the seedling never reaches the
    wall end: whatever min_exit_speed, even 0, it fails), a landing-time rule that needs a seedling that never lands
    is not evaluated, and every other rule is evaluated (the free falls, the other tubes' walls), each saying where
    it sticks.  Returns the rules and the first sticking (None if every seedling lands)."""
    stuck: dict[float, str] = {}
    stuck_tubes: dict[str, str] = {}

    def at(spacing: float) -> list[DropPhases]:
        drops = []
        for i, t in enumerate(scene.tubes):
            phases, sticks = slide(angles[t.name], scene.tube(i, spacing), scene.physics)
            if sticks is not None:
                why = f"at row spacing {spacing:g} mm {sticks}"
                stuck.setdefault(spacing, why)
                stuck_tubes.setdefault(t.name, why)
            drops.append(phases)
        return drops

    design_spacing = scene.rows.design_spacing
    design, swept = at(design_spacing), [at(w) for w in grid]
    on_grid = next((stuck[w] for w in grid if w in stuck), None)
    rules = _rules(scene, design, swept, grid, limits, True, stuck.get(design_spacing), on_grid, stuck_tubes)
    return rules, stuck.get(design_spacing, on_grid)


def _rules(scene: GuideTubeScene, design: list[DropPhases], swept: list[list[DropPhases]], grid: list[float],
           limits, equalise: bool, stuck_at_design: str | None = None, stuck_on_grid: str | None = None,
           stuck_tubes: dict[str, str] | None = None) -> list[Rule]:
    """The rules of the drops ``design`` (at the design row spacing) and ``swept`` (at each spacing of ``grid``);
    a ``stuck_*`` reason leaves the landing-time rule(s) of those drops, and the wall-exit rule of each tube in
    ``stuck_tubes`` (name: reason), not evaluated."""
    spacing = scene.rows.design_spacing
    if stuck_at_design is None:
        rules = [landing_time_spread_rule([d.landing_time for d in design], limits.max_time_spread, spacing,
                                          equalise)]
    else:
        rules = [not_evaluated("landing_time_spread", None, limits.max_time_spread, "s",
                               f"at row spacing {spacing:g} mm", stuck_at_design)]
    if limits.max_spacing_error is not None:
        if stuck_on_grid is None:
            rules.append(spacing_error_rule([[d.landing_time for d in ds] for ds in swept], grid,
                                            scene.forward_mm_per_s, limits.max_spacing_error))
        else:
            rules.append(not_evaluated("spacing_error", None, limits.max_spacing_error, "mm",
                                       f"over row spacings {min(grid):g}-{max(grid):g} mm", stuck_on_grid))
    at_all = [design] + swept
    for i, t in enumerate(scene.tubes):
        if stuck_tubes is not None and t.name in stuck_tubes:
            rules.append(not_evaluated(f"wall_exit_speed_{t.name}", limits.min_exit_speed, None, "m/s",
                                       "at the wall end, every sampled row spacing",
                                       f"{stuck_tubes[t.name]} (it never reaches the wall end)"))
        else:
            rules.append(wall_exit_speed_rule(t.name, [ds[i].exit_speed_sq for ds in at_all], limits.min_exit_speed))
        rules.append(free_fall_height_rule(t.name, [ds[i].h1 / MM for ds in at_all], limits.min_free_fall))
    return rules


def spacing_error_mm(scene: GuideTubeScene, angles: dict[str, float], spacing: float,
                     physics: Physics | None = None) -> float | None:
    """Forward speed x landing-time spread at ``spacing`` (mm); None if a seedling sticks."""
    try:
        times = [d.landing_time for d in drops(scene, angles, spacing, physics)]
    except SeedlingSticks:
        return None
    return scene.forward_mm_per_s * (max(times) - min(times))


def _phase_table(d: DropPhases) -> dict:
    return {"h1_mm": d.h1 / MM, "h2_mm": d.h2 / MM, "s1_mm": d.s1 / MM, "t_fall": d.t_fall,
            "t_slide": d.t_slide, "t_after": d.t_after, "t_z": d.landing_time, "v_impact": d.v_impact,
            "v_wall": d.v_wall, "v_exit": d.v_exit, "v_land": d.v_land}


def _worst(values: list[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return None if len(known) < len(values) else max(known)


def scene_facts(spec, scene: GuideTubeScene, angles: dict[str, float], samples: int) -> dict:
    """The kind-specific part of result.json: physics, per-tube phases with the ODE twin and the
    analytic slope, the row-spacing sweep and the mu / v_L sensitivity."""
    design_spacing = scene.rows.design_spacing
    tubes = []
    for i, t in enumerate(scene.tubes):
        tube = scene.tube(i, design_spacing)
        closed = landing(angles[t.name], tube, scene.physics)
        ode = simulate(angles[t.name], tube, scene.physics, None if t.wall_gap is None else t.wall_gap * MM)
        tubes.append({
            "name": t.name, "mirror": t.mirror, "delta_deg": angles[t.name], "l3_mm": t.l3, "h5_mm": t.h5,
            "h6_mm": t.h6, **_phase_table(closed),
            "dtz_ddelta_s_per_deg": landing_time_slope(angles[t.name], tube, scene.physics) * math.pi / 180,
            "ode": {"t_fall": ode.t_fall, "t_slide": ode.t_slide, "t_after": ode.t_after, "t_z": ode.landing_time,
                    "v_land": ode.v_land, "hit_vertical_wall": ode.hit_vertical_wall,
                    "profile_t": ode.samples_t, "profile_height_mm": [h / MM for h in ode.samples_height]},
            "closed_form_minus_ode_s": closed.landing_time - ode.landing_time,
        })
    times = [t["t_z"] for t in tubes]
    grid = scene.spacing_grid(samples)
    sweep = [drops(scene, angles, w) for w in grid]
    sweep_times = {t.name: [ds[i].landing_time for ds in sweep] for i, t in enumerate(scene.tubes)}
    spreads = [max(ts) - min(ts) for ts in zip(*sweep_times.values())]
    base = scene.physics
    coarse = scene.spacing_grid(max(samples // FINE, 8))

    def sensitivity(changed: list[Physics]) -> dict:
        return {"design_spacing_mm": [spacing_error_mm(scene, angles, design_spacing, p) for p in changed],
                "worst_over_spacings_mm": [_worst([spacing_error_mm(scene, angles, w, p) for w in coarse])
                                           for p in changed]}

    cal = scene.calibration
    return {
        "source": spec.source,
        "physics": physics_facts(scene),
        "calibration": None if cal is None else {
            "tube": cal.tube, "delta_deg": cal.delta_deg, "landing_time": cal.target, "mu_range": list(cal.mu_range),
            "roots": cal.roots, "landing_time_range": list(cal.landing_time_range) if cal.landing_time_range else None},
        "rows": {"tray_pitch_mm": scene.rows.tray_pitch, "design_spacing_mm": design_spacing,
                 "spacings_mm": list(scene.rows.spacings), "forward_speed": scene.rows.forward_speed},
        "tubes": tubes,
        "landing_time_spread_s": max(times) - min(times),
        "spacing_error_mm": scene.forward_mm_per_s * (max(times) - min(times)),
        "closed_form_vs_ode_max_s": max(abs(t["closed_form_minus_ode_s"]) for t in tubes),
        "row_spacing_sweep": {
            "spacing_mm": grid, "t_z": sweep_times, "spread_s": spreads,
            "spacing_error_mm": [scene.forward_mm_per_s * s for s in spreads],
            "v_land": {t.name: [ds[i].v_land for ds in sweep] for i, t in enumerate(scene.tubes)}},
        "sensitivity": {
            "factors": SENSITIVITY,
            "mu": sensitivity([base.with_(mu=base.mu * f) for f in SENSITIVITY]),
            "terminal_speed": sensitivity([base.with_(terminal_speed=base.terminal_speed * f) for f in SENSITIVITY]),
        },
    }


def design_of(angles: dict[str, float]) -> dict[str, float]:
    return {f"delta_{name}": value for name, value in angles.items()}


def run_check(loaded: LoadedSpec) -> Result:
    """The given angles against every rule.  A design whose seedling sticks on a wall is checked too, and fails:
    its wall rules are evaluated, its landing-time rules are not (no seedling lands), and its facts name where it
    sticks instead of the drop phases."""
    spec = cast(GuideTubeSpec, loaded.model)       # load_spec validated it with this kind's model
    scene = GuideTubeScene.from_spec(spec)
    angles = spec.given_angles()
    samples = FINE * spec.solver.samples
    rules, sticks = rules_even_if_stuck(scene, angles, scene.spacing_grid(samples), spec.rules)
    extra = scene_facts(spec, scene, angles, samples) if sticks is None else stuck_facts(spec, scene, sticks)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=design_of(angles), rules=[r.record().to_json() for r in rules], extra=extra)


def stuck_facts(spec, scene: GuideTubeScene, sticks: str) -> dict:
    """The facts of a design whose seedling sticks: no drop to draw (no ``tubes``), the reason instead."""
    return {"source": spec.source, "sticks": sticks, "physics": physics_facts(scene)}


def physics_facts(scene: GuideTubeScene) -> dict:
    base = scene.physics
    return {"drop_height_mm": base.height / MM, "gravity": base.gravity,
            "terminal_speed": None if math.isinf(base.terminal_speed) else base.terminal_speed,
            "mu": base.mu, "mu_source": "given" if scene.calibration is None else "calibrated"}


def headline(result: Result) -> list[str]:
    """Each tube's landing time and wall angle, the spread between them and the plant-position error it makes, from
    result.json facts."""
    facts = result.extra or {}
    tubes = [t for t in facts.get("tubes") or [] if isinstance(t, dict)]
    if not tubes:
        return []
    times = ", ".join(f"{t.get('name')} {figure_text(t.get('t_z'), 's', 4)} "
                      f"(delta {figure_text(t.get('delta_deg'), 'deg', 4)})" for t in tubes)
    spread = facts.get("landing_time_spread_s")
    return [f"landing times: {times}",
            f"spread {figure_text(None if spread is None else 1000.0 * spread, 'ms')}, plant-position error "
            f"{figure_text(facts.get('spacing_error_mm'), 'mm')}"]
