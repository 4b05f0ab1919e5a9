"""The solve side of kind picker_double_crank (:data:`SOLVING`): its two-stage NLP, the independent
fine-grid re-check and the result facts."""

from __future__ import annotations

from synthesis.core.coordinates import outside_bounds
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import FINE, Recheck, StartReport
from synthesis.kinds.picker.check import evaluate, facts, linkage
from synthesis.kinds.picker.dynamics import PEAK_UNITS
from synthesis.kinds.picker.nlp import NAMES, PickerNLP
from synthesis.spec.common import design_box

OBJECTIVE_UNITS = {"sum_of_distances": "mm", "sum_of_squares": "mm^2", **PEAK_UNITS}


def build(setting: Setting, elastic: bool = False) -> PickerNLP:
    return PickerNLP(setting.spec, elastic=elastic, setting=setting)


def recheck(setting: Setting, outcome) -> Recheck:
    """Rules of a returned design from the float kinematics on a grid 10x finer than the solver's."""
    spec = setting.spec
    outside = outside_bounds(NAMES, design_box(spec.variables(), NAMES)[0], outcome.design)
    dc = linkage(spec, outcome.design)
    return Recheck(evaluate(spec, dc, samples=FINE * spec.solver.samples), dc, invalid=outside)


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    design = {**best.outcome.design, "branch": spec.linkage.branch}
    try:
        kind_facts = facts(spec, linkage(spec, best.outcome.design))
    except Exception as exc:   # noqa: BLE001 - a broken best design still gets a result (status infeasible)
        kind_facts = {"source": spec.source, "facts_error": str(exc)}
    settings = {"stages": best.outcome.details.get("stages"), "samples": spec.solver.samples}
    if "key_pose_crank_deg" in best.outcome.details:     # free key poses: where the solver held them
        settings["key_pose_crank_deg"] = best.outcome.details["key_pose_crank_deg"]
    return Finished(design=design,
                    objective={"name": spec.objective.name, "value": best.outcome.objective,
                               "unit": OBJECTIVE_UNITS[spec.objective.name]},
                    facts=kind_facts, solver_settings=settings)


def baseline_rules(setting: Setting) -> list[dict] | None:
    spec = setting.spec
    try:
        rules = evaluate(spec, linkage(spec))
    except Exception:   # noqa: BLE001 - a given design that does not assemble has no rule table
        return None
    return [r.record().to_json() for r in rules]


SOLVING = Solving(build=build, recheck=recheck, finish=finish, baseline_rules=baseline_rules,
                  # from the given design pulled into the Grashof region (the best start may not assemble)
                  elastic_from="given", samples_hint="[solver] samples")
