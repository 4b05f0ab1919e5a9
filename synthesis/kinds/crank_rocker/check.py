"""``agrisynth check`` for kind crank_rocker: simulate the given lengths and evaluate every rule.

Rules: the crank turns fully (Grashof), the time ratio K and the rocker swing read off the simulated
extreme positions, and the smallest transmission angle over a turn.
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np

from synthesis.constraints import Rule
from synthesis.constraints.grashof import grashof_rule
from synthesis.kinds.crank_rocker.rules import rocker_swing_rule, time_ratio_rule
from synthesis.constraints.transmission import acute_transmission_rule
from synthesis.kinematics.rocker_drive import (CrankRocker, QuickReturn, acute, joints, quick_return, rocker_curve,
                                              transmission_angles_deg, turn_grid)
from synthesis.dynamics.linkage import FourbarDynamics, dynamics_facts, dynamics_rules
from synthesis.core.kind import figure_text
from synthesis.core.verdict import FINE
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.crank_rocker.spec import CrankRockerSpec

#: crank angles of the transmission-angle check in ``check`` (even, so 0 and 180 deg are included)
CHECK_SAMPLES = 3600


def check_samples(spec: CrankRockerSpec) -> int:
    """The crank angles a design is checked on -- by `check` and by the solve's re-check alike, so both read one rule
    table: 10x the solver's samples, at least :data:`CHECK_SAMPLES` (a peak the solve passed on 720 samples, check
    failed on 3600)."""
    return max(FINE * spec.solver.samples_per_turn, CHECK_SAMPLES)


def mechanism(spec: CrankRockerSpec, values: dict[str, float] | None = None) -> CrankRocker:
    v = spec.design_values() if values is None else values
    return CrankRocker(v["l7"], v["l8"], v["l9"], v["l10"], spec.branch)


def rules_of(spec: CrankRockerSpec, lengths, stroke, u, w, mu) -> list[Rule]:
    """Every rule of the spec on a trace of floats or CasADi symbols: the lengths (l7, l8, l9, l10), the
    quick stroke's crank angle, the rocker tip's positions u, w at the two extremes relative to its
    pivot, and the transmission angles (deg) over a turn.  Used by check, the NLP and the re-check."""
    req, tol = spec.requirements, spec.tolerances
    l7, l8, l9, l10 = lengths
    rules = [grashof_rule(l10, l7, l8, l9),
             time_ratio_rule(stroke, req.time_ratio, tol.time_ratio),
             rocker_swing_rule(u, w, l9, req.rocker_swing, tol.rocker_swing),
             acute_transmission_rule(mu, req.min_transmission_angle, "over a turn")]
    if spec.dynamics is not None and spec.dynamics.has_rules():
        # sampled on the transmission angle's grid (the solver's samples_per_turn, the check's, the re-check's)
        samples = mu.numel() if hasattr(mu, "numel") else len(mu)
        rules += dynamics_rules(linkage_dynamics(spec, lengths), spec.dynamics.limits, samples)
    return rules


def unevaluated_dynamics_rules(spec: CrankRockerSpec, why: str) -> list[Rule]:
    """The ``[dynamics.limits]`` rules of a crank that cannot turn: not evaluated, for the same reason."""
    return [] if spec.dynamics is None else dynamics_rules(None, spec.dynamics.limits, 0, missing=why)


#: the crank-rocker's joints and links by their seed-001 names, in synthesis.dynamics.fourbar's order
DYNAMICS_JOINTS = ("G", "F", "E", "A")
DYNAMICS_LINKS = ("crank GF", "coupler FE", "rocker AE")


def linkage_dynamics(spec: CrankRockerSpec, lengths) -> FourbarDynamics:
    """The inverse dynamics' inputs of the lengths (l7, l8, l9, l10: floats or symbols): the shared four-bar with
    frame l10, crank l7, coupler l8, rocker l9 and the frame along +x (synthesis.kinematics.rocker_drive)."""
    l7, l8, l9, l10 = lengths
    table = spec.dynamics
    # called only with a [dynamics] table, whose crank speed CrankRockerSpec's validator requires
    assert table is not None and table.crank_speed is not None
    bars = {"crank": [((0.0, 0.0), (l7, 0.0))], "coupler": [((0.0, 0.0), (l8, 0.0))],
            "rocker": [((0.0, 0.0), (l9, 0.0))]}
    counterweight = None if table.counterweight is None else table.counterweight.values()
    rocker_counterweight = None if table.rocker_counterweight is None else table.rocker_counterweight.values()
    return FourbarDynamics.of(table, spec.branch, (l10, l7, l8, l9, 0.0), bars, table.crank_speed * 2 * math.pi / 60,
                              counterweight=counterweight, rocker_counterweight=rocker_counterweight)


def evaluate(spec: CrankRockerSpec, cr: CrankRocker, samples: int = CHECK_SAMPLES
             ) -> tuple[list[Rule], QuickReturn | None]:
    """Every rule of the spec for the mechanism ``cr``; K, swing and transmission need a turning crank."""
    req, tol = spec.requirements, spec.tolerances

    def not_evaluated(why: str) -> tuple[list[Rule], None]:
        return [grashof_rule(cr.l10, cr.l7, cr.l8, cr.l9),
                time_ratio_rule(None, req.time_ratio, tol.time_ratio, why),
                rocker_swing_rule(None, None, None, req.rocker_swing, tol.rocker_swing, why),
                acute_transmission_rule(None, req.min_transmission_angle, "over a turn", missing=why),
                *unevaluated_dynamics_rules(spec, why)], None

    if not cr.crank_turns():
        slacks = cr.grashof_slacks()
        listed = ", ".join(f"{k} {v:.3g} mm" for k, v in slacks.items())
        if min(slacks.values()) == 0.0:     # the rule holds (margin 0), yet the motion is not one linkage's
            return not_evaluated(f"the linkage is at a change point (Grashof crank-rocker slacks {listed}): at its "
                                 f"toggle it can go on either way, so a turn of it is not defined")
        return not_evaluated(f"the crank cannot make a full turn (Grashof crank-rocker slacks {listed})")
    try:
        q = quick_return(cr)
    except ValueError as exc:     # e.g. a crank so short (5e-324 mm) that the rocker has no extremes to find
        return not_evaluated(f"the rocker's extreme positions cannot be found: {exc}")
    ex = q.extremes
    tips = rocker_curve(cr, np.array([ex.phi_folded, ex.phi_extended]))["tip"]
    a = np.array([cr.l10, 0.0])
    u, w = tips[:, 0] - a, tips[:, 1] - a
    return rules_of(spec, (cr.l7, cr.l8, cr.l9, cr.l10), min(q.stroke_fold_to_ext, q.stroke_ext_to_fold), u, w,
                    transmission_angles_deg(cr, samples)), q


def motion_facts(cr: CrankRocker, q: QuickReturn | None, samples: int = 361, checked: int = CHECK_SAMPLES) -> dict:
    """What the simulated mechanism does: extremes, strokes, K, swing, angles (the smallest transmission angle on the
    ``checked`` crank angles its rule reads); curves for the figures."""
    if q is None:
        return {"crank_turns": False}
    ex = q.extremes
    phi = np.linspace(0.0, 2 * math.pi, samples)
    curve = rocker_curve(cr, phi)
    mu = np.degrees(curve["mu"])
    fine = turn_grid(checked)
    gam = acute(transmission_angles_deg(cr, checked))
    k = int(np.argmin(gam))
    return {
        "crank_turns": True,
        "time_ratio": q.time_ratio,
        "rocker_swing_deg": math.degrees(q.swing),
        "min_transmission_angle_deg": float(gam[k]),
        "min_transmission_at_crank_deg": math.degrees(fine[k]),
        "extreme_crank_angle_deg": math.degrees(q.extreme_crank_angle),
        "theta1_deg": math.degrees(q.frame_rocker_angle),
        "extremes": {
            "folded": {"crank_deg": math.degrees(ex.phi_folded), "rocker_deg": math.degrees(ex.beta_folded),
                       "joints": joints(cr, ex.phi_folded)},
            "extended": {"crank_deg": math.degrees(ex.phi_extended), "rocker_deg": math.degrees(ex.beta_extended),
                         "joints": joints(cr, ex.phi_extended)},
        },
        "strokes_deg": {"folded_to_extended": math.degrees(q.stroke_fold_to_ext),
                        "extended_to_folded": math.degrees(q.stroke_ext_to_fold)},
        "curve": {"crank_deg": np.degrees(phi).tolist(), "rocker_deg": np.degrees(np.unwrap(curve["beta"])).tolist(),
                  "transmission_deg": mu.tolist(), "E_x": curve["tip"][0].tolist(), "E_y": curve["tip"][1].tolist()},
    }


def facts(spec: CrankRockerSpec, cr: CrankRocker, q: QuickReturn | None) -> dict:
    req = spec.requirements
    extra = {}
    if spec.dynamics is not None and q is not None:
        crank_speed = spec.dynamics.crank_speed
        assert crank_speed is not None           # CrankRockerSpec's validator requires it with a [dynamics] table
        extra["dynamics"] = dynamics_facts(linkage_dynamics(spec, (cr.l7, cr.l8, cr.l9, cr.l10)),
                                           spec.dynamics.samples, DYNAMICS_JOINTS, DYNAMICS_LINKS,
                                           crank_speed, spec.dynamics)
    return {"source": spec.source, "branch": spec.branch,
            "requirements": {"time_ratio": req.time_ratio, "rocker_swing_deg": req.rocker_swing,
                             "min_transmission_angle_deg": req.min_transmission_angle},
            "frame": "crank pivot G at the origin, rocker pivot A on +x; crank angle from G -> A, counter-clockwise",
            "motion": motion_facts(cr, q, checked=check_samples(spec)), **extra}


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(CrankRockerSpec, loaded.model)      # load_spec validated it with this kind's model
    cr = mechanism(spec)
    rules, q = evaluate(spec, cr, check_samples(spec))
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=spec.design_values(), rules=[r.record().to_json() for r in rules],
                  extra=facts(spec, cr, q))


def headline(result: Result) -> list[str]:
    """Rocker stroke, time ratio and the smallest transmission angle (where), from result.json facts."""
    motion = (result.extra or {}).get("motion") or {}
    if not motion:
        return []
    strokes = motion.get("strokes_deg") or {}
    line = (f"rocker stroke {figure_text(motion.get('rocker_swing_deg'), 'deg', 4)}, time ratio "
            f"{figure_text(motion.get('time_ratio'), '', 4)}, transmission angle min "
            f"{figure_text(motion.get('min_transmission_angle_deg'), 'deg', 4)} at crank "
            f"{figure_text(motion.get('min_transmission_at_crank_deg'), 'deg')}")
    out = [line]
    if strokes:
        out.append(f"crank turn: {figure_text(strokes.get('folded_to_extended'), 'deg', 4)} folded to extended, "
                   f"{figure_text(strokes.get('extended_to_folded'), 'deg', 4)} back")
    return out
