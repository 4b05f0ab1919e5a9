"""``agrisynth solve`` for kind clamp_cam: multistart IPOPT, fine-grid re-check, infeasibility diagnosis."""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from synthesis.clamp_cam.check import FINE, describe
from synthesis.clamp_cam.nlp import CamNLP, StartOutcome
from synthesis.clamp_cam.scene import CamScene, evaluate, fit_law
from synthesis.errors import SolverError
from synthesis.multistart import latin_hypercube_starts, run_starts
from synthesis.result import Result
from synthesis.rule_solve import ElasticDiagnosis, status_of, unsatisfied_error
from synthesis.spec import LoadedSpec


def build_nlp(spec, optimised=None, elastic: bool = False) -> CamNLP:
    return CamNLP(spec, optimised, elastic=elastic)


@dataclass
class StartReport:
    outcome: StartOutcome
    satisfied: bool                 # every rule on the fine grid
    worst_violation: float          # largest normalised violation on the fine grid (0 when satisfied)
    records: list = field(default_factory=list)


def fine_check(spec, design: dict[str, float], optimised=None) -> list:
    """Evaluate a design independently of the solver (numpy, no CasADi) on a 10x finer grid."""
    scene = CamScene.from_spec(spec, design, optimised)
    rules, _ = evaluate(scene, FINE * spec.solver.samples_per_segment)
    return [r.record() for r in rules]


def _report(spec, outcome: StartOutcome, optimised) -> StartReport:
    records = fine_check(spec, outcome.design, optimised)
    worst = max([0.0] + [-r.normalised_margin for r in records if not r.satisfied])
    return StartReport(outcome, all(r.satisfied for r in records), worst, records)


def _better(a: StartReport, b: StartReport) -> bool:
    """Is a better than b: feasible first, then the objective, then the start index."""
    if a.satisfied != b.satisfied:
        return a.satisfied
    if not a.satisfied:
        return a.worst_violation < b.worst_violation
    fa, fb = a.outcome.objective, b.outcome.objective
    return fa < fb - 1e-12 or (abs(fa - fb) <= 1e-12 and a.outcome.start < b.outcome.start)


def objective_value(nlp: CamNLP, report: StartReport) -> float:
    """The objective in report units; the peak pressure angle is read from the fine-grid re-check."""
    if nlp.spec.objective.name == "pressure_angle" and report.records:
        return max(r.value for r in report.records if r.name.startswith("pressure_angle_"))
    return nlp.objective_value(report.outcome.design, report.outcome.objective)


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None
              ) -> tuple[Result, list[StartReport], str]:
    """Multistart solve; returns (result, every start's report, IPOPT log)."""
    spec = loaded.model
    starts = spec.solver.starts if starts is None else starts
    seed = spec.solver.seed if seed is None else seed
    optimised = fit_law(spec)             # the B-spline law is fitted once (cvxpy), then held fixed
    nlp = build_nlp(spec, optimised)
    x_starts = latin_hypercube_starts(nlp.bounds, nlp.init, starts, seed)
    reports: dict[int, StartReport] = {}
    best: list[StartReport] = []

    def done(outcome: StartOutcome) -> None:
        rep = _report(spec, outcome, optimised)
        reports[outcome.start] = rep
        if not best or _better(rep, best[0]):
            best[:] = [rep]
        on_start(rep, best[0])

    t0 = time.perf_counter()
    factory = functools.partial(build_nlp, spec, optimised)
    if workers <= 1:
        factory = lambda: nlp  # noqa: E731 - reuse the solver already built
    run_starts(factory, x_starts, workers, done)
    wall = time.perf_counter() - t0
    ordered = [reports[i] for i in range(starts)]
    chosen = best[0]
    elastic = None if chosen.satisfied else elastic_diagnosis(spec, optimised, chosen.outcome.design)
    status = status_of(chosen, ordered, elastic)
    scene = CamScene.from_spec(spec, chosen.outcome.design, optimised)
    extra, trajectory = describe(scene)
    log = "\n".join(f"===== start {r.outcome.start}: {r.outcome.return_status}, {r.outcome.iterations} iterations\n"
                    f"{r.outcome.log}" for r in ordered)
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status,
        design=dict(scene.design), rules=[r.to_json() for r in chosen.records],
        objective={"name": spec.objective.name,
                   "value": objective_value(nlp, chosen)},
        trajectory=trajectory,
        solver={"name": "ipopt", "return_status": chosen.outcome.return_status,
                "iterations": chosen.outcome.iterations, "wall_s": wall, "starts": starts, "seed": seed,
                "best_start": chosen.outcome.start, "workers": workers,
                "samples_per_segment": spec.solver.samples_per_segment, "fine_grid_factor": FINE},
        extra={
            **extra,
            "baseline_design": spec.design_values(),
            "fine_grid_worst_violation": chosen.worst_violation,
            "starts": [{"start": r.outcome.start, "return_status": r.outcome.return_status,
                        "iterations": r.outcome.iterations, "wall_s": r.outcome.wall_s,
                        "objective": objective_value(nlp, r),
                        "satisfied_on_fine_grid": r.satisfied, "worst_violation": r.worst_violation,
                        "design": r.outcome.design} for r in ordered],
            "elastic": None if elastic is None else elastic.to_json(),
        },
    )
    return result, ordered, log


def elastic_diagnosis(spec, optimised, design: dict[str, float]) -> ElasticDiagnosis:
    """Re-solve from ``design`` with one elastic slack per rule: the rules whose slack stays > 0 conflict."""
    nlp = build_nlp(spec, optimised, elastic=True)
    out = nlp.solve(0, np.array([design[n] for n in nlp.names]))
    scales = {r.name: r.scale for r in nlp.rules}
    return ElasticDiagnosis(out.return_status, out.success,
                            {n: s * scales[n] for n, s in nlp.slack_values(out.x).items()},
                            {r.name: r.unit for r in nlp.rules}, scales)


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error of a run where no start satisfied every rule (status infeasible or failed)."""
    return unsatisfied_error(result, reports, ElasticDiagnosis.from_json(result.extra["elastic"]),
                             samples_hint="[solver] samples_per_segment or [solver] backoff",
                             relax_hint="Try wider bounds on the design variables, looser limits on those rules, "
                                        "or another motion law.")


def baseline_rules(loaded: LoadedSpec) -> list[dict] | None:
    """The rule table of the spec's given design (start values), for the side-by-side table."""
    spec = loaded.model
    return [r.to_json() for r in fine_check(spec, spec.design_values(), fit_law(spec))]
