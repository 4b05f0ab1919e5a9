"""``agrisynth compare``: several results of one kind side by side in one page, from result.json alone.

Among the inputs may be the output of ``agrisynth bench`` (a folder with bench.json, or the file):
its error-against-run-time plot and table are added to the page.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from pathlib import Path

from synthesis.errors import ResultError
from synthesis.report import comparison_figures
from synthesis.report.page import render
from synthesis.report.tables import Candidate, candidates
from synthesis.result import load_result


def is_bench(path: Path) -> bool:
    return path.name == "bench.json" or (path.is_dir() and (path / "bench.json").exists()
                                          and not (path / "result.json").exists())


def load_bench(path: Path) -> list[dict]:
    """The per-problem results of a bench.json, shaped as ``synthesis.bench.run_case`` returns them."""
    path = path if path.name == "bench.json" else path / "bench.json"
    try:
        data = json.loads(path.read_text())
        rows, problems = data["rows"], data["problems"]
        for row in rows:
            missing = [key for key in BENCH_ROW_KEYS if key not in row]
            if missing:
                raise KeyError(f"a row lacks {', '.join(missing)}")
            row["worst_violation"] = _number(row["worst_violation"])
        return [dict(p, rows=[r for r in rows if r["problem"] == p["problem"]], best_known=_number(p["best_known"]))
                for p in problems]
    except (OSError, json.JSONDecodeError, KeyError, TypeError, AttributeError) as exc:
        raise ResultError(f"{path}: not a readable agrisynth bench.json ({type(exc).__name__}: {exc})") from None


#: what the error-against-run-time plot and table read from each bench row
BENCH_ROW_KEYS = ("problem", "method", "objective", "objectives", "objective_gap", "worst_violation",
                  "wall_s", "median_s", "trace")


def _number(v) -> float:
    """bench.json writes a value that could not be measured as null."""
    return math.nan if v is None else float(v)


def load_candidates(paths: list[Path]) -> list[Candidate]:
    """Read every result (run folder or result.json); one kind only, the first is the baseline."""
    if not paths:
        raise ResultError("compare needs at least one RESULT (a run folder or its result.json)")
    from synthesis.spec import KINDS

    results = [load_result(p) for p in paths]
    files = [p / "result.json" if p.is_dir() else p for p in paths]
    for f, r in zip(files, results):
        if r.kind not in KINDS:
            raise ResultError(f"{f}: kind {r.kind!r} is not one this agrisynth knows ({', '.join(KINDS)})")
    kinds = {r.kind for r in results}
    if len(kinds) > 1:
        listing = "; ".join(f"{f}: {r.kind}" for f, r in zip(files, results))
        raise ResultError(f"compare takes results of one kind, got {len(kinds)} kinds ({listing})")
    return candidates(results, files)


def write_comparison(cands: list[Candidate], out: Path, bench: list[dict] | None = None) -> Path:
    """Write ``out/compare.html`` and its figures; every file lands by rename, the page last."""
    out.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".compare.", dir=out))
    try:
        figures, notes = comparison_figures(cands, staging)
        if bench:
            from synthesis.bench import plot_error_vs_time

            try:
                plot_error_vs_time(bench, staging / "error_vs_time.png")
                figures.append(("error_vs_time.png", "error against run time (agrisynth bench): objective gap "
                                                     "and worst fine-grid violation against wall time"))
            except Exception as exc:    # noqa: BLE001 - the table still shows the bench; say why the plot is missing
                notes.append(f"error_vs_time.png not drawn: {type(exc).__name__}: {exc}")
        title = "compare: " + " vs ".join(c.label for c in cands)
        (staging / "compare.html").write_text(render(cands, figures, notes, title, bench))
        for f, _ in figures:
            os.replace(staging / f, out / f)
        os.replace(staging / "compare.html", out / "compare.html")
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return out / "compare.html"
