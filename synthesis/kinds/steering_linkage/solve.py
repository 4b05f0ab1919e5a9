"""The solve side of kind steering_linkage (:data:`SOLVING`): its NLP, the independent re-check on a 10x
finer grid of inside locks (closed-form outer locks, dead centre root-found) and the result facts."""

from __future__ import annotations

from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import FINE, Recheck, StartReport
from synthesis.kinds.steering_linkage.check import evaluate, facts
from synthesis.kinds.steering_linkage.nlp import problem
from synthesis.kinds.steering_linkage.table12 import explain


def prepare(spec) -> dict:
    """Table 12 explained once per run (it does not depend on the design being solved for)."""
    return explain(spec)


def _fine_max_error(report: StartReport) -> float:
    tr = report.context
    return float("inf") if tr is None or tr.max_error_deg is None else tr.max_error_deg


def recheck(setting: Setting, outcome) -> Recheck:
    """The rules on FINE x the solver's samples; the objective re-measured there (the largest error over the
    fine grid, which is what the result reports, not the epigraph value at the solver's samples)."""
    spec = setting.spec
    rules, tr = evaluate(spec, outcome.design, FINE * spec.solver.samples)
    return Recheck(rules, tr, _fine_max_error)


def comparison(spec, tr, table12: dict) -> dict:
    """The redesign's largest error beside the published actual column's, over the rows within the range
    solved for (against the printed accurate column and against the Ackermann locks of the fitted w)."""
    if not table12 or tr.alpha_deg is None:
        return {}
    rows = [r for r in table12["rows"] if r["inside_deg"] <= spec.requirements.max_inside_lock + 1e-9]
    return {"max_error_deg": tr.max_error_deg, "over_inside_lock_deg": [0.0, spec.requirements.max_inside_lock],
            "published_rows_inside_deg": [r["inside_deg"] for r in rows],
            "published_actual_max_error_deg": max((abs(r["error_of_printed_columns_deg"]) for r in rows), default=None),
            "published_actual_max_error_vs_consistent_ackermann_deg":
                max((abs(r["actual_error_vs_consistent_ackermann_deg"]) for r in rows), default=None)}


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    design = dict(best.outcome.design)
    tr = best.context
    if tr is None:
        _, tr = evaluate(spec, design, FINE * spec.solver.samples)
    table12 = setting.data or {}
    return Finished(design=design,
                    objective={"name": spec.objective.name, "value": best.outcome.objective, "unit": "deg"},
                    facts={**facts(spec, design, tr, table12), "versus_published": comparison(spec, tr, table12)},
                    solver_settings={"samples": spec.solver.samples, "backoff": spec.solver.backoff})


def baseline_rules(setting: Setting) -> list[dict]:
    spec = setting.spec
    rules, _ = evaluate(spec, spec.design_values(), FINE * spec.solver.samples)
    return [r.record().to_json() for r in rules]


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules, prepare=prepare,
                  elastic_from="given", samples_hint="[solver] samples or [solver] backoff",
                  relax_hint="Lower min_transmission_angle, widen the arm_length limits or the bounds of "
                             "arm_length / base_angle.")
