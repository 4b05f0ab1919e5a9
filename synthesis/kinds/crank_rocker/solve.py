"""The solve side of kind crank_rocker (:data:`SOLVING`): its NLP, independent re-check and result facts;
the closed form of eq (8)-(10) beside the optimum."""

from __future__ import annotations

from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import Recheck, StartReport
from synthesis.kinds.crank_rocker.check import check_samples, evaluate, facts, mechanism
from synthesis.kinds.crank_rocker.closed_form import solve_paper_equations
from synthesis.core.coordinates import outside_bounds
from synthesis.dynamics.linkage import PEAK_OBJECTIVES
from synthesis.kinds.crank_rocker.nlp import NAMES, problem
from synthesis.spec.common import design_box, is_free

OBJECTIVE_UNITS = {"min_total_length": "mm", "max_transmission_angle": "deg",
                   **{name: unit for name, (unit, _) in PEAK_OBJECTIVES.items()}}


def recheck(setting: Setting, outcome) -> Recheck:
    """Rules of a returned design on a grid 10x finer than the solver's and at least as fine as the check's (a sampled
    peak the solve passed on 720 samples and `check` of its solved.toml failed on 3600), extremes root-found anew."""
    spec = setting.spec
    outside = outside_bounds(NAMES, design_box(spec.variables(), NAMES)[0], outcome.design)
    cr = mechanism(spec, outcome.design)
    rules, q = evaluate(spec, cr, samples=check_samples(spec))
    return Recheck(rules, (cr, q), invalid=outside)


def closed_form(spec) -> dict | None:
    """Eq (8)-(10) solved directly, when the frame l10 is given (the paper's setting)."""
    if is_free(spec.links.l10):
        return None
    req = spec.requirements
    designs = solve_paper_equations(req.time_ratio, req.rocker_swing, req.min_transmission_angle,
                                    spec.design_values()["l10"], spec.branch)
    # a root of the equations is a design only if the simulated mechanism does what they assume
    valid = [d for d in designs if d.min_transmission_deg is not None
             and abs(d.time_ratio - req.time_ratio) < 1e-6 and abs(d.swing_deg - req.rocker_swing) < 1e-6
             and d.min_transmission_deg >= req.min_transmission_angle - 1e-6]
    return {"equations": "seed 001 eq (8)-(10), gamma_min = requirement, l10 given",
            "roots": [d.to_json() for d in designs],
            "shortest_valid": valid[0].to_json() if valid else None}


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    if best.context is None:
        cr, q = mechanism(spec, best.outcome.design), None
    else:
        cr, q = best.context
    return Finished(
        design=dict(best.outcome.design),
        objective={"name": spec.objective.name, "value": best.outcome.objective,
                   "unit": OBJECTIVE_UNITS[spec.objective.name]},
        facts={**facts(spec, cr, q), "solver_extremes_crank_deg": best.outcome.details.get("extremes_crank_deg"),
               "closed_form": closed_form(spec)},
        solver_settings={"samples_per_turn": spec.solver.samples_per_turn})


def baseline_rules(setting: Setting) -> list[dict] | None:
    spec = setting.spec
    rules, _ = evaluate(spec, mechanism(spec), check_samples(spec))
    return [r.record().to_json() for r in rules]


def maximise(setting: Setting) -> bool:
    return setting.spec.objective.name == "max_transmission_angle"


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules, maximise=maximise,
                  # the given design assembles; the least-violating start may not
                  elastic_from="given", samples_hint="[solver] samples_per_turn")
