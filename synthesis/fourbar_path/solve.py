"""``agrisynth solve`` for kind fourbar_path: multistart IPOPT, independent re-check, diagnosis.

Every start's design is re-checked by synthesis.fourbar_path.check (its own kinematics, a 0.1 deg
grid over the turn).  The best start is the feasible one with the smallest objective (ties: the
lower start index).  With [solver] stop_at_objective the multistart ends at the first start, in
start order, that satisfies every rule with an objective at or below it (the same start for any
number of workers); the result reports how many starts were run and needed.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from synthesis.errors import SolverError
from synthesis.fourbar_path.check import Evaluation, evaluate, path_facts, result_design, trajectory
from synthesis.fourbar_path.nlp import PathNLP, StartOutcome
from synthesis.fourbar_path.starts import grashof_anchor
from synthesis.ipopt_log import reached_optimum
from synthesis.multistart import best_in_start_order, latin_hypercube_starts, run_starts
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.spec.fourbar_path import FourbarPathSpec

OBJECTIVE = "sum_squared_distance"
#: a start "reaches the best" when its objective is within this of the best one (mm^2, relative)
SAME_OPTIMUM = (1e-9, 1e-6)


def build_nlp(spec: FourbarPathSpec, seed: int = 0, elastic: bool = False) -> PathNLP:
    return PathNLP(spec, seed=seed, elastic=elastic)


@dataclass
class StartReport:
    outcome: StartOutcome
    satisfied: bool                  # every rule on the re-check grid
    worst_violation: float           # largest normalised violation there (0 when satisfied)
    records: list = field(default_factory=list)
    evaluation: Evaluation | None = None


def recheck(spec: FourbarPathSpec, outcome: StartOutcome) -> StartReport:
    """Evaluate a start's design independently of the solver (check.evaluate)."""
    ev = evaluate(spec, outcome.design, outcome.crank_deg, timing="solved")
    records = [r.record() for r in ev.rules]
    closes = bool(np.all(np.isfinite(ev.errors_mm)))
    worst = max([0.0] + [-(r.normalised_margin if r.normalised_margin is not None else -math.inf)
                         for r in records if not r.satisfied])
    ok = closes and math.isfinite(outcome.objective) and all(r.satisfied for r in records)
    return StartReport(outcome, ok, worst if closes else math.inf, records, ev)


def better(a: StartReport, b: StartReport) -> bool:
    """Is a better than b: feasible first, then objective, then the lower start index."""
    if a.satisfied != b.satisfied:
        return a.satisfied
    if not a.satisfied:
        return (a.worst_violation, a.outcome.start) < (b.worst_violation, b.outcome.start)
    fa, fb = a.outcome.objective, b.outcome.objective
    return fa < fb or (fa == fb and a.outcome.start < b.outcome.start)


def reaches(best: float, objective: float) -> bool:
    abs_tol, rel_tol = SAME_OPTIMUM
    return objective <= best + max(abs_tol, rel_tol * abs(best))


def run_solve(loaded: LoadedSpec, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
              scheduler: str | None = None) -> tuple[Result, list[StartReport], str]:
    """Multistart solve; returns (result, the report of every start run, IPOPT log).

    ``scheduler``: a dask.distributed scheduler address to run the starts on instead of local workers.
    """
    spec: FourbarPathSpec = loaded.model
    starts = spec.solver.starts if starts is None else starts
    seed = spec.solver.seed if seed is None else seed
    target = spec.solver.stop_at_objective
    nlp = build_nlp(spec, seed)          # also validates the build before any worker starts
    x_starts = latin_hypercube_starts(nlp.bounds, nlp.init, starts, seed)
    reports: dict[int, StartReport] = {}
    best: list[StartReport] = []

    def done(outcome: StartOutcome) -> None:
        rep = recheck(spec, outcome)
        reports[outcome.start] = rep
        if not best or better(rep, best[0]):
            best[:] = [rep]
        on_start(rep, best[0])

    def good_enough(outcome: StartOutcome) -> bool:
        rep = reports[outcome.start]
        return rep.satisfied and outcome.objective <= target

    t0 = time.perf_counter()
    local = workers <= 1 and scheduler is None
    factory = (lambda: nlp) if local else functools.partial(build_nlp, spec, seed)
    outcomes = run_starts(factory, x_starts, workers, done, stop_when=None if target is None else good_enough,
                          scheduler=scheduler)
    wall = time.perf_counter() - t0
    ordered = [reports[o.start] for o in outcomes]     # the starts that count (early stop: 0..k)
    chosen = best_in_start_order(ordered, better)
    out = chosen.outcome
    feasible = chosen.satisfied
    status = ("optimal" if reached_optimum(out.return_status) else "feasible") if feasible else "infeasible"
    needed = next((r.outcome.start + 1 for r in ordered
                   if r.satisfied and reaches(out.objective, r.outcome.objective)), None) if feasible else None
    at_best = sum(1 for r in ordered if r.satisfied and reaches(out.objective, r.outcome.objective)) if feasible else 0
    ev = chosen.evaluation
    log = "\n".join(f"===== start {r.outcome.start}: {r.outcome.return_status}, {r.outcome.iterations} iterations\n"
                    f"{r.outcome.log}" for r in ordered)
    result = Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status,
        design=result_design(out.design, out.crank_deg, spec), rules=[r.to_json() for r in chosen.records],
        objective={"name": OBJECTIVE, "value": _finite(out.objective), "unit": "mm^2"},
        trajectory=trajectory(spec, out.design, out.crank_deg, -1.0 if out.direction == "cw" else 1.0),
        solver={"name": "ipopt", "return_status": out.return_status, "iterations": out.iterations,
                "wall_s": wall, "starts": starts, "seed": seed, "best_start": out.start,
                "workers": workers if scheduler is None else None, "scheduler": scheduler,
                "starts_run": len(ordered), "starts_needed": needed, "starts_reaching_best": at_best,
                "stop_at_objective": target, "stopped_early": len(ordered) < starts},
        extra={
            **path_facts(spec, ev),
            "crank_direction": out.direction,
            "baseline_design": spec.design_values(),
            "fine_grid_worst_violation": _finite(chosen.worst_violation),
            "starts": [{"start": r.outcome.start, "return_status": r.outcome.return_status,
                        "iterations": r.outcome.iterations, "wall_s": r.outcome.wall_s,
                        "objective": _finite(r.outcome.objective),
                        "satisfied_on_fine_grid": r.satisfied,
                        "worst_violation": _finite(r.worst_violation),
                        "direction": r.outcome.direction} for r in ordered],
        },
    )
    return result, ordered, log


def _finite(x: float) -> float | None:
    """JSON has no infinity: a start that failed reports null."""
    return x if math.isfinite(x) else None


def conflicting_rules(spec: FourbarPathSpec, design: dict, seed: int) -> tuple[list[str], str]:
    """Re-solve with one elastic slack per rule; the rules whose slack stays > 0 conflict."""
    nlp = build_nlp(spec, seed, elastic=True)
    out = nlp.solve(0, np.array([design[n] for n in nlp.names]))
    slacks = nlp.slack_values(out.x)
    return [n for n, s in sorted(slacks.items(), key=lambda kv: -kv[1]) if s > 1e-6], out.return_status


def diagnose_infeasible(loaded: LoadedSpec, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error for a run where no start satisfied every rule."""
    spec: FourbarPathSpec = loaded.model
    statuses = ", ".join(sorted({r.outcome.return_status for r in reports}))
    anchor = grashof_anchor(np.array(spec.bounds_array(), dtype=float), spec.rules.grashof)
    if anchor is not None and anchor[1] < 0:
        return SolverError(
            f"no start satisfies every rule ({len(reports)} starts; IPOPT said: {statuses}). Rule grashof: no "
            f"{spec.rules.grashof} fits in bounds r1..r4 (the best smallest Grashof slack there is "
            f"{anchor[1]:.3g} mm); widen the bounds of r1..r4 or choose another [rules] grashof.")
    names, status = conflicting_rules(spec, {k: result.design[k] for k in spec.design_values()}, result.solver["seed"])
    violated = ", ".join(r["name"] for r in result.violated()) or "none"
    if not names:
        return SolverError(
            f"no start satisfies every rule on the re-check grid ({len(reports)} starts; IPOPT said: {statuses}); "
            f"violated there: {violated}. The elastic re-solve needs no slack, so more --starts may find one.")
    return SolverError(
        f"no start satisfies every rule ({len(reports)} starts; IPOPT said: {statuses}). Rules that conflict "
        f"(non-zero elastic slack, largest first): {', '.join(names)} (elastic re-solve: {status}). "
        f"Widen the bounds or loosen those rules.")


def baseline_rules(loaded: LoadedSpec) -> list[dict] | None:
    """The rule table of the spec's given design, for the side-by-side table."""
    spec: FourbarPathSpec = loaded.model
    ev = evaluate(spec, spec.design_values(), spec.design.crank_deg)
    return [r.record().to_json() for r in ev.rules]
