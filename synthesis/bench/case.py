"""One bench case run: its methods timed to the same target, their rows and time ratios (:func:`run_case`).

A run reaches the target when its objective is at most the target *and* every rule holds on the fine re-check
grid.  Each run's *time to target* is the moment it first met the target (:func:`time_to_target`; a method that
goes on past it is not charged for the rest); a row's ``time_to_target_s`` is the median over its runs when every
run reached the target, else null and "target not reached".  The time ratio (method's median time to target / the
reference method's) so compares times to the same target, and exists only when every run of both methods reached
it; otherwise ``time_ratio`` is null and ``time_ratio_note`` says "n/a (target not reached)" and by which methods.
"""

from __future__ import annotations

import math
import statistics
import time
from typing import Callable

# the case and run types are the kind contract's (a kind's bench plug-in builds them without importing the bench)
from synthesis.core.bench_case import BenchCase, MethodRun

__all__ = ["BenchCase", "MethodRun", "NOT_REACHED", "PEERS", "TARGET_NOT_REACHED", "reached", "run_case", "time_ratio",
           "time_to_target"]

#: methods that are not IPOPT: one run per case whatever ``repeats`` says (their budgets bound them)
PEERS = {"slsqp", "differential_evolution", "differential_evolution_equal_budget"}
NOT_REACHED = "n/a (target not reached)"
TARGET_NOT_REACHED = "target not reached"


def _median(values: list[float]) -> float:
    return float(statistics.median(values))


def reached(run: MethodRun, target: float) -> bool:
    """The run ended at or below the target with every rule holding."""
    return run.worst_violation == 0 and math.isfinite(run.objective) and run.objective <= target


def time_to_target(run: MethodRun, target: float) -> float | None:
    """Seconds from the run's start to the first moment its design met the target (objective at or below
    it, every rule on the fine grid), or None when it never did.  A run whose trace holds only designs
    meeting every rule (``trace_satisfied``: the generic multistart and peers) has it at the trace's first
    point at or below the target; another run (a kind's own method stopping at the target) at its end."""
    if not reached(run, target):
        return None
    if run.trace_satisfied:
        hit = next((t for t, f in run.trace if f is not None and math.isfinite(f) and f <= target), None)
        if hit is not None:
            return float(hit)
    return run.wall_s


def time_ratio(row: dict, reference: dict) -> dict:
    """The ratio entry of a method's row against the reference row: the ratio of their median times to
    the target (``time_to_target_s``), a number only when both reached the target in every run."""
    missed = [r["method"] for r in (reference, row) if not all(r["reached_target_runs"])]
    entry = {"problem": row["problem"], "method": row["method"], "reference": reference["method"],
             "objective": row["objective"], "reference_objective": reference["objective"],
             "time_to_target_s": row.get("time_to_target_s"),
             "reference_time_to_target_s": reference.get("time_to_target_s")}
    if missed:
        return entry | {"time_ratio": None, "time_ratio_note": f"{NOT_REACHED} by {', '.join(missed)}"}
    if not reference["time_to_target_s"] > 0:
        return entry | {"time_ratio": None, "time_ratio_note": "n/a (reference time is 0)"}
    return entry | {"time_ratio": row["time_to_target_s"] / reference["time_to_target_s"], "time_ratio_note": None}


def run_case(case: BenchCase, repeats: int, tick: Callable[[str | None], None] = lambda what: None) -> dict:
    """Every method of the case, ``repeats`` times each; the case's rows and ratios.

    ``tick(description)`` announces each run (and the reference solve), ``tick(None)`` ends it.
    """
    best, target = _best_known(case, tick)
    if case.warmup is not None:
        case.warmup()
    runs = _timed_runs(case, repeats, target, tick)
    feasible = {method: min([r.objective for r in rs if r.worst_violation == 0 and math.isfinite(r.objective)],
                            default=math.inf) for method, rs in runs.items()}
    before = best
    best = min([best, *feasible.values()])
    moved = None
    if math.isfinite(best) and (not math.isfinite(target) or best + case.tolerance(best) < target):
        # no best known before, or a timed run found a better design than it: the target is the new best's, every
        # run measured against it (a run that stopped at the old one, short of it, has not reached it)
        if math.isfinite(target):
            moved = {"from": target, "best_known_before": before,
                     "by": sorted(m for m, f in feasible.items() if f == best)}
        target = best + case.tolerance(best)
    rows = [_method_row(case, method, rs, best, target) for method, rs in runs.items()]
    ratios = [time_ratio(r, rows[0]) for r in rows[1:]]
    _ratio_texts(rows, ratios)
    out = {"problem": case.problem, "kind": case.kind, "note": case.note, "best_known": best,
           "target": target, "rows": rows, "ratios": ratios, **({"target_moved": moved} if moved else {})}
    if case.sweep is not None:
        out["sweep"] = case.sweep(tick)
    if case.studies:
        out["studies"] = {}
        for name, study in case.studies.items():
            tick(f"{case.problem}: {name}")
            out["studies"][name] = study()
            tick(None)
    return out


def _best_known(case: BenchCase, tick: Callable[[str | None], None]) -> tuple[float, float]:
    """(best known objective, target) before the timed runs: the case's, its untimed reference solve's, or
    (none known) inf and inf."""
    if callable(case.best_known):
        tick(f"{case.problem}: reference solve")
        best = case.best_known()
        tick(None)
    else:
        best = math.inf if case.best_known is None else case.best_known
    return best, (best + case.tolerance(best) if math.isfinite(best) else math.inf)


def _timed_runs(case: BenchCase, repeats: int, target: float,
                tick: Callable[[str | None], None]) -> dict[str, list[MethodRun]]:
    """Each method's runs, timed (less the bench's own ``excluded_s``)."""
    runs: dict[str, list[MethodRun]] = {method: [] for method in case.methods}
    # round robin (method 1, method 2, ..., method 1, ...): a slow spell of a shared machine spreads
    # over every method instead of landing on one
    for k in range(repeats):
        for method, run in case.methods.items():
            n = 1 if method in case.single_runs else repeats
            if k >= n:
                continue
            tick(f"{case.problem}: {method} {k + 1}/{n}")
            t0 = time.perf_counter()
            out = run(target)
            out.wall_s = time.perf_counter() - t0 - out.excluded_s
            runs[method].append(out)
            tick(None)
    return runs


def _method_row(case: BenchCase, method: str, rs: list[MethodRun], best: float, target: float) -> dict:
    """A method's row: its median run's figures, every run's objective, wall time and time to target."""
    walls = [r.wall_s for r in rs]
    median = _median(walls)
    typical = min(rs, key=lambda r: abs(r.wall_s - median))
    to_target = [time_to_target(r, target) for r in rs]
    every = all(t is not None for t in to_target)
    return {
        "problem": case.problem, "kind": case.kind, "method": method,
        "objective": typical.objective, "objectives": [r.objective for r in rs],
        "objective_gap": typical.objective - best, "best_known": best, "target": target,
        "reached_target": reached(typical, target), "reached_target_runs": [reached(r, target) for r in rs],
        "worst_violation": typical.worst_violation,
        "wall_s": walls, "median_s": median, "trace": typical.trace, "details": typical.details,
        # each run's solver seconds, where the method reports them (the IPOPT methods' details.ipopt_s)
        "ipopt_s_runs": [(r.details or {}).get("ipopt_s") for r in rs],
        # median time to the target over the runs, when every run reached it
        "time_to_target_runs": to_target, "time_to_target_s": _median(to_target) if every else None,
        "time_to_target_text": f"{_median(to_target):.3g}" if every else TARGET_NOT_REACHED,
    }


def _ratio_texts(rows: list[dict], ratios: list[dict]) -> None:
    """What a table prints in each row's "time ratio" column (a method that was not a solve has none)."""
    rows[0]["time_ratio_text"] = "1 (reference)"
    for row, ratio in zip(rows[1:], ratios):
        status = str(row["details"].get("return_status", "")) if isinstance(row["details"], dict) else ""
        if status.startswith("not run"):     # not a solve (e.g. a published design, scored): no time to compare
            ratio.update(time_ratio=None, time_ratio_note=status)
            row["time_ratio_text"] = status
        else:
            row["time_ratio_text"] = (f"{ratio['time_ratio']:.1f}x" if ratio["time_ratio"] is not None
                                      else ratio["time_ratio_note"])
