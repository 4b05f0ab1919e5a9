"""``agrisynth solve`` for kind planting_fourbar: multistart IPOPT, fine-grid re-check, diagnosis."""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from synthesis.errors import AgrisynthError, SolverError
from synthesis.ipopt_log import reached_optimum
from synthesis.multistart import best_in_start_order, latin_hypercube_starts, run_starts
from synthesis.planting.check import evaluate, scene_facts, trajectory
from synthesis.planting.nlp import PlantingNLP, StartOutcome
from synthesis.planting.scene import PlantingScene
from synthesis.result import Result
from synthesis.spec import LoadedSpec

#: the fine re-check grid is this many times finer than the solver's samples (DESIGN.md)
FINE = 10


def build_nlp(spec, elastic: bool = False) -> PlantingNLP:
    return PlantingNLP(spec, elastic=elastic)


@dataclass
class StartReport:
    outcome: StartOutcome
    satisfied: bool                 # every rule on the fine grid
    worst_violation: float          # largest normalised violation on the fine grid (0 when satisfied)
    records: list = field(default_factory=list)     # RuleRecord per rule, fine grid
    scene: PlantingScene | None = None               # None when the design does not assemble
    points: object = None


def fine_check(spec, design: dict[str, float]) -> tuple[list, object, PlantingScene]:
    """Evaluate a design independently of the solver: root-found precision points, 10x finer grids."""
    scene = PlantingScene.from_spec(spec, design)
    rules, pts = evaluate(scene, spec.rules, phase_samples=FINE * spec.solver.samples_per_phase,
                          turn_samples=FINE * spec.solver.samples_per_turn)
    return rules, pts, scene


def _report(spec, outcome: StartOutcome) -> StartReport:
    try:
        rules, pts, scene = fine_check(spec, outcome.design)
    except AgrisynthError:
        return StartReport(outcome, False, float("inf"))
    records = [r.record() for r in rules]
    worst = max([0.0] + [-(r.normalised_margin if r.normalised_margin is not None else -1e9)
                         for r in records if not r.satisfied])
    return StartReport(outcome, all(r.satisfied for r in records), worst, records, scene, pts)


def _better(spec, a: StartReport, b: StartReport) -> bool:
    """Is a better than b: feasible first, then objective (robust maximises), then start index."""
    if a.satisfied != b.satisfied:
        return a.satisfied
    if not a.satisfied:
        return a.worst_violation < b.worst_violation
    fa, fb = a.outcome.objective, b.outcome.objective
    if spec.objective.name == "robust":
        fa, fb = -fa, -fb
    return fa < fb - 1e-12 or (abs(fa - fb) <= 1e-12 and a.outcome.start < b.outcome.start)


def conflicting_rules(spec, design: dict[str, float]) -> tuple[list[str], str]:
    """Re-solve with one elastic slack per rule; the rules whose slack stays > 0 conflict."""
    nlp = build_nlp(spec, elastic=True)
    x0 = np.array([design[n] for n in nlp.names])
    out = nlp.solve(0, x0)
    slacks = nlp.slack_values(out.x)
    names = [n for n, s in sorted(slacks.items(), key=lambda kv: -kv[1]) if s > 1e-5]
    return names, out.return_status


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
              scheduler: str | None = None) -> tuple[Result, list[StartReport], str]:
    """Multistart solve; returns (result, every start's report, IPOPT log).

    ``scheduler``: a dask.distributed scheduler address to run the starts on instead of local workers.
    """
    spec = loaded.model
    starts = spec.solver.starts if starts is None else starts
    seed = spec.solver.seed if seed is None else seed
    nlp_shape = build_nlp(spec)          # also validates the build before spawning workers
    x_starts = latin_hypercube_starts(nlp_shape.bounds, nlp_shape.init, starts, seed)
    reports: dict[int, StartReport] = {}
    best: list[StartReport] = []

    def done(outcome: StartOutcome) -> None:
        rep = _report(spec, outcome)
        reports[outcome.start] = rep
        if not best or _better(spec, rep, best[0]):
            best[:] = [rep]
        on_start(rep, best[0])

    t0 = time.perf_counter()
    factory = functools.partial(build_nlp, spec)
    if workers <= 1 and scheduler is None:
        factory = lambda: nlp_shape  # noqa: E731 - reuse the solver already built
    run_starts(factory, x_starts, workers, done, scheduler=scheduler)
    wall = time.perf_counter() - t0
    ordered = [reports[i] for i in range(starts)]
    chosen = best_in_start_order(ordered, functools.partial(_better, spec))
    if chosen.scene is None:    # no start assembles: re-evaluate to raise the AssemblyError (exit 2)
        fine_check(spec, chosen.outcome.design)
    pts, scene = chosen.points, chosen.scene
    records = [r.to_json() for r in chosen.records]
    feasible = chosen.satisfied
    if feasible:
        status = "optimal" if reached_optimum(chosen.outcome.return_status) else "feasible"
    else:   # IPOPT neither converged nor proved infeasibility from any start: a failure, not a conflict
        evidence = any(r.outcome.success or r.outcome.return_status == "Infeasible_Problem_Detected"
                       for r in reports.values())
        status = "infeasible" if evidence else "failed"
    objective_value = nlp_shape.objective_value(chosen.outcome.design, chosen.outcome.objective)
    design = dict(chosen.outcome.design)
    design["branch"] = spec.arm.branch
    log = "\n".join(f"===== start {r.outcome.start}: {r.outcome.return_status}, {r.outcome.iterations} iterations\n"
                    f"{r.outcome.log}" for r in ordered)
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status, design=design, rules=records,
        objective={"name": spec.objective.name, "value": objective_value},
        trajectory=trajectory(scene, pts),
        solver={"name": "ipopt", "return_status": chosen.outcome.return_status,
                "iterations": chosen.outcome.iterations, "wall_s": wall, "starts": starts, "seed": seed,
                "best_start": chosen.outcome.start, "workers": workers if scheduler is None else None,
                "scheduler": scheduler,
                "samples_per_phase": spec.solver.samples_per_phase,
                "samples_per_turn": spec.solver.samples_per_turn, "fine_grid_factor": FINE},
        extra={
            **scene_facts(spec, scene, pts),
            "baseline_design": spec.design_values(),
            "fine_grid_worst_violation": chosen.worst_violation,
            "starts": [{"start": r.outcome.start, "return_status": r.outcome.return_status,
                        "iterations": r.outcome.iterations, "wall_s": r.outcome.wall_s,
                        "objective": nlp_shape.objective_value(r.outcome.design, r.outcome.objective),
                        "satisfied_on_fine_grid": r.satisfied, "worst_violation": r.worst_violation,
                        "design": r.outcome.design} for r in ordered],
        },
    )
    return result, ordered, log


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error for a run where no start satisfied every rule."""
    spec = loaded.model
    statuses = sorted({r.outcome.return_status for r in reports})
    if result.status == "failed":
        return SolverError(
            f"IPOPT converged from none of the {len(reports)} starts (it said: {', '.join(statuses)}); the best "
            f"design found still violates {', '.join(r['name'] for r in result.violated())}. Try more --starts, "
            f"a larger [solver] max_iter, or a start design ([arm] init values) closer to a feasible one; "
            f"the per-start log is in ipopt.log.")
    names, _ = conflicting_rules(spec, result.design)
    worst = [r["name"] for r in result.violated()]
    if not names:
        return SolverError(
            f"no start satisfies every rule on the 10x finer check grid ({len(reports)} starts; IPOPT said: "
            f"{', '.join(statuses)}), though the rules hold at the solver's samples (the elastic re-solve needs "
            f"no slack). Violated between samples: {', '.join(worst)}. Raise [solver] samples_per_phase / "
            f"samples_per_turn or [solver] backoff.")
    return SolverError(
        f"no start satisfies every rule ({len(reports)} starts; IPOPT said: {', '.join(statuses)}). "
        f"Rules that conflict (non-zero elastic slack, largest first): {', '.join(names)}. "
        f"Try wider bounds on the design variables, looser limits on those rules, or more --starts.")


def baseline_rules(loaded: LoadedSpec) -> list[dict] | None:
    """The rule table of the spec's given design (start values), for the side-by-side table."""
    try:
        rules, _ = evaluate(PlantingScene.from_spec(loaded.model), loaded.model.rules)
    except AgrisynthError:
        return None
    return [r.record().to_json() for r in rules]
