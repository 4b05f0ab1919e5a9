"""``agrisynth solve`` for kind clamp_cam: multistart IPOPT, fine-grid re-check, infeasibility diagnosis."""

from __future__ import annotations

import functools
from typing import Callable

import numpy as np

from synthesis.clamp_cam.check import FINE, describe
from synthesis.clamp_cam.nlp import OBJECTIVE_UNITS, CamNLP
from synthesis.clamp_cam.scene import CamScene, evaluate, fit_law
from synthesis.errors import SolverError
from synthesis.result import Result
from synthesis.rule_solve import (ElasticDiagnosis, StartReport, diagnosis_of, ipopt_log, measured, run_multistart,
                                  starts_table, status_of, unsatisfied_error)
from synthesis.spec import LoadedSpec


def build_nlp(spec, optimised=None, elastic: bool = False) -> CamNLP:
    return CamNLP(spec, optimised, elastic=elastic)


def fine_check(spec, design: dict[str, float], optimised=None) -> list:
    """Evaluate a design independently of the solver (numpy, no CasADi) on a 10x finer grid: the rules."""
    scene = CamScene.from_spec(spec, design, optimised)
    rules, _ = evaluate(scene, FINE * spec.solver.samples_per_segment)
    return rules


def recheck(spec, optimised, design: dict[str, float]):
    return fine_check(spec, design, optimised), None


def objective_value(spec, report: StartReport) -> float:
    """The objective in report units; the peak pressure angle is read from the fine-grid re-check."""
    if spec.objective.name == "pressure_angle" and report.records:
        return max(r.value for r in report.records if r.name.startswith("pressure_angle_"))
    return report.outcome.objective


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
              scheduler: str | None = None) -> tuple[Result, list[StartReport], str]:
    """Multistart solve; returns (result, every start's report, IPOPT log)."""
    spec = loaded.model
    optimised = fit_law(spec)             # the B-spline law is fitted once (cvxpy), then held fixed
    run = run_multistart(build_nlp, spec, functools.partial(recheck, spec, optimised), starts=starts, seed=seed,
                         workers=workers, on_start=on_start, build_args=(optimised,), scheduler=scheduler)
    chosen, ordered = run.best, run.reports
    elastic = None if chosen.satisfied else elastic_diagnosis(spec, optimised, chosen.outcome.design)
    scene = CamScene.from_spec(spec, chosen.outcome.design, optimised)
    extra, trajectory = describe(scene)
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status_of(chosen, ordered, elastic),
        design=dict(scene.design), rules=[r.to_json() for r in chosen.records],
        objective={"name": spec.objective.name, "value": objective_value(spec, chosen),
                   "unit": OBJECTIVE_UNITS[spec.objective.name]},
        trajectory=trajectory,
        solver=run.solver_record(samples_per_segment=spec.solver.samples_per_segment),
        extra={
            **extra,
            "baseline_design": spec.design_values(),
            "fine_grid_worst_violation": measured(chosen.worst_violation),
            "starts": starts_table(ordered, functools.partial(objective_value, spec)),
            "elastic": None if elastic is None else elastic.to_json(),
        },
    )
    return result, ordered, ipopt_log(ordered)


def elastic_diagnosis(spec, optimised, design: dict[str, float]) -> ElasticDiagnosis:
    """Re-solve from ``design`` with one elastic slack per rule: the rules whose slack stays > 0 conflict."""
    elastic = build_nlp(spec, optimised, elastic=True)
    return diagnosis_of(elastic.nlp, elastic.nlp.solve(0, np.array([design[n] for n in elastic.names])))


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error of a run where no start satisfied every rule (status infeasible or failed)."""
    return unsatisfied_error(result, reports, ElasticDiagnosis.from_json(result.extra["elastic"]),
                             samples_hint="[solver] samples_per_segment or [solver] backoff",
                             relax_hint="Try wider bounds on the design variables, looser limits on those rules, "
                                        "or another motion law.")


def baseline_rules(loaded: LoadedSpec) -> list[dict] | None:
    """The rule table of the spec's given design (start values), for the side-by-side table."""
    spec = loaded.model
    return [r.record().to_json() for r in fine_check(spec, spec.design_values(), fit_law(spec))]
