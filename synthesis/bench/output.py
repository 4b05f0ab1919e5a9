"""What ``agrisynth bench`` writes into OUT/bench/: bench.json, bench.md (the machine, the per-problem summary,
the method table, the sample sweeps, the kinds' own studies, the extreme-case matrix) and the plots
(:mod:`synthesis.report.bench_plots`)."""

from __future__ import annotations

import json
import math
import os
import platform
import re
import statistics
from pathlib import Path

from synthesis.report.bench_plots import plot_error_vs_time, plot_sample_sweep
from synthesis.result import atomic_write_drawn, atomic_write_text, open_run_folder, versions


def write_bench(out: Path, results: list[dict], settings: dict, extreme: list[dict] | None = None, *,
                force: bool = False, run_folder=None) -> Path:
    """OUT/bench/: bench.json, bench.md, error_vs_time.png and one samples_<problem>.png per swept problem,
    written into a staging folder (with the ``.agrisynth-run`` marker) moved into place at the end, as
    check and solve do: an earlier bench there is replaced only with ``force``, anything else is never
    replaced (OutputError, exit 2).  ``run_folder``: that folder opened already (the CLI opens it first)."""
    run_folder = open_run_folder(out, "bench", force=force) if run_folder is None else run_folder
    run_folder.fill(lambda staging: write_bench_files(staging, results, settings, extreme))
    return run_folder.final


def write_bench_files(folder: Path, results: list[dict], settings: dict, extreme: list[dict] | None) -> None:
    """bench.json, bench.md and the plots, written into ``folder`` (a run folder's staging folder: the writer of
    run folders, ``RunFolder.fill``, moves it into place)."""
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


def _median_ipopt_s(row: dict) -> float | None:
    """The median over a row's runs of their solver seconds (a row written before they were kept: its median run's)."""
    runs = [v for v in row.get("ipopt_s_runs") or [] if isinstance(v, (int, float))]
    if runs and len(runs) == len(row.get("ipopt_s_runs") or []):
        return float(statistics.median(runs))
    value = (row.get("details") or {}).get("ipopt_s")
    return float(value) if isinstance(value, (int, float)) else None


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
                     # the solver's own time, build left out (an exact Hessian costs build time FD does not pay): the
                     # ratio of the two methods' medians over their runs
                     "fd_ipopt_ratio": (f"{_median_ipopt_s(fd) / _median_ipopt_s(ad):.1f}x"
                                        if fd["time_ratio_text"].endswith("x") and (_median_ipopt_s(ad) or 0) > 0
                                        and _median_ipopt_s(fd) is not None else None)}
        compiled = _row(res, "ipopt_compiled")
        if compiled is not None and "build_s" in (compiled.get("details") or {}):
            line |= {"compiled_median_s": compiled["median_s"], "compiled_build_s": compiled["details"]["build_s"],
                     "compiled_ipopt_s": compiled["details"]["ipopt_s"],
                     "compiled_ratio": compiled["time_ratio_text"],
                     "compiled_ipopt_ratio": (f"{compiled['details']['ipopt_s'] / ad['details']['ipopt_s']:.2f}x"
                                              if ad["details"]["ipopt_s"] > 0 else None)}
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
    parts = [_preamble(data["machine"], data["settings"])]
    study = data["settings"].get("study") if isinstance(data["settings"], dict) else None
    if study:
        parts.append(_budgets(study))
    parts += [_summary_table(data["summary"]), _methods_table(data["rows"])]
    parts += [f"- {p['problem']}: {p['note']}" for p in data["problems"] if p.get("note")]
    parts += [f"- {p['problem']}: a timed run ({', '.join(p['target_moved']['by'])}) bettered the best known "
              f"({_fmt(p['target_moved']['best_known_before'], '.7g')} -> {_fmt(p['best_known'], '.7g')}); every run is "
              f"measured against the new target, {_fmt(p['target'], '.7g')} (was {_fmt(p['target_moved']['from'], '.7g')})"
              for p in data["problems"] if isinstance(p.get("target_moved"), dict)]
    parts += _sweep_sections(data["problems"])
    for p in data["problems"]:
        for name, rows in (p.get("studies") or {}).items():
            if rows:
                parts.append(f"## {name.replace('_', ' ')} ({p['kind']})\n\n"
                             + _table(rows, [(k, k.replace("_", " ")) for k in rows[0]]))
    if data.get("extreme"):
        parts.append(_extreme_section(data["extreme"]))
    elif isinstance(data["settings"], dict) and data["settings"].get("extreme_not_run"):
        parts.append(f"## Extreme-case matrix\n\nNot run: {data['settings']['extreme_not_run']}.")
    parts.append("![error against run time](error_vs_time.png)")
    return "\n\n".join(parts) + "\n"


def _preamble(m: dict, settings) -> str:
    return (f"# agrisynth bench\n\nMachine: {m['cpu']}, {m['cores_usable']} usable cores, {m['system']}, "
            f"Python {m['python']}.  Settings: {_fmt(settings)}.\n\n"
            "Times are medians of a method's runs ('runs': the repeats for IPOPT, one for SLSQP and differential_evolution, "
            "whose budgets bound them; wall clock, one worker; the machine may be shared, so read "
            "ratios within one run).  Objectives are minimised (a maximising kind's is negated).  "
            "**Time to target**: seconds from a method's start (its NLP build included) to the first moment its "
            "design met the target (objective at or below best known + tolerance, every rule holding on the fine "
            "re-check grid), or 'target not reached'; every time ratio is the ratio of two such times (medians "
            "of the repeats), so no ratio is taken between runs that ended at different objectives.  IPOPT "
            "(AD and finite differences): the end of the first start whose re-checked design meets the target, its "
            "re-check left out as a peer's checks are (the time of a multistart stopping there; the run itself goes "
            "on, its whole time is 'median s').  "
            "SLSQP and differential_evolution: the first SLSQP iteration / DE generation whose iterate (DE: best "
            "member), mapped to the kind's design and objective and re-checked with the kind's own functions, "
            "meets the target; the peer stops there.  That check runs at most once per iteration / generation "
            "and its own time is **excluded** from the time to target, from 'median s' and from the budgets "
            "(bench.json: details.target_check_s, details.target_checks).  A kind's own method that stops at "
            "the target itself: its whole run.")


def _budgets(study: dict) -> str:
    return (f"Budgets: {study['starts']} start(s) per method (at most the spec's), "
            + (f"SLSQP stopped at {study['slsqp_budget_s']:g} s per run (shared by its starts), "
               if "slsqp" in study["peers"] else "")
            + (f"differential_evolution one run stopped at {study['de_budget_s']:g} s, "
               if "differential_evolution" in study["peers"] else "")
            + ("" if study["peers"] else "no peers (SLSQP, differential_evolution), ")
            + f"sample counts x {', '.join(f'{f:g}' for f in study['factors'])} with a count skipped when "
            f"predicted over {study['sweep_budget_s']:g} s, "
            + (f"best known from an untimed multistart of at most {study['reference_starts']} starts."
               if study["reference"] else "best known: the best any run reached."))


def _summary_table(lines: list[dict]) -> str:
    summ = []
    for line in lines:
        reach = line.get("samples_reaching") or {}
        summ.append(line | {"reach": _fmt(reach.get("samples")) if reach else "not reached",
                            "reach_s": reach.get("median_s") if reach else None})
    return "## Summary per problem\n\n" + _table(summ, [
        ("kind", "kind"), ("problem", "problem"), ("reach", "samples at violation <= 1e-6"), ("reach_s", "its build + solve s"),
        ("ad_median_iterations", "AD iterations"), ("fd_median_iterations", "FD iterations"),
        ("fd_ratio", "FD / AD time to target"), ("fd_ipopt_ratio", "FD / AD IPOPT time"),
        ("ad_median_s", "AD median s"), ("fd_median_s", "FD median s"), ("ad_successes", "AD success"),
        ("fd_successes", "FD success"), ("ad_time_to_target", "AD time to target (s)"),
        ("slsqp_time_to_target", "SLSQP time to target (s)"), ("slsqp_ratio", "SLSQP / AD time to target"),
        ("differential_evolution_time_to_target", "DE time to target (s)"),
        ("differential_evolution_ratio", "DE / AD time to target"), ("build_s", "build s"), ("ipopt_s", "IPOPT s"),
        ("recheck_s", "re-check s")]) + (_compiled_table(lines) if any("compiled_ratio" in line for line in lines) else "")


def _compiled_table(lines: list[dict]) -> str:
    """``bench --compiled``: the same IPOPT runs with the NLP's functions compiled to C, against the interpreted."""
    return "\n\n### Compiled derivatives (`--compiled`)\n\n" + _table([line for line in lines if "compiled_ratio" in line], [
        ("kind", "kind"), ("problem", "problem"), ("ad_median_s", "interpreted median s"),
        ("compiled_median_s", "compiled median s"), ("compiled_ratio", "compiled / interpreted time to target"),
        ("build_s", "interpreted build s"), ("compiled_build_s", "compiled build s (library found)"),
        ("ipopt_s", "interpreted IPOPT s"), ("compiled_ipopt_s", "compiled IPOPT s"),
        ("compiled_ipopt_ratio", "compiled / interpreted IPOPT s")])


def _methods_table(rows: list[dict]) -> str:
    rows = [r | {"iters": (r.get("details") or {}).get("median_iterations"),
                 "success": (f"{r['details']['successes']}/{r['details']['starts']}"
                             if isinstance(r.get("details"), dict) and "successes" in r["details"] else None),
                 "unit": (r.get("details") or {}).get("objective_unit"), "runs": len(r.get("wall_s") or [])}
            for r in rows]
    return "## Methods\n\n" + _table(rows, [
        ("problem", "problem"), ("method", "method"), ("runs", "runs"), ("objective", "objective"),
        ("unit", "objective unit"), ("objective_gap", "gap to best"),
        ("worst_violation", "worst violation"), ("median_s", "median s"), ("time_to_target_text", "time to target (s)"),
        ("iters", "median iterations"), ("success", "solver success"), ("time_ratio_text", "time-to-target ratio")])


def _sweep_sections(problems: list[dict]) -> list[str]:
    sweeps = [p for p in problems if p.get("sweep")]
    if not sweeps:
        return []
    parts = ["## Accuracy against time: sample counts\n\nEvery `[solver]` sample setting scaled together; worst "
             "violation on the 10x finer re-check grid (normalised by each rule's scale); gap = |objective - "
             "objective at the finest count|.  'build + solve s' is the NLP's build, IPOPT and the re-check of a run "
             "(the x 1 row reuses the AD run, whose 'median s' in the methods table is its whole timed wall, the "
             "multistart's own work around them too)."]
    for p in sweeps:
        sw = p["sweep"]
        parts.append(f"### {p['problem']} ({p['kind']}; {sw['starts']} starts, {sw['repeats']} run(s) each)\n\n"
                     + _table(sw["rows"], [("samples", "samples"), ("median_s", "build + solve s"),
                                           ("build_s", "build s"), ("ipopt_s", "IPOPT s"),
                                           ("median_iterations", "median iterations"),
                                           ("worst_violation", "worst violation"), ("objective", "objective"),
                                           ("objective_gap", "gap to finest")])
                     + "".join(f"\n\nNot run: samples {_fmt(k['samples'])} (predicted {k['predicted_s']:.0f} s "
                               f"> sweep budget {k['budget_s']:g} s)" for k in sw.get("skipped") or [])
                     + f"\n\n![samples]({sweep_plot_name(p['problem'])})")
    return parts


def _extreme_section(ext: list[dict]) -> str:
    passed = sum(r["outcome"] == "passed" for r in ext)
    known = sum(str(r["outcome"]).startswith("known failure") for r in ext)
    return (f"## Extreme-case matrix (tests/extreme/: {passed} of {len(ext)} passed"
            + (f", {known} known failure(s) with the measured cause" if known else "") + ")\n\n"
            + _table(ext, [("file", "file"), ("case", "case"), ("tried", "what was tried"), ("outcome", "outcome"),
                           ("figure", "figure / what the tool did"), ("seconds", "s")]))


def _json_safe(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    return x


#: the earlier name of :func:`write_bench_files` (tests write a bench's files into a plain folder with it)
_write_bench_files = write_bench_files
