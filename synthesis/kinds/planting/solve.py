"""The solve side of kind planting_fourbar (:data:`SOLVING`): its NLP, the independent fine-grid
re-check of a returned design, and the result's facts.  The multistart, the verdict and the elastic
diagnosis are the core's (:mod:`synthesis.core.solve`)."""

from __future__ import annotations

from typing import cast

from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import FINE, Recheck, StartReport
from synthesis.dynamics.linkage import PEAK_OBJECTIVES
from synthesis.errors import AgrisynthError
from synthesis.kinds.planting.check import (CHECK_PHASE_SAMPLES, CHECK_TURN_SAMPLES, evaluate, scene_facts, trajectory,
                                      unevaluated)
from synthesis.kinds.planting.nlp import declare
from synthesis.kinds.planting.scene import PlantingScene

OBJECTIVE_UNITS = {"nearest": "-", "robust": "-", "smooth": "mm/s^2",
                   **{name: unit for name, (unit, _) in PEAK_OBJECTIVES.items()}}


def smallest_margin(report: StartReport) -> float:
    """The robust objective of a returned design: its smallest normalised margin on the fine grid."""
    return report.smallest_normalised_margin


def recheck(setting: Setting, outcome) -> Recheck:
    """Every rule of a returned design, independently of the solver: root-found precision points,
    phases and turn sampled 10x finer than the NLP, and never coarser than `check` samples them (so the check of
    solved.toml gives the solve's rule table to the last digit; AssemblyError when it never assembles)."""
    spec = setting.spec
    scene = PlantingScene.from_spec(spec, outcome.design)
    rules, pts = evaluate(scene, spec.rules,
                          phase_samples=max(FINE * spec.solver.samples_per_phase, CHECK_PHASE_SAMPLES),
                          turn_samples=max(FINE * spec.solver.samples_per_turn, CHECK_TURN_SAMPLES))
    return Recheck(rules, (scene, pts), smallest_margin if spec.objective.name == "robust" else None)


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    design = dict(best.outcome.design)
    if best.context is not None:
        (scene, pts), rules = best.context, None
    else:       # the linkage never assembles: only the link-length rules can be evaluated
        scene, pts = PlantingScene.from_spec(spec, design), None
        # a start without context is one the verdict could not evaluate, which always says why
        rules = [r.record().to_json() for r in unevaluated(scene, spec.rules, cast(str, best.why))]
    return Finished(
        design={**design, "branch": spec.arm.branch},
        objective={"name": spec.objective.name, "value": best.outcome.objective,
                   "unit": OBJECTIVE_UNITS[spec.objective.name]},
        facts={**scene_facts(spec, scene, pts), "solver_crank_deg": best.outcome.details.get("solver_crank_deg")},
        trajectory=trajectory(scene, pts),
        solver_settings={"samples_per_phase": spec.solver.samples_per_phase,
                         "samples_per_turn": spec.solver.samples_per_turn, "backoff": spec.solver.backoff},
        rules=rules,
        # the assembly branch is the spec's in both (the design table showed "-" for the given one)
        baseline_design={**spec.design_values(), "branch": spec.arm.branch})


def baseline_rules(setting: Setting) -> list[dict] | None:
    """The rule table of the spec's given design, for the side-by-side table (None: it never assembles)."""
    try:
        rules, _ = evaluate(PlantingScene.from_spec(setting.spec), setting.spec.rules)
    except AgrisynthError:
        return None
    return [r.record().to_json() for r in rules]


def maximise(setting: Setting) -> bool:
    return setting.spec.objective.name == "robust"


SOLVING = Solving(build=declared(declare), recheck=recheck, finish=finish, baseline_rules=baseline_rules, maximise=maximise,
                  samples_hint="[solver] samples_per_phase / samples_per_turn or [solver] backoff")
