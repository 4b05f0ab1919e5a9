"""``agrisynth bench``: objective reached and wall time of several methods on the same problems.

Generic over problem kinds.  A kind declares a function that turns problems into
:class:`BenchCase` objects (its ``Kind.bench``, see :mod:`synthesis.kinds`); this module runs every method of every case ``repeats``
times, takes the median wall time, and writes ``OUT/bench/bench.json`` and ``error_vs_time.png``
(accuracy -- objective gap to the best known, worst fine-grid rule violation -- against wall time).

Equal objective tolerance: each case has a target objective (best known + tolerance) and every
method stops as soon as it reaches it, or at its own convergence / budget otherwise.  A run reaches
the target when its objective is at most the target *and* every rule holds on the fine re-check
grid.  Each run's *time to target* is the moment it first met the target (:func:`time_to_target`;
a method that goes on past it is not charged for the rest); a row's ``time_to_target_s`` is the median
over its runs when every run reached the target, else null and "target not reached".  The time ratio
(method's median time to target / the reference method's) so compares times to the same target, and
exists only when every run of both methods reached it; otherwise ``time_ratio`` is null and
``time_ratio_note`` says "n/a (target not reached)" and by which methods.
"""

from __future__ import annotations

import json
import math
import os
import re
import statistics
import time
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

#: methods that are not IPOPT: one run per case whatever ``repeats`` says (their budgets bound them)
PEERS = {"slsqp", "differential_evolution", "differential_evolution_equal_budget"}
FLOOR = 1e-16      # log axes: a gap or violation of 0 is drawn here
NOT_REACHED = "n/a (target not reached)"
TARGET_NOT_REACHED = "target not reached"


@dataclass
class MethodRun:
    """One run of one method on one problem."""

    objective: float                     # objective reached (the problem's units)
    worst_violation: float               # worst normalised rule violation on the fine re-check grid, 0 = none
    trace: list[tuple[float, float]]     # (seconds since the start, best objective so far)
    details: dict = field(default_factory=dict)
    wall_s: float = 0.0                  # filled in by the runner (less ``excluded_s``)
    #: True: ``trace`` holds only designs meeting every rule on the fine grid, its times the method's own, so
    #: its first point at or below a target is the run's time to that target (:func:`time_to_target`);
    #: False: a method that stops at the target itself, whose whole run is its time to target
    trace_satisfied: bool = False
    #: seconds of the run that were the bench's own instrumentation, not the method's (the peers' check of
    #: an iterate against the target): left out of ``wall_s``
    excluded_s: float = 0.0


@dataclass
class BenchCase:
    problem: str
    kind: str
    #: method name -> run(target objective) -> MethodRun; the first is the reference of the ratios
    methods: dict[str, Callable[[float], MethodRun]]
    #: objective of the best known design, or a callable computing it (untimed) when not known, or
    #: None: the best any run of the case reached (the methods then run to their own convergence)
    best_known: float | Callable[[], float] | None
    tolerance: Callable[[float], float]  # best known -> allowed gap of the target
    note: str = ""
    loaded: Any = None                   # the LoadedSpec of a generic case (synthesis.bench.generic)
    single_runs: set = field(default_factory=set)   # methods run once whatever ``repeats`` says
    #: the sample-count study of the case: sweep(tick) -> its table, and how many runs it ticks
    sweep: Callable[[Callable], dict] | None = None
    sweep_runs: int = 0
    #: further rows of the case: name -> () -> list of dicts (bench.md prints each as a table)
    studies: dict[str, Callable[[], list[dict]]] = field(default_factory=dict)
    warmup: Callable[[], Any] | None = None   # untimed, before the first timed run (imports, first solve)

    def runs(self, repeats: int) -> int:
        """Progress-bar steps of the case."""
        return (sum(1 if m in self.single_runs else repeats for m in self.methods) + (1 if callable(self.best_known) else 0)
                + self.sweep_runs + len(self.studies))


_quick: ContextVar[bool] = ContextVar("agrisynth_bench_quick", default=False)


@contextmanager
def quick_mode(on: bool):
    """Bench cases made inside use the ``--quick`` study settings (:data:`synthesis.bench.generic.QUICK`)."""
    token = _quick.set(on)
    try:
        yield
    finally:
        _quick.reset(token)


def current_settings():
    from synthesis.bench.generic import FULL, QUICK

    return QUICK if _quick.get() else FULL


def kinds_with_bench() -> list[str]:
    from synthesis import kinds

    return [k.name for k in kinds.all_kinds() if k.benches]


#: an every-kind run (``agrisynth bench`` with no KIND) takes at most this many of a kind's own
#: (non-generic) default cases; ``agrisynth bench KIND`` runs them all
OWN_CASES_IN_EVERY_KIND_RUN = 1


def cases_for(kind: str, specs, seed: int, own_limit: int | None = None) -> list[BenchCase]:
    """The kind's bench cases on ``specs`` (None: its default set): its own (``Kind.bench_cases``), else the generic
    studies on the specs or its ``Kind.bench_specs``.

    ``own_limit``: keep at most this many of the default cases of a kind with its own bench methods
    (not the generic studies).  ``--quick``: the first case of a default set only (specs a user names all run),
    and a kind with its own methods and a library example runs only the generic studies on that example (its own
    cases -- reference solve, its peers -- are the slow part; the case note says so)."""
    from synthesis import kinds

    own_cases = kinds.get(kind).bench_cases(specs, seed)
    if own_cases is None:
        from synthesis.bench.generic import library_cases

        own_cases = library_cases(specs, seed, list(kinds.get(kind).bench_specs),
                                  studies=kinds.get(kind).bench_studies() or None)
    cases = own_cases
    own = specs is None and kinds.get(kind).solves and not any(c.loaded is not None for c in cases)
    left_out = 0
    if own and _quick.get() and kinds.get(kind).example:
        left_out, cases = len(cases), []
    elif _quick.get() and specs is None:        # the first of a default set; the specs a user names all run
        cases = cases[:1]
    elif own and own_limit is not None and len(cases) > own_limit:
        left_out, cases = len(cases) - own_limit, cases[:own_limit]
    if own:
        for case in cases:      # peers (not IPOPT) run once in every case, as in the generic studies
            case.single_runs = set(case.single_runs) | (set(case.methods) & PEERS)
        # a kind with its own bench methods: the generic studies too, on its library example
        from synthesis.bench.generic import LIBRARY, case_for
        from synthesis.spec import load_spec

        example = kinds.get(kind).example
        if example:
            case = case_for(load_spec(LIBRARY / example), current_settings(), seed)
            case.problem = f"{case.problem} (generic studies)"
            if left_out:
                case.note += (f"; {left_out} case(s) of the kind's own bench set not run here"
                              f" ({'--quick' if _quick.get() else 'every-kind run'}: `agrisynth bench {kind}` runs them)")
            cases.append(case)
    return cases


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
    if callable(case.best_known):
        tick(f"{case.problem}: reference solve")
        best = case.best_known()
        tick(None)
    else:
        best = math.inf if case.best_known is None else case.best_known
    target = best + case.tolerance(best) if math.isfinite(best) else math.inf
    if case.warmup is not None:
        case.warmup()
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
    feasible = [r.objective for rs in runs.values() for r in rs
                if r.worst_violation == 0 and math.isfinite(r.objective)]
    best = min([best] + feasible)
    if not math.isfinite(target) and math.isfinite(best):     # no best known before: the best any run reached
        target = best + case.tolerance(best)
    rows = []
    for method, rs in runs.items():
        walls = [r.wall_s for r in rs]
        median = _median(walls)
        typical = min(rs, key=lambda r: abs(r.wall_s - median))
        to_target = [time_to_target(r, target) for r in rs]
        every = all(t is not None for t in to_target)
        rows.append({
            "problem": case.problem, "kind": case.kind, "method": method,
            "objective": typical.objective, "objectives": [r.objective for r in rs],
            "objective_gap": typical.objective - best, "best_known": best, "target": target,
            "reached_target": reached(typical, target), "reached_target_runs": [reached(r, target) for r in rs],
            "worst_violation": typical.worst_violation,
            "wall_s": walls, "median_s": median, "trace": typical.trace, "details": typical.details,
            # median time to the target over the runs, when every run reached it
            "time_to_target_runs": to_target, "time_to_target_s": _median(to_target) if every else None,
            "time_to_target_text": f"{_median(to_target):.3g}" if every else TARGET_NOT_REACHED,
        })
    ratios = [time_ratio(r, rows[0]) for r in rows[1:]]
    # what a table prints in its "time ratio" column
    rows[0]["time_ratio_text"] = "1 (reference)"
    for row, ratio in zip(rows[1:], ratios):
        status = str(row["details"].get("return_status", "")) if isinstance(row["details"], dict) else ""
        if status.startswith("not run"):     # not a solve (e.g. a published design, scored): no time to compare
            ratio.update(time_ratio=None, time_ratio_note=status)
            row["time_ratio_text"] = status
        else:
            row["time_ratio_text"] = (f"{ratio['time_ratio']:.1f}x" if ratio["time_ratio"] is not None
                                      else ratio["time_ratio_note"])
    out = {"problem": case.problem, "kind": case.kind, "note": case.note, "best_known": best,
           "target": target, "rows": rows, "ratios": ratios}
    if case.sweep is not None:
        out["sweep"] = case.sweep(tick)
    if case.studies:
        out["studies"] = {}
        for name, study in case.studies.items():
            tick(f"{case.problem}: {name}")
            out["studies"][name] = study()
            tick(None)
    return out


def write_bench(out: Path, results: list[dict], settings: dict, extreme: list[dict] | None = None, *,
                force: bool = False, run_folder=None) -> Path:
    """OUT/bench/: bench.json, bench.md, error_vs_time.png and one samples_<problem>.png per swept problem,
    written into a staging folder (with the ``.agrisynth-run`` marker) moved into place at the end, as
    check and solve do: an earlier bench there is replaced only with ``force``, anything else is never
    replaced (OutputError, exit 2).  ``run_folder``: that folder opened already (the CLI opens it first)."""
    from synthesis.errors import OutputError
    from synthesis.result import open_run_folder

    run_folder = open_run_folder(out, "bench", force=force) if run_folder is None else run_folder
    try:
        _write_bench_files(run_folder.staging, results, settings, extreme)
        run_folder.commit()
    except OutputError:
        raise
    except BaseException:
        run_folder.discard()
        raise
    return run_folder.final


def _write_bench_files(folder: Path, results: list[dict], settings: dict, extreme: list[dict] | None) -> None:
    from synthesis.result import atomic_write_drawn, atomic_write_text, versions

    rows = [row for res in results for row in res["rows"]]
    data = {"settings": settings, "versions": versions(), "machine": machine(), "problems": [
        {k: v for k, v in res.items() if k != "rows"} for res in results], "rows": rows,
        "summary": summary(results), "extreme": extreme}
    plots = {"error_vs_time.png": lambda path: plot_error_vs_time(results, path)}
    for res in results:
        if res.get("sweep") and res["sweep"]["rows"]:
            plots[sweep_plot_name(res["problem"])] = lambda path, sweep=res["sweep"]: plot_sample_sweep(sweep, path)
    for name, draw in plots.items():
        atomic_write_drawn(folder / name, draw)
    data["plots"] = list(plots)
    data = _json_safe(data)
    atomic_write_text(folder / "bench.md", markdown(data))
    atomic_write_text(folder / "bench.json", json.dumps(data, indent=1) + "\n")


def machine() -> dict:
    """What the figures were measured on."""
    import platform

    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    return {"cpu": model or platform.processor(), "cores_usable": usable, "system": platform.platform(),
            "python": platform.python_version()}


def _row(res: dict, method: str) -> dict | None:
    return next((r for r in res["rows"] if r["method"] == method), None)


def summary(results: list[dict]) -> list[dict]:
    """One line per problem: the figures the performance study reports (sample count reaching the violation target
    and its time, exact against finite-difference derivatives, the peers' ratios, build against solve)."""
    out = []
    for res in results:
        ad = _row(res, "ipopt_multistart")
        if ad is None or "build_s" not in (ad.get("details") or {}):
            continue
        line = {"problem": res["problem"], "kind": res["kind"], "ad_median_s": ad["median_s"],
                "ad_median_iterations": ad["details"]["median_iterations"],
                "ad_successes": f"{ad['details']['successes']}/{ad['details']['starts']}",
                "ad_time_to_target": ad.get("time_to_target_text"),
                "build_s": ad["details"]["build_s"], "ipopt_s": ad["details"]["ipopt_s"],
                "recheck_s": ad["details"]["recheck_s"]}
        fd = _row(res, "ipopt_finite_differences")
        if fd is not None:
            line |= {"fd_median_s": fd["median_s"], "fd_median_iterations": fd["details"]["median_iterations"],
                     "fd_successes": f"{fd['details']['successes']}/{fd['details']['starts']}",
                     "fd_objective_gap": fd["objective_gap"], "fd_ratio": fd["time_ratio_text"],
                     # the solver's own time, build left out (an exact Hessian costs build time FD does not pay)
                     "fd_ipopt_ratio": (f"{fd['details']['ipopt_s'] / ad['details']['ipopt_s']:.1f}x"
                                        if fd["time_ratio_text"].endswith("x") and ad["details"]["ipopt_s"] > 0
                                        else None)}
        for peer in ("slsqp", "differential_evolution"):
            row = _row(res, peer)
            if row is not None:
                line[f"{peer}_ratio"] = row["time_ratio_text"]
                line[f"{peer}_time_to_target"] = row.get("time_to_target_text")
        sweep = res.get("sweep")
        if sweep:
            line["samples_reaching"] = sweep["reaching"]
        out.append(line)
    return out


def sweep_plot_name(problem: str) -> str:
    """The sample sweep plot's file name of a problem: ``samples_<problem>.png`` with every character but
    letters, digits, ``.``, ``_`` and ``-`` made ``_`` (a name like ``picking_arc (generic studies)`` has spaces
    and brackets, which break a Markdown image link and are awkward in a file name)."""
    return "samples_" + re.sub(r"[^A-Za-z0-9._-]+", "_", problem).strip("_") + ".png"


#: columns that hold counts (iterations): printed as plain numbers (``1000``, ``1580``, ``18.5``), never as
#: ``1e+03`` / ``1.58e+03``
COUNT_COLUMNS = {"ad_median_iterations", "fd_median_iterations", "iters", "median_iterations"}


def _count(v) -> str:
    """A count or a median of counts: an integer, or one decimal for a median halfway between two."""
    if v is None:
        return "–"
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
        return str(int(v)) if float(v).is_integer() else f"{v:.1f}"
    return _fmt(v)


def _fmt(v, spec: str = ".3g") -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return format(v, spec) if math.isfinite(v) else str(v)
    if isinstance(v, dict):
        return ", ".join(f"{k} {_fmt(x)}" for k, x in v.items())
    if isinstance(v, list):
        return " ".join(_fmt(x) for x in v)
    return str(v).replace("|", "\\|").replace("\n", " ")


def _table(rows: list[dict], columns: list[tuple[str, str]]) -> str:
    head = "| " + " | ".join(title for _, title in columns) + " |"
    rule = "|" + "---|" * len(columns)
    body = ["| " + " | ".join((_count if key in COUNT_COLUMNS else _fmt)(r.get(key)) for key, _ in columns) + " |"
            for r in rows]
    return "\n".join([head, rule, *body])


def markdown(data: dict) -> str:
    """bench.md: the machine, the per-problem summary, the method table, the sample sweeps, the kind's
    own studies and the extreme-case matrix."""
    m, st = data["machine"], data["settings"]
    parts = [f"# agrisynth bench\n\nMachine: {m['cpu']}, {m['cores_usable']} usable cores, {m['system']}, "
             f"Python {m['python']}.  Settings: {_fmt(st)}.\n\n"
             "Times are medians of the repeats (wall clock, one worker; the machine may be shared, so read "
             "ratios within one run).  Objectives are minimised (a maximising kind's is negated).  "
             "**Time to target**: seconds from a method's start (its NLP build included) to the first moment its "
             "design met the target (objective at or below best known + tolerance, every rule holding on the fine "
             "re-check grid), or 'target not reached'; every time ratio is the ratio of two such times (medians "
             "of the repeats), so no ratio is taken between runs that ended at different objectives.  IPOPT "
             "(AD and finite differences): the end of the first start whose re-checked design meets the target "
             "(the time of a multistart stopping there; the run itself goes on, its whole time is 'median s').  "
             "SLSQP and differential_evolution: the first SLSQP iteration / DE generation whose iterate (DE: best "
             "member), mapped to the kind's design and objective and re-checked with the kind's own functions, "
             "meets the target; the peer stops there.  That check runs at most once per iteration / generation "
             "and its own time is **excluded** from the time to target, from 'median s' and from the budgets "
             "(bench.json: details.target_check_s, details.target_checks).  A kind's own method that stops at "
             "the target itself: its whole run."]
    study = st.get("study") if isinstance(st, dict) else None
    if study:
        parts.append(f"Budgets: {study['starts']} start(s) per method (at most the spec's), "
                     + (f"SLSQP stopped at {study['slsqp_budget_s']:g} s per run (shared by its starts), "
                        if "slsqp" in study["peers"] else "")
                     + (f"differential_evolution one run stopped at {study['de_budget_s']:g} s, "
                        if "differential_evolution" in study["peers"] else "")
                     + ("" if study["peers"] else "no peers (SLSQP, differential_evolution), ")
                     + f"sample counts x {', '.join(f'{f:g}' for f in study['factors'])} with a count skipped when "
                     f"predicted over {study['sweep_budget_s']:g} s, "
                     + (f"best known from an untimed multistart of at most {study['reference_starts']} starts."
                        if study["reference"] else "best known: the best any run reached."))
    summ = []
    for line in data["summary"]:
        reach = line.get("samples_reaching") or {}
        summ.append(line | {"reach": _fmt(reach.get("samples")) if reach else "not reached",
                            "reach_s": reach.get("median_s") if reach else None})
    parts.append("## Summary per problem\n\n" + _table(summ, [
        ("kind", "kind"), ("problem", "problem"), ("reach", "samples at violation <= 1e-6"), ("reach_s", "its median s"),
        ("ad_median_iterations", "AD iterations"), ("fd_median_iterations", "FD iterations"),
        ("fd_ratio", "FD / AD time to target"), ("fd_ipopt_ratio", "FD / AD IPOPT time"),
        ("ad_median_s", "AD median s"), ("fd_median_s", "FD median s"), ("ad_successes", "AD success"),
        ("fd_successes", "FD success"), ("ad_time_to_target", "AD time to target (s)"),
        ("slsqp_time_to_target", "SLSQP time to target (s)"), ("slsqp_ratio", "SLSQP / AD time to target"),
        ("differential_evolution_time_to_target", "DE time to target (s)"),
        ("differential_evolution_ratio", "DE / AD time to target"), ("build_s", "build s"), ("ipopt_s", "IPOPT s"),
        ("recheck_s", "re-check s")]))
    rows = [r | {"iters": (r.get("details") or {}).get("median_iterations"),
                 "success": (f"{r['details']['successes']}/{r['details']['starts']}"
                             if isinstance(r.get("details"), dict) and "successes" in r["details"] else None)}
            for r in data["rows"]]
    parts.append("## Methods\n\n" + _table(rows, [
        ("problem", "problem"), ("method", "method"), ("objective", "objective"), ("objective_gap", "gap to best"),
        ("worst_violation", "worst violation"), ("median_s", "median s"), ("time_to_target_text", "time to target (s)"),
        ("iters", "median iterations"), ("success", "solver success"), ("time_ratio_text", "time-to-target ratio")]))
    for p in data["problems"]:
        if p.get("note"):
            parts.append(f"- {p['problem']}: {p['note']}")
    sweeps = [p for p in data["problems"] if p.get("sweep")]
    if sweeps:
        parts.append("## Accuracy against time: sample counts\n\nEvery `[solver]` sample setting scaled "
                     "together; worst violation on the 10x finer re-check grid (normalised by each rule's "
                     "scale); gap = |objective - objective at the finest count|.")
        for p in sweeps:
            sw = p["sweep"]
            parts.append(f"### {p['problem']} ({p['kind']}; {sw['starts']} starts, {sw['repeats']} run(s) each)\n\n"
                         + _table(sw["rows"], [("samples", "samples"), ("median_s", "median s"),
                                               ("build_s", "build s"), ("ipopt_s", "IPOPT s"),
                                               ("median_iterations", "median iterations"),
                                               ("worst_violation", "worst violation"), ("objective", "objective"),
                                               ("objective_gap", "gap to finest")])
                         + "".join(f"\n\nNot run: samples {_fmt(k['samples'])} (predicted {k['predicted_s']:.0f} s "
                                   f"> sweep budget {k['budget_s']:g} s)" for k in sw.get("skipped") or [])
                         + f"\n\n![samples]({sweep_plot_name(p['problem'])})")
    for p in data["problems"]:
        for name, rows_ in (p.get("studies") or {}).items():
            if rows_:
                parts.append(f"## {name.replace('_', ' ')} ({p['kind']})\n\n"
                             + _table(rows_, [(k, k.replace("_", " ")) for k in rows_[0]]))
    if data.get("extreme"):
        ext = data["extreme"]
        passed = sum(r["outcome"] == "passed" for r in ext)
        known = sum(str(r["outcome"]).startswith("known failure") for r in ext)
        parts.append(f"## Extreme-case matrix (tests/extreme/: {passed} of {len(ext)} passed"
                     + (f", {known} known failure(s) with the measured cause" if known else "") + ")\n\n"
                     + _table(ext, [("file", "file"), ("case", "case"), ("tried", "what was tried"),
                                    ("outcome", "outcome"),
                                    ("figure", "figure / what the tool did"), ("seconds", "s")]))
    parts.append("![error against run time](error_vs_time.png)")
    return "\n\n".join(parts) + "\n"


def plot_sample_sweep(sweep: dict, path: Path) -> None:
    """Log-log: fine-grid worst violation and objective gap to the finest count against median wall time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = sweep["rows"]
    t = [r["median_s"] for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for key, label, marker in (("worst_violation", "worst violation (fine grid, normalised)", "o"),
                               ("objective_gap", "objective gap to the finest count", "s")):
        ys = [max(r[key], FLOOR) if r[key] is not None and math.isfinite(r[key]) else math.nan for r in rows]
        ax.plot(t, ys, marker + "-", label=label)
    for r, x in zip(rows, t):
        ax.annotate(" ".join(str(v) for v in r["samples"].values()), (x, FLOOR), fontsize=7, rotation=60)
    ax.axhline(sweep["violation_target"], color="0.5", lw=0.8, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median wall time, s")
    ax.set_ylabel(f"error (0 drawn at {FLOOR:g})")
    ax.set_title(f"{sweep['problem']}: sample counts ({', '.join(rows[0]['samples'])})", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _json_safe(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    return x


def best_so_far(row: dict, best_known: float) -> list[tuple[float, float]]:
    """The median run's best-so-far gap (floored at FLOOR) against time, drawn as steps: one point per
    improvement, held to the median run's end (a trace whose one improvement came early is then a line, not a
    lone point far from the run's marker)."""
    trace = [(t, max(f - best_known, FLOOR)) for t, f in row["trace"] if f is not None and math.isfinite(f)]
    end = row.get("median_s")
    if trace and isinstance(end, (int, float)) and math.isfinite(end) and end > trace[-1][0]:
        trace.append((end, trace[-1][1]))
    return trace


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
            trace = best_so_far(row, res["best_known"])
            if trace:
                ax_gap.plot(*zip(*trace), "-" if methods.index(row["method"]) == 0 else "--", color=colour,
                            lw=0.9, alpha=0.6, drawstyle="steps-post")
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
    if ax_gap.get_legend_handles_labels()[0]:     # a bench with no result has nothing to name (matplotlib warns)
        ax_gap.legend(fontsize=7, loc="best", ncol=2)
    fig.suptitle("error against run time (points: repeats; lines: best so far in the median run)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
