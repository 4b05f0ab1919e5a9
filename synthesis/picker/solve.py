"""``agrisynth solve`` for kind picker_double_crank: multistart, independent fine-grid re-check, diagnosis."""

from __future__ import annotations

import functools
from typing import Callable

from synthesis.errors import SolverError
from synthesis.picker.check import evaluate, facts, linkage
from synthesis.picker.nlp import PickerNLP
from synthesis.result import Result
from synthesis.rule_solve import (FINE, ElasticDiagnosis, StartReport, diagnosis_of, ipopt_log, measured,
                                  run_multistart, starts_table, status_of, unsatisfied_error)
from synthesis.spec import LoadedSpec


def build_nlp(spec, elastic: bool = False) -> PickerNLP:
    return PickerNLP(spec, elastic=elastic)


def recheck(spec, design: dict[str, float]):
    """Rules of a returned design from the float kinematics on a grid 10x finer than the solver's."""
    dc = linkage(spec, design)
    return evaluate(spec, dc, samples=FINE * spec.solver.samples), dc


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
              scheduler: str | None = None) -> tuple[Result, list[StartReport], str]:
    spec = loaded.model
    run = run_multistart(build_nlp, spec, functools.partial(recheck, spec), starts=starts, seed=seed,
                         workers=workers, on_start=on_start, scheduler=scheduler)
    best, reports = run.best, run.reports
    elastic = None if best.satisfied else elastic_diagnosis(spec)
    design = dict(best.outcome.design)
    design["branch"] = spec.linkage.branch
    try:
        extra = facts(spec, linkage(spec, best.outcome.design))
    except Exception as exc:   # noqa: BLE001 - a broken best design still gets a result (status infeasible)
        extra = {"source": spec.source, "facts_error": str(exc)}
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status_of(best, reports, elastic),
        design=design, rules=[r.to_json() for r in best.records],
        objective={"name": spec.objective.name, "value": measured(best.outcome.objective),
                   "unit": "mm" if spec.objective.name == "sum_of_distances" else "mm^2"},
        solver=run.solver_record(stages=best.outcome.stages, samples=spec.solver.samples),
        extra={**extra, "baseline_design": spec.design_values(), "fine_grid_worst_violation": measured(best.worst_violation),
               "starts": [{**row, "stages": r.outcome.stages} for row, r in zip(starts_table(reports), reports)],
               "elastic": None if elastic is None else elastic.to_json()},
    )
    return result, reports, ipopt_log(reports)


def elastic_diagnosis(spec) -> ElasticDiagnosis:
    """One slack per rule (least-squares stage), from the given design pulled into the Grashof region."""
    elastic = build_nlp(spec, elastic=True)
    stage = elastic.stages[0]
    return diagnosis_of(stage, stage.solve(0, elastic.start_coordinates(elastic.init)))


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error of a run where no start satisfied every rule (status infeasible or failed)."""
    return unsatisfied_error(result, reports, ElasticDiagnosis.from_json(result.extra["elastic"]),
                             samples_hint="[solver] samples")


def baseline_rules(loaded: LoadedSpec) -> list[dict] | None:
    spec = loaded.model
    try:
        rules = evaluate(spec, linkage(spec))
    except Exception:   # noqa: BLE001 - a given design that does not assemble has no rule table
        return None
    return [r.record().to_json() for r in rules]
