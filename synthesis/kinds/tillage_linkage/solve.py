"""The solve side of kind tillage_linkage (:data:`SOLVING`): its NLP, the independent re-check on a 10x
finer crank grid (extremes and soil entry/exit root-found anew, floats) and the result facts."""

from __future__ import annotations

from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import FINE, Recheck, StartReport
from synthesis.kinds.tillage_linkage.check import curves, evaluate, facts
from synthesis.kinds.tillage_linkage.nlp import problem

OBJECTIVE_UNITS = {"min_bar_length": "mm", "max_margin": "normalised margin", "min_peak_torque": "N m"}


def fine(spec, design: dict[str, float]):
    s = spec.solver
    return evaluate(spec, design, FINE * s.samples, FINE * s.soil_samples)


def smallest_margin(report: StartReport) -> float:
    """max_margin: the fine grid's smallest normalised margin (what the epigraph maximised at the samples)."""
    return report.smallest_normalised_margin


def recheck(setting: Setting, outcome) -> Recheck:
    spec = setting.spec
    rules, m = fine(spec, outcome.design)
    return Recheck(rules, m, smallest_margin if spec.objective.name == "max_margin" else None)


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    design = dict(best.outcome.design)
    m = best.context
    if m is None:
        _, m = fine(spec, design)
    _, trajectory = curves(spec, design, m)
    return Finished(design=design,
                    objective={"name": spec.objective.name, "value": best.outcome.objective,
                               "unit": OBJECTIVE_UNITS[spec.objective.name]},
                    facts={**facts(spec, design, m), "solver_crank_deg": best.outcome.details.get("crank_deg")},
                    trajectory=trajectory,
                    solver_settings={"samples": spec.solver.samples, "soil_samples": spec.solver.soil_samples,
                                     "backoff": spec.solver.backoff})


def baseline_rules(setting: Setting) -> list[dict]:
    spec = setting.spec
    rules, _ = fine(spec, spec.design_values())
    return [r.record().to_json() for r in rules]


def maximise(setting: Setting) -> bool:
    return setting.spec.objective.name == "max_margin"


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules, maximise=maximise,
                  samples_hint="[solver] samples / soil_samples or [solver] backoff",
                  relax_hint="Loosen those requirements (depth, lift, rearward speed, slot angle, engagement) or "
                             "widen the bounds of a, b, c, theta and height_c.")
