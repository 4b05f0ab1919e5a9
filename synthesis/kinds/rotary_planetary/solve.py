"""The solve side of kind rotary_planetary (:data:`SOLVING`): its declared problem, the fine-grid re-check and the facts."""

from __future__ import annotations

from synthesis.core.coordinates import outside_bounds
from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import Recheck, StartReport
from synthesis.kinds.rotary_planetary.check import check_grid, evaluate, facts, find_angles, train_of, trajectory
from synthesis.kinds.rotary_planetary.nlp import problem
from synthesis.spec.common import design_box

OBJECTIVE_UNITS = {"key_pose_miss": "mm^2 + deg^2", "smooth_law": "deg^2/rad^4"}


def recheck(setting: Setting, outcome) -> Recheck:
    """Every rule of a returned design on a grid 10x finer than the solver's, its angles found anew."""
    spec = setting.spec
    names = list(spec.variables())
    outside = outside_bounds(names, design_box(spec.variables(), names)[0], outcome.design)
    rules, train, angles = evaluate(spec, outcome.design, *check_grid(spec))
    return Recheck(rules, (train, angles), invalid=outside)


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    design = dict(best.outcome.design)
    if best.context is None:
        train = train_of(spec, design)
        angles = find_angles(spec, train)
    else:
        train, angles = best.context
    return Finished(design=design,
                    objective={"name": spec.objective.name, "value": best.outcome.objective,
                               "unit": OBJECTIVE_UNITS[spec.objective.name]},
                    facts={**facts(spec, train, angles),
                           "solver_carrier_deg": best.outcome.details.get("carrier_deg")},
                    trajectory=trajectory(spec, train),
                    solver_settings={"samples_per_turn": spec.solver.samples_per_turn,
                                     "in_soil_samples": spec.solver.in_soil_samples})


def baseline_rules(setting: Setting) -> list[dict] | None:
    rules, _, _ = evaluate(setting.spec, setting.spec.design_values(), *check_grid(setting.spec))
    return [r.record().to_json() for r in rules]


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules,
                  samples_hint="[solver] samples_per_turn")
