"""The solve side of kind comb_finger (:data:`SOLVING`): its NLP, the re-check over a turn 10x finer, and the
result's facts, with the limits that bind (rules whose multipliers are non-zero, variables at a bound)."""

from __future__ import annotations

import math

from synthesis.kinds.comb_finger.check import evaluate, facts, trajectory
from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.kinds.comb_finger.nlp import problem
from synthesis.core.verdict import Recheck, StartReport


def recheck(setting: Setting, outcome) -> Recheck:
    """The rules of a returned design on floats, the finger's turn sampled 10x finer; theta measured anew."""
    spec = setting.spec
    rules, tr = evaluate(spec, dict(outcome.design))          # check's grid: >= 10x the solver's
    return Recheck(rules, tr, lambda report: math.degrees(tr.theta))


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    design = dict(best.outcome.design)
    details = best.outcome.details
    return Finished(design=design,
                    objective={"name": "max_combing_angle", "value": best.outcome.objective, "unit": "deg"},
                    trajectory=trajectory(spec, design),
                    facts={**facts(spec, design), "binding_rules": details.get("binding_rules", []),
                           "variables_at_bounds": details.get("variables_at_bounds", [])},
                    solver_settings={"turn_samples": spec.solver.turn_samples})


def baseline_rules(setting: Setting) -> list[dict] | None:
    spec = setting.spec
    rules, _ = evaluate(spec, spec.design_values())
    return [r.record().to_json() for r in rules]


def maximise(setting: Setting) -> bool:
    return True


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules, maximise=maximise,
                  samples_hint="[solver] turn_samples",
                  relax_hint="Loosen those requirements or widen the bounds of r, e, alpha, omega, b and rho.")
