"""``agrisynth bench``: objective reached and wall time of several methods on the same problems.

Generic over problem kinds.  A kind declares a function that turns problems into
:class:`BenchCase` objects (its ``Kind.bench``, see :mod:`synthesis.kinds`); this module runs every method of every case ``repeats``
times, takes the median wall time, and writes ``OUT/bench/bench.json`` and ``error_vs_time.png``
(accuracy -- objective gap to the best known, worst fine-grid rule violation -- against wall time).

Equal objective tolerance: each case has a target objective (best known + tolerance) and every
method stops as soon as it reaches it, or at its own convergence / budget otherwise.  A run reaches
the target when its objective is at most the target *and* every rule holds on the fine re-check
grid.  The time ratio (method's median wall time / the reference method's) compares times to the
same target, so it exists only when every run of both methods reached it; otherwise ``time_ratio``
is null and ``time_ratio_note`` says "n/a (target not reached)" and by which methods.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

FLOOR = 1e-16      # log axes: a gap or violation of 0 is drawn here
NOT_REACHED = "n/a (target not reached)"


@dataclass
class MethodRun:
    """One run of one method on one problem."""

    objective: float                     # objective reached (the problem's units)
    worst_violation: float               # worst normalised rule violation on the fine re-check grid, 0 = none
    trace: list[tuple[float, float]]     # (seconds since the start, best objective so far)
    details: dict = field(default_factory=dict)
    wall_s: float = 0.0                  # filled in by the runner


@dataclass
class BenchCase:
    problem: str
    kind: str
    #: method name -> run(target objective) -> MethodRun; the first is the reference of the ratios
    methods: dict[str, Callable[[float], MethodRun]]
    #: objective of the best known design, or a callable computing it (untimed) when not known
    best_known: float | Callable[[], float]
    tolerance: Callable[[float], float]  # best known -> allowed gap of the target
    note: str = ""


def kinds_with_bench() -> list[str]:
    from synthesis import kinds

    return [k.name for k in kinds.all_kinds() if k.bench is not None]


def cases_for(kind: str, specs, seed: int) -> list[BenchCase]:
    """The kind's bench cases: ``Kind.bench(specs: list[LoadedSpec] | None, seed)``; None = its default set."""
    from synthesis import kinds
    from synthesis.core.kind import resolve

    return resolve(kinds.get(kind).bench)(specs, seed)


def _median(values: list[float]) -> float:
    return float(statistics.median(values))


def reached(run: MethodRun, target: float) -> bool:
    """The run ended at or below the target with every rule holding."""
    return run.worst_violation == 0 and math.isfinite(run.objective) and run.objective <= target


def time_ratio(row: dict, reference: dict) -> dict:
    """The ratio entry of a method's row against the reference row: a number only when both reached
    the target in every run."""
    missed = [r["method"] for r in (reference, row) if not all(r["reached_target_runs"])]
    entry = {"problem": row["problem"], "method": row["method"], "reference": reference["method"],
             "objective": row["objective"], "reference_objective": reference["objective"]}
    if missed:
        return entry | {"time_ratio": None, "time_ratio_note": f"{NOT_REACHED} by {', '.join(missed)}"}
    if reference["median_s"] <= 0:
        return entry | {"time_ratio": None, "time_ratio_note": "n/a (reference time is 0)"}
    return entry | {"time_ratio": row["median_s"] / reference["median_s"], "time_ratio_note": None}


def run_case(case: BenchCase, repeats: int, tick: Callable[[str | None], None] = lambda what: None) -> dict:
    """Every method of the case, ``repeats`` times each; the case's rows and ratios.

    ``tick(description)`` announces each run (and the reference solve), ``tick(None)`` ends it.
    """
    if callable(case.best_known):
        tick(f"{case.problem}: reference solve")
        best = case.best_known()
        tick(None)
    else:
        best = case.best_known
    target = best + case.tolerance(best)
    runs: dict[str, list[MethodRun]] = {}
    for method, run in case.methods.items():
        runs[method] = []
        for k in range(repeats):
            tick(f"{case.problem}: {method} {k + 1}/{repeats}")
            t0 = time.perf_counter()
            out = run(target)
            out.wall_s = time.perf_counter() - t0
            runs[method].append(out)
            tick(None)
    feasible = [r.objective for rs in runs.values() for r in rs
                if r.worst_violation == 0 and math.isfinite(r.objective)]
    best = min([best] + feasible)
    rows = []
    for method, rs in runs.items():
        walls = [r.wall_s for r in rs]
        median = _median(walls)
        typical = min(rs, key=lambda r: abs(r.wall_s - median))
        rows.append({
            "problem": case.problem, "kind": case.kind, "method": method,
            "objective": typical.objective, "objectives": [r.objective for r in rs],
            "objective_gap": typical.objective - best, "best_known": best, "target": target,
            "reached_target": reached(typical, target), "reached_target_runs": [reached(r, target) for r in rs],
            "worst_violation": typical.worst_violation,
            "wall_s": walls, "median_s": median, "trace": typical.trace, "details": typical.details,
        })
    ratios = [time_ratio(r, rows[0]) for r in rows[1:]]
    # what a table prints in its "time ratio" column
    rows[0]["time_ratio_text"] = "1 (reference)"
    for row, ratio in zip(rows[1:], ratios):
        row["time_ratio_text"] = (f"{ratio['time_ratio']:.1f}x" if ratio["time_ratio"] is not None
                                  else ratio["time_ratio_note"])
    return {"problem": case.problem, "kind": case.kind, "note": case.note, "best_known": best,
            "target": target, "rows": rows, "ratios": ratios}


def write_bench(out: Path, results: list[dict], settings: dict) -> Path:
    """OUT/bench/bench.json and error_vs_time.png, each written to a temporary file and renamed."""
    from synthesis.result import atomic_write_text, versions

    folder = out / "bench"
    folder.mkdir(parents=True, exist_ok=True)
    rows = [row for res in results for row in res["rows"]]
    data = {"settings": settings, "versions": versions(), "problems": [
        {k: v for k, v in res.items() if k != "rows"} for res in results], "rows": rows}
    fd, tmp = tempfile.mkstemp(prefix=".error_vs_time.", suffix=".png", dir=folder)
    os.close(fd)
    try:
        plot_error_vs_time(results, Path(tmp))
        os.replace(tmp, folder / "error_vs_time.png")
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    atomic_write_text(folder / "bench.json", json.dumps(_json_safe(data), indent=1) + "\n")
    return folder


def _json_safe(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    return x


def plot_error_vs_time(results: list[dict], path: Path) -> None:
    """Log-log: objective gap and worst violation against wall time, per problem (colour) and method
    (marker); every repeat a point, the median run's best-so-far trace a line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    markers = ["o", "s", "^", "D", "v"]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    methods = list(dict.fromkeys(row["method"] for res in results for row in res["rows"]))
    fig, (ax_gap, ax_vio) = plt.subplots(1, 2, figsize=(13, 5.5))
    for p, res in enumerate(results):
        colour = colours[p % len(colours)]
        for row in res["rows"]:
            m = markers[methods.index(row["method"]) % len(markers)]
            gaps = [max(o - res["best_known"], FLOOR) if o is not None and math.isfinite(o) else math.nan
                    for o in row["objectives"]]
            ax_gap.plot(row["wall_s"], gaps, m, color=colour, ms=6, mfc="none" if m != "o" else colour, alpha=0.8)
            trace = [(t, max(f - res["best_known"], FLOOR)) for t, f in row["trace"]
                     if f is not None and math.isfinite(f)]
            if trace:
                ax_gap.plot(*zip(*trace), "-" if methods.index(row["method"]) == 0 else "--", color=colour,
                            lw=0.9, alpha=0.6)
            vio = max(row["worst_violation"], FLOOR) if math.isfinite(row["worst_violation"]) else math.nan
            ax_vio.plot([row["median_s"]], [vio], m, color=colour, ms=7, mfc="none" if m != "o" else colour)
        ax_gap.plot([], [], "-", color=colour, label=res["problem"])
    for k, method in enumerate(methods):
        ax_gap.plot([], [], markers[k % len(markers)], color="0.3", mfc="none" if k else "0.3", label=method)
    for ax, title, ylabel in ((ax_gap, "objective gap to the best known", "objective - best known"),
                              (ax_vio, "worst rule violation (fine re-check grid)", "normalised violation")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time, s")
        ax.set_ylabel(f"{ylabel} (0 drawn at {FLOOR:g})")
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3, which="both")
    ax_gap.legend(fontsize=7, loc="best", ncol=2)
    fig.suptitle("error against run time (points: repeats; lines: best so far in the median run)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
