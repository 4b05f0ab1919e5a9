"""``agrisynth compare``: several results of one kind side by side in one page, from result.json alone."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from synthesis.errors import ResultError
from synthesis.report import comparison_figures
from synthesis.report.page import render
from synthesis.report.tables import Candidate, candidates
from synthesis.result import load_result


def load_candidates(paths: list[Path]) -> list[Candidate]:
    """Read every result (run folder or result.json); one kind only, the first is the baseline."""
    if not paths:
        raise ResultError("compare needs at least one RESULT (a run folder or its result.json)")
    results = [load_result(p) for p in paths]
    files = [p / "result.json" if p.is_dir() else p for p in paths]
    kinds = {r.kind for r in results}
    if len(kinds) > 1:
        listing = "; ".join(f"{f}: {r.kind}" for f, r in zip(files, results))
        raise ResultError(f"compare takes results of one kind, got {len(kinds)} kinds ({listing})")
    return candidates(results, files)


def write_comparison(cands: list[Candidate], out: Path) -> Path:
    """Write ``out/compare.html`` and its figures; every file lands by rename, the page last."""
    out.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".compare.", dir=out))
    try:
        figures, notes = comparison_figures(cands, staging)
        title = "compare: " + " vs ".join(c.label for c in cands)
        (staging / "compare.html").write_text(render(cands, figures, notes, title))
        for f, _ in figures:
            os.replace(staging / f, out / f)
        os.replace(staging / "compare.html", out / "compare.html")
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return out / "compare.html"
