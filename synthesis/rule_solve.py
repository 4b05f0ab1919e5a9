"""Multistart driver shared by the crank_rocker, picker, clamp_cam and guide_tube kinds: every start
re-checked independently, one verdict (status) and one exit-3 diagnosis.

Each start's design is re-evaluated by the kind's own ``recheck`` (float kinematics, root-found
extremes, a grid 10x finer than the solver's samples), never by the NLP's constraint values; the
best start is the feasible one with the best objective, else the least violating one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import functools
import time

import numpy as np

from synthesis.errors import AgrisynthError, SolverError
from synthesis.ipopt_log import reached_optimum
from synthesis.multistart import best_in_start_order, latin_hypercube_starts, run_starts

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
    why: str | None = None           # why the design could not be evaluated at all


def report_of(outcome, recheck: Callable[[dict], tuple[list, Any]]) -> StartReport:
    """Re-evaluate ``outcome.design`` with ``recheck(design) -> (rules, context)``; a design it cannot
    evaluate (AgrisynthError, ValueError) gets an infinite violation and the reason."""
    try:
        rules, context = recheck(outcome.design)
    except (AgrisynthError, ValueError) as exc:
        return StartReport(outcome, False, math.inf, why=str(exc))
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
               on_start: Callable[[StartReport, StartReport], None],
               scheduler: str | None = None) -> tuple[list[StartReport], StartReport]:
    """Run every start (solver built once per worker by ``factory``); returns (reports in order, best)."""
    reports: dict[int, StartReport] = {}
    best: list[StartReport] = []

    def done(outcome) -> None:
        rep = report_of(outcome, recheck)
        reports[outcome.start] = rep
        if not best or better(rep, best[0], maximise):
            best[:] = [rep]
        on_start(rep, best[0])

    run_starts(factory, x_starts, workers, done, scheduler=scheduler)
    ordered = [reports[i] for i in range(len(x_starts))]
    return ordered, best_in_start_order(ordered, lambda a, b: better(a, b, maximise))


@dataclass
class Run:
    """A finished multistart: the problem as built in this process, every start's report, the best one."""

    nlp: Any                         # the kind's NLP (bounds, init, ...) built once here
    reports: list[StartReport]
    best: StartReport
    starts: int
    seed: int
    workers: int
    wall_s: float
    scheduler: str | None = None     # the dask scheduler the starts ran on, if not local workers

    def solver_record(self, **more) -> dict:
        """result.json ``solver`` (DESIGN.md keys) plus the kind's own settings."""
        o = self.best.outcome
        return {"name": "ipopt", "return_status": o.return_status, "iterations": o.iterations,
                "wall_s": self.wall_s, "starts": self.starts, "seed": self.seed, "best_start": o.start,
                "workers": None if self.scheduler else self.workers, "scheduler": self.scheduler,
                **more, "fine_grid_factor": FINE}


def run_multistart(build: Callable[..., Any], spec, recheck: Callable[[dict], tuple[list, Any]], *,
                   starts: int | None, seed: int | None, workers: int, maximise: bool = False,
                   on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
                   build_args: tuple = (), scheduler: str | None = None) -> Run:
    """Solve from ``starts`` Latin-hypercube starts (start 0 = the spec's design; default counts from
    ``spec.solver``).  ``build(spec, *build_args)`` builds the NLP (with ``bounds`` and ``init``); it is
    built once here and, with several workers, once in each worker (it must be picklable).
    ``scheduler``: a dask.distributed address to run the starts on instead of local workers."""
    starts = spec.solver.starts if starts is None else starts
    seed = spec.solver.seed if seed is None else seed
    nlp = build(spec, *build_args)
    x_starts = latin_hypercube_starts(nlp.bounds, nlp.init, starts, seed)
    local = workers <= 1 and scheduler is None
    factory = (lambda: nlp) if local else functools.partial(build, spec, *build_args)
    t0 = time.perf_counter()
    reports, best = multistart(factory, x_starts, workers, recheck, maximise, on_start, scheduler)
    return Run(nlp, reports, best, starts, seed, workers, time.perf_counter() - t0, scheduler)


def measured(x: float) -> float | None:
    """A figure for result.json: JSON has no infinity, and a violation (or objective) that could not be
    measured, because the design cannot be evaluated, is written as null rather than as a number."""
    return x if math.isfinite(x) else None


def starts_table(reports: list[StartReport], objective: Callable[[StartReport], float] | None = None) -> list[dict]:
    """result.json ``starts``: one row per start; ``objective(report)`` in report units (default the outcome's)."""
    value = objective or (lambda r: r.outcome.objective)
    return [{"start": r.outcome.start, "return_status": r.outcome.return_status, "iterations": r.outcome.iterations,
             "wall_s": r.outcome.wall_s, "objective": measured(value(r)),
             "satisfied_on_fine_grid": r.satisfied, "worst_violation": measured(r.worst_violation),
             "why": r.why, "design": r.outcome.design} for r in reports]


def ipopt_log(reports: list[StartReport]) -> str:
    return "\n".join(f"===== start {r.outcome.start}: {r.outcome.return_status}, {r.outcome.iterations} iterations\n"
                     f"{r.outcome.log}" for r in reports)


@dataclass
class ElasticDiagnosis:
    """What an elastic re-solve (one slack per rule, minimise their sum) says about a rule set."""

    return_status: str
    converged: bool
    slacks: dict[str, float]        # rule -> how far it must be relaxed, in the rule's unit
    units: dict[str, str]
    scales: dict[str, float]        # rule -> its typical margin (a slack counts above tol x scale)
    binding: list[str] = field(default_factory=list)   # rules with a non-zero multiplier there
    tol: float = 1e-6

    @property
    def relaxed(self) -> list[str]:
        """The rules the relaxation gives up on, largest slack first (none unless it converged)."""
        if not self.converged:
            return []
        return [n for n, s in sorted(self.slacks.items(), key=lambda kv: -kv[1] / self.scales[kv[0]])
                if s > self.tol * self.scales[n]]

    def to_json(self) -> dict:
        return {"return_status": self.return_status, "converged": self.converged,
                "slacks": {n: measured(s) for n, s in self.slacks.items()}, "units": self.units,
                "scales": self.scales, "binding": self.binding, "relaxed": self.relaxed}

    @classmethod
    def from_json(cls, data: dict) -> "ElasticDiagnosis":
        slacks = {n: math.inf if s is None else s for n, s in data["slacks"].items()}
        return cls(data["return_status"], data["converged"], slacks, data["units"], data["scales"],
                   data.get("binding", []))


def diagnosis_of(nlp, out) -> ElasticDiagnosis:
    """The diagnosis of an elastic :class:`synthesis.rule_nlp.RuleNLP` solved to ``out``."""
    return ElasticDiagnosis(out.return_status, out.success, nlp.slack_values(out.x),
                            {r.name: r.unit for r in nlp.rules}, {r.name: r.scale for r in nlp.rules},
                            nlp.active_rules(out))


def status_of(best: StartReport, reports: list[StartReport], elastic: ElasticDiagnosis | None) -> str:
    """DESIGN.md status of a multistart run.

    optimal/feasible: the best start satisfies every rule (and IPOPT met its full tolerances there, or not);
    infeasible: no start does, and the elastic re-solve must relax a rule, or some start converged
    to a design that misses the fine grid between the solver's samples;
    failed: no start converged and the elastic re-solve needs no slack (or did not converge either):
    nothing says the rules conflict, IPOPT just found no solution.
    """
    if best.satisfied:
        return "optimal" if reached_optimum(best.outcome.return_status) else "feasible"
    if elastic is not None and elastic.relaxed:
        return "infeasible"
    return "infeasible" if any(r.outcome.success for r in reports) else "failed"


def said(reports: list[StartReport]) -> str:
    """IPOPT's return statuses over the starts, most frequent first: "Maximum_Iterations_Exceeded x5, ..."."""
    counts: dict[str, int] = {}
    for r in reports:
        counts[r.outcome.return_status] = counts.get(r.outcome.return_status, 0) + 1
    return ", ".join(f"{s} x{n}" if n > 1 else s for s, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))


def unsatisfied_error(result, reports: list[StartReport], elastic: ElasticDiagnosis, *, samples_hint: str,
                      relax_hint: str = "Loosen those requirements or widen the bounds of the design variables.",
                      max_iter_hint: str = "[solver] max_iter") -> SolverError:
    """The exit-3 message of a run where no start satisfies every rule (status infeasible or failed).

    Names the rules an elastic re-solve must relax (by how much, largest first) and those holding them
    back (binding there), or says that nothing conflicts: IPOPT's words and what to try either way.
    """
    n = len(reports)
    violated = ", ".join(r["name"] for r in result.rules if not r["satisfied"]) or "none evaluated"
    relaxed = elastic.relaxed
    if relaxed:
        gives_up = ", ".join(f"{name} (misses its limit by {elastic.slacks[name]:.3g} {elastic.units[name]})"
                             for name in relaxed)
        holding = [name for name in elastic.binding if name not in relaxed]
        against = f"; they conflict with {', '.join(holding)} (binding there)" if holding else ""
        return SolverError(
            f"no start satisfies every rule ({n} starts; IPOPT said: {said(reports)}). Rules that conflict "
            f"(the smallest relaxation, an elastic re-solve ({elastic.return_status}), gives up on them, largest "
            f"first): {gives_up}{against}. {relax_hint}")
    if result.status == "failed":
        why = ("and an elastic re-solve needs no slack, so the rules do not conflict" if elastic.converged else
               f"and an elastic re-solve did not converge either ({elastic.return_status}), so nothing is known "
               f"about conflicts")
        return SolverError(
            f"IPOPT found no solution: it converged from none of the {n} starts (IPOPT said: {said(reports)}), "
            f"{why}. Violated at the best start: {violated}. This is a solver failure, not an infeasible rule "
            f"set: try more --starts, a higher {max_iter_hint}, or a given design (start 0) nearer one that "
            f"meets the rules.")
    return SolverError(
        f"no start satisfies every rule on the 10x finer check grid ({n} starts; IPOPT said: {said(reports)}), "
        f"though an elastic re-solve needs no slack: the rules hold at the solver's samples. Violated between "
        f"samples: {violated}. Raise {samples_hint}, or try more --starts.")
