"""``agrisynth solve`` for kind guide_tube: multistart IPOPT, independent re-check, diagnosis."""

from __future__ import annotations

import functools
from typing import Callable

from constraints import not_evaluated
from synthesis.errors import AgrisynthError, SolverError
from synthesis.guide_tube.check import FINE, design_of, rules_of, scene_facts
from synthesis.guide_tube.drop import SeedlingSticks
from synthesis.guide_tube.nlp import OBJECTIVE_UNITS, GuideTubeNLP
from synthesis.guide_tube.scene import GuideTubeScene
from synthesis.result import Result
from synthesis.rule_solve import (ElasticDiagnosis, StartReport, diagnosis_of, ipopt_log, measured, run_multistart,
                                  said, starts_table, status_of, unsatisfied_error)
from synthesis.spec import LoadedSpec


def build_nlp(spec, elastic: bool = False) -> GuideTubeNLP:
    return GuideTubeNLP(spec, GuideTubeScene.from_spec(spec), elastic=elastic)


def angles_of(design: dict[str, float]) -> dict[str, float]:
    return {k.removeprefix("delta_"): v for k, v in design.items()}


def fine_rules(spec, scene: GuideTubeScene, design: dict[str, float]) -> list:
    """The rules re-evaluated on floats on a 10x finer row-spacing grid, independently of the solver."""
    return rules_of(scene, angles_of(design), scene.spacing_grid(FINE * spec.solver.samples), spec.rules)


def recheck(spec, scene: GuideTubeScene, design: dict[str, float]):
    """(rules, None); raises SeedlingSticks / WallAboveDropPoint for a design the drop model cannot evaluate."""
    return fine_rules(spec, scene, design), None


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
              scheduler: str | None = None) -> tuple[Result, list[StartReport], str]:
    """Multistart solve; returns (result, every start's report, IPOPT log)."""
    spec = loaded.model
    scene = GuideTubeScene.from_spec(spec)
    run = run_multistart(build_nlp, spec, functools.partial(recheck, spec, scene), starts=starts, seed=seed,
                         workers=workers, on_start=on_start, scheduler=scheduler)
    chosen, ordered = run.best, run.reports
    if chosen.why is not None:
        # no start gives a design the drop model can evaluate (a seedling sticks at every start's angles):
        # report the given design's facts and the rules as not evaluated; the angle range conflicts
        design, facts = design_of(spec.given_angles()), {"source": spec.source}
        records = [r.record().to_json() for r in unevaluated_rules(spec, chosen.why)]
        elastic, status = None, "infeasible"
    else:
        design = chosen.outcome.design
        records = [r.to_json() for r in chosen.records]
        facts = scene_facts(spec, scene, angles_of(design), FINE * spec.solver.samples)
        elastic = None if chosen.satisfied else elastic_diagnosis(spec, design)
        status = status_of(chosen, ordered, elastic)
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status, design=design, rules=records,
        objective={"name": spec.objective.name, "value": chosen.outcome.objective,
                   "unit": OBJECTIVE_UNITS[spec.objective.name]},
        solver=run.solver_record(samples=spec.solver.samples),
        extra={**facts,
               "baseline_design": design_of(spec.given_angles()),
               "fine_grid_worst_violation": measured(chosen.worst_violation),
               "starts": starts_table(ordered),
               "elastic": None if elastic is None else elastic.to_json()},
    )
    return result, ordered, ipopt_log(ordered)


def unevaluated_rules(spec, why: str) -> list:
    """The rule table of a design the drop model cannot evaluate: every rule, with the reason."""
    r = spec.rules
    where = "row spacings"
    rules = [not_evaluated("landing_time_spread", None, r.max_time_spread, "s", where, why)]
    if r.max_spacing_error is not None:
        rules.append(not_evaluated("spacing_error", None, r.max_spacing_error, "mm", where, why))
    for t in spec.tubes:
        rules.append(not_evaluated(f"wall_exit_speed_{t.name}", r.min_exit_speed, None, "m/s", where, why))
        rules.append(not_evaluated(f"free_fall_height_{t.name}", r.min_free_fall, None, "mm", where, why))
    return rules


def elastic_diagnosis(spec, design: dict[str, float]) -> ElasticDiagnosis:
    """Re-solve from ``design`` with one elastic slack per rule: the rules whose slack stays > 0 conflict."""
    elastic = build_nlp(spec, elastic=True)
    angles = angles_of(design)
    return diagnosis_of(elastic.nlp, elastic.nlp.solve(0, [angles[n] for n in elastic.names]))


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error of a run where no start satisfied every rule (status infeasible or failed)."""
    if result.extra.get("elastic") is None:
        # no start gives a design the drop model can evaluate: say why (sticking first)
        best = min(reports, key=lambda r: r.worst_violation)
        sticking = next((r.why for r in reports if r.why and "sticks" in r.why), best.why)
        return SolverError(f"no start gives a design the drop model can evaluate ({len(reports)} starts; IPOPT "
                           f"said: {said(reports)}): {sticking}")
    return unsatisfied_error(result, reports, ElasticDiagnosis.from_json(result.extra["elastic"]),
                             samples_hint="[solver] samples or [solver] backoff",
                             relax_hint="Try wider bounds on the wall angles, looser limits on those rules, "
                                        "or more --starts.")


def baseline_rules(loaded: LoadedSpec) -> list[dict] | None:
    """The rule table of the spec's given angles, for the side-by-side table."""
    spec = loaded.model
    try:
        scene = GuideTubeScene.from_spec(spec)
        return [r.record().to_json() for r in fine_rules(spec, scene, design_of(spec.given_angles()))]
    except (AgrisynthError, SeedlingSticks):
        return None
