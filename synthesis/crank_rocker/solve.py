"""``agrisynth solve`` for kind crank_rocker: multistart IPOPT, independent re-check, closed form beside it."""

from __future__ import annotations

import functools
import math
from typing import Callable

from synthesis.crank_rocker.check import evaluate, facts, mechanism
from synthesis.crank_rocker.closed_form import solve_paper_equations
from synthesis.crank_rocker.nlp import CrankRockerNLP
from synthesis.errors import SolverError
from synthesis.result import Result
from synthesis.rule_solve import (FINE, ElasticDiagnosis, StartReport, diagnosis_of, ipopt_log, measured,
                                  run_multistart, starts_table, status_of, unsatisfied_error)
from synthesis.spec import LoadedSpec
from synthesis.spec.common import is_free


def build_nlp(spec, elastic: bool = False) -> CrankRockerNLP:
    return CrankRockerNLP(spec, elastic=elastic)


def recheck(spec, design: dict[str, float]):
    """Rules of a returned design on a grid 10x finer than the solver's, extremes root-found anew."""
    cr = mechanism(spec, design)
    rules, q = evaluate(spec, cr, samples=FINE * spec.solver.samples_per_turn)
    return rules, (cr, q)


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


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
              scheduler: str | None = None) -> tuple[Result, list[StartReport], str]:
    spec = loaded.model
    maximise = spec.objective.name == "max_transmission_angle"
    run = run_multistart(build_nlp, spec, functools.partial(recheck, spec), starts=starts, seed=seed,
                         workers=workers, maximise=maximise, on_start=on_start, scheduler=scheduler)
    best, reports = run.best, run.reports
    if best.context is None:
        cr, q = mechanism(spec, best.outcome.design), None
    else:
        cr, q = best.context
    elastic = None if best.satisfied else elastic_diagnosis(spec)
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status_of(best, reports, elastic),
        design=dict(best.outcome.design), rules=[r.to_json() for r in best.records],
        objective={"name": spec.objective.name, "value": best.outcome.objective, "unit": "deg" if maximise else "mm"},
        solver=run.solver_record(samples_per_turn=spec.solver.samples_per_turn),
        extra={**facts(spec, cr, q),
               "baseline_design": spec.design_values(),
               "solver_extremes_crank_deg": [math.degrees(v) for v in best.outcome.extremes],
               "fine_grid_worst_violation": measured(best.worst_violation),
               "closed_form": closed_form(spec),
               "starts": starts_table(reports),
               "elastic": None if elastic is None else elastic.to_json()},
    )
    return result, reports, ipopt_log(reports)


def elastic_diagnosis(spec) -> ElasticDiagnosis:
    """One slack per rule, from the given design (it assembles; the best start may not)."""
    elastic = build_nlp(spec, elastic=True)
    return diagnosis_of(elastic.nlp, elastic.solve_design(0, elastic.prepared_start(elastic.init)))


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error of a run where no start satisfied every rule (status infeasible or failed)."""
    return unsatisfied_error(result, reports, ElasticDiagnosis.from_json(result.extra["elastic"]),
                             samples_hint="[solver] samples_per_turn")


def baseline_rules(loaded: LoadedSpec) -> list[dict] | None:
    spec = loaded.model
    rules, _ = evaluate(spec, mechanism(spec))
    return [r.record().to_json() for r in rules]
