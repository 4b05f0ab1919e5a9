"""Multistart driver shared by the crank_rocker and picker kinds: every start re-checked independently.

Each start's design is re-evaluated by the kind's own ``recheck`` (float kinematics, root-found
extremes, a grid 10x finer than the solver's samples), never by the NLP's constraint values; the
best start is the feasible one with the best objective, else the least violating one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from synthesis.errors import AgrisynthError, SolverError
from synthesis.multistart import run_starts

#: the fine re-check grid is this many times finer than the solver's samples (DESIGN.md)
FINE = 10


@dataclass
class StartReport:
    outcome: Any                     # the kind's StartOutcome (start, design, objective, return_status, ...)
    satisfied: bool                  # every rule holds on the fine grid
    worst_violation: float           # largest normalised violation on the fine grid (0 when satisfied;
                                     # math.inf when a rule cannot be evaluated: see :func:`measured`)
    records: list = field(default_factory=list)     # RuleRecord per rule
    context: Any = None              # whatever the kind's recheck wants to keep (scene, motion facts)


def report_of(outcome, recheck: Callable[[dict], tuple[list, Any]]) -> StartReport:
    """Re-evaluate ``outcome.design`` with ``recheck(design) -> (rules, context)``."""
    try:
        rules, context = recheck(outcome.design)
    except (AgrisynthError, ValueError):
        return StartReport(outcome, False, math.inf)
    records = [r.record() for r in rules]
    worst = max([0.0] + [-(r.normalised_margin if r.normalised_margin is not None else -math.inf)
                         for r in records if not r.satisfied])
    return StartReport(outcome, all(r.satisfied for r in records), worst, records, context)


def better(a: StartReport, b: StartReport, maximise: bool) -> bool:
    """Feasible first, then the objective, then the lower start index (deterministic ties)."""
    if a.satisfied != b.satisfied:
        return a.satisfied
    if not a.satisfied:
        return a.worst_violation < b.worst_violation
    fa, fb = a.outcome.objective, b.outcome.objective
    if maximise:
        fa, fb = -fa, -fb
    return fa < fb - 1e-9 * max(1.0, abs(fb)) or (abs(fa - fb) <= 1e-9 * max(1.0, abs(fb))
                                                    and a.outcome.start < b.outcome.start)


def multistart(factory: Callable[[], Any], x_starts: np.ndarray, workers: int,
               recheck: Callable[[dict], tuple[list, Any]], maximise: bool,
               on_start: Callable[[StartReport, StartReport], None]) -> tuple[list[StartReport], StartReport]:
    """Run every start (solver built once per worker by ``factory``); returns (reports in order, best)."""
    reports: dict[int, StartReport] = {}
    best: list[StartReport] = []

    def done(outcome) -> None:
        rep = report_of(outcome, recheck)
        reports[outcome.start] = rep
        if not best or better(rep, best[0], maximise):
            best[:] = [rep]
        on_start(rep, best[0])

    run_starts(factory, x_starts, workers, done)
    return [reports[i] for i in range(len(x_starts))], best[0]


def measured(x: float) -> float | None:
    """A figure for result.json: JSON has no infinity, and a violation (or objective) that could not be
    measured, because the design cannot be evaluated, is written as null rather than as a number."""
    return x if math.isfinite(x) else None


def starts_table(reports: list[StartReport]) -> list[dict]:
    return [{"start": r.outcome.start, "return_status": r.outcome.return_status, "iterations": r.outcome.iterations,
             "wall_s": r.outcome.wall_s, "objective": measured(r.outcome.objective),
             "satisfied_on_fine_grid": r.satisfied, "worst_violation": measured(r.worst_violation),
             "design": r.outcome.design} for r in reports]


def ipopt_log(reports: list[StartReport]) -> str:
    return "\n".join(f"===== start {r.outcome.start}: {r.outcome.return_status}, {r.outcome.iterations} iterations\n"
                     f"{r.outcome.log}" for r in reports)


def infeasible_error(slacks: dict[str, float], units: dict[str, str], binding: list[str], elastic_status: str,
                     reports: list[StartReport], violated: list[str]) -> SolverError:
    """The exit-3 message: the rules an elastic re-solve must relax (by how much, largest first), the
    rules holding them back (non-zero multipliers there) and IPOPT's words."""
    statuses = ", ".join(sorted({r.outcome.return_status for r in reports}))
    short = [n for n, s in sorted(slacks.items(), key=lambda kv: -kv[1]) if s > 1e-6]
    if not short:
        return SolverError(
            f"no start satisfies every rule on the 10x finer check grid ({len(reports)} starts; IPOPT said: "
            f"{statuses}), though an elastic re-solve needs no slack. Violated: {', '.join(violated)}. "
            f"Try more --starts or more [solver] samples.")
    relaxed = ", ".join(f"{n} (misses its limit by {slacks[n]:.3g} {units[n]})" for n in short)
    holding = [n for n in binding if n not in short]
    against = f"; it conflicts with {', '.join(holding)} (binding there)" if holding else ""
    return SolverError(
        f"no start satisfies every rule ({len(reports)} starts; IPOPT said: {statuses}). "
        f"The smallest relaxation (elastic re-solve, {elastic_status}) gives up on: {relaxed}{against}. "
        f"Loosen those requirements or widen the bounds of the design variables.")
