"""``agrisynth solve`` for kind guide_tube: multistart IPOPT, independent re-check, diagnosis."""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Callable

from constraints import not_evaluated
from synthesis.errors import AgrisynthError, SolverError
from synthesis.guide_tube.check import FINE, design_of, rules_of, scene_facts
from synthesis.guide_tube.drop import SeedlingSticks
from synthesis.guide_tube.nlp import GuideTubeNLP, StartOutcome
from synthesis.guide_tube.scene import GuideTubeScene
from synthesis.multistart import latin_hypercube_starts, run_starts
from synthesis.result import Result
from synthesis.rule_solve import ElasticDiagnosis, status_of, unsatisfied_error
from synthesis.spec import LoadedSpec


def build_nlp(spec, elastic: bool = False) -> GuideTubeNLP:
    return GuideTubeNLP(spec, GuideTubeScene.from_spec(spec), elastic=elastic)


@dataclass
class StartReport:
    outcome: StartOutcome
    satisfied: bool                 # every rule on the fine row-spacing grid, closed form on floats
    worst_violation: float          # largest normalised violation there (0 when satisfied)
    records: list = field(default_factory=list)
    why: str | None = None          # why the design could not be evaluated (sticks, wall above drop point)


def angles_of(design: dict[str, float]) -> dict[str, float]:
    return {k.removeprefix("delta_"): v for k, v in design.items()}


def fine_rules(spec, scene: GuideTubeScene, design: dict[str, float]) -> list:
    """The rules re-evaluated on floats on a 10x finer row-spacing grid, independently of the solver."""
    return rules_of(scene, angles_of(design), scene.spacing_grid(FINE * spec.solver.samples), spec.rules)


def _report(spec, scene: GuideTubeScene, outcome: StartOutcome) -> StartReport:
    try:
        records = [r.record() for r in fine_rules(spec, scene, outcome.design)]
    except AgrisynthError as exc:
        return StartReport(outcome, False, float("inf"), why=str(exc))
    worst = max([0.0] + [-(r.normalised_margin if r.normalised_margin is not None else -1e9)
                         for r in records if not r.satisfied])
    return StartReport(outcome, all(r.satisfied for r in records), worst, records)


def _better(a: StartReport, b: StartReport) -> bool:
    """Feasible first, then smaller objective, then the smaller start index."""
    if a.satisfied != b.satisfied:
        return a.satisfied
    if not a.satisfied:
        return a.worst_violation < b.worst_violation
    fa, fb = a.outcome.objective, b.outcome.objective
    return fa < fb - 1e-12 or (abs(fa - fb) <= 1e-12 and a.outcome.start < b.outcome.start)


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None
              ) -> tuple[Result, list[StartReport], str]:
    """Multistart solve; returns (result, every start's report, IPOPT log)."""
    spec = loaded.model
    starts = spec.solver.starts if starts is None else starts
    seed = spec.solver.seed if seed is None else seed
    nlp = build_nlp(spec)
    scene = nlp.scene
    x_starts = latin_hypercube_starts(nlp.bounds, nlp.init, starts, seed)
    reports: dict[int, StartReport] = {}
    best: list[StartReport] = []

    def done(outcome: StartOutcome) -> None:
        rep = _report(spec, scene, outcome)
        reports[outcome.start] = rep
        if not best or _better(rep, best[0]):
            best[:] = [rep]
        on_start(rep, best[0])

    t0 = time.perf_counter()
    factory = functools.partial(build_nlp, spec) if workers > 1 else (lambda: nlp)
    run_starts(factory, x_starts, workers, done)
    wall = time.perf_counter() - t0
    ordered = [reports[i] for i in range(starts)]
    chosen = best[0]
    if chosen.why is not None:
        # no start gives an evaluable design: report the given design's facts, status infeasible
        design, facts = design_of(spec.given_angles()), {"source": spec.source}
        records = [r.record().to_json() for r in unevaluated_rules(spec, chosen.why)]
    else:
        design = chosen.outcome.design
        records = [r.to_json() for r in chosen.records]
        facts = scene_facts(spec, scene, angles_of(design), FINE * spec.solver.samples)
    if chosen.why is not None:      # no start gives a design the drop model can evaluate: the angles conflict
        elastic, status = None, "infeasible"
    else:
        elastic = None if chosen.satisfied else elastic_diagnosis(spec, design)
        status = status_of(chosen, ordered, elastic)
    log = "\n".join(f"===== start {r.outcome.start}: {r.outcome.return_status}, {r.outcome.iterations} iterations\n"
                    f"{r.outcome.log}" for r in ordered)
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status, design=design, rules=records,
        objective={"name": spec.objective.name, "value": chosen.outcome.objective},
        solver={"name": "ipopt", "return_status": chosen.outcome.return_status,
                "iterations": chosen.outcome.iterations, "wall_s": wall, "starts": starts, "seed": seed,
                "best_start": chosen.outcome.start, "workers": workers, "samples": spec.solver.samples,
                "fine_grid_factor": FINE},
        extra={**facts,
               "baseline_design": design_of(spec.given_angles()),
               "fine_grid_worst_violation": _finite(chosen.worst_violation),
               "starts": [{"start": r.outcome.start, "return_status": r.outcome.return_status,
                           "iterations": r.outcome.iterations, "wall_s": r.outcome.wall_s,
                           "objective": r.outcome.objective, "satisfied_on_fine_grid": r.satisfied,
                           "worst_violation": _finite(r.worst_violation), "why": r.why, "design": r.outcome.design}
                          for r in ordered],
               "elastic": None if elastic is None else elastic.to_json()},
    )
    return result, ordered, log


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


def _finite(x: float) -> float | None:
    """JSON has no infinity: a design that could not be evaluated has no violation figure."""
    return x if math.isfinite(x) else None


def elastic_diagnosis(spec, design: dict[str, float]) -> ElasticDiagnosis:
    """Re-solve from ``design`` with one elastic slack per rule: the rules whose slack stays > 0 conflict."""
    nlp = build_nlp(spec, elastic=True)
    angles = angles_of(design)
    out = nlp.solve(0, [angles[n] for n in nlp.names])
    scales = {r.name: r.scale for r in nlp.rules}
    return ElasticDiagnosis(out.return_status, out.success,
                            {n: s * scales[n] for n, s in nlp.slack_values(out.x).items()},
                            {r.name: r.unit for r in nlp.rules}, scales)


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error of a run where no start satisfied every rule (status infeasible or failed)."""
    if result.extra.get("elastic") is None:
        # no start gives a design the drop model can evaluate: say why (sticking first)
        best = min(reports, key=lambda r: r.worst_violation)
        sticking = next((r.why for r in reports if r.why and "sticks" in r.why), best.why)
        statuses = sorted({r.outcome.return_status for r in reports})
        return SolverError(f"no start gives a design the drop model can evaluate ({len(reports)} starts; IPOPT "
                           f"said: {', '.join(statuses)}): {sticking}")
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
