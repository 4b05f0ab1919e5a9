"""Run folders of real planting results, written once per test session, for the report tests."""

from __future__ import annotations

from pathlib import Path

from synthesis import kinds
from synthesis.report import write_report
from synthesis.result import Result, write_run
from synthesis.spec import load_spec


def checked_run(spec: Path, out: Path) -> tuple[Path, Result]:
    """What `agrisynth check SPEC --out OUT` writes, done in-process."""
    loaded = load_spec(spec)
    result = kinds.checker(loaded.kind)(loaded)
    figures = kinds.figure_writers(result)
    artifacts = dict(figures)
    artifacts["report.html"] = lambda path: write_report(result, path, list(figures))
    folder, _ = write_run(out, result, artifacts)
    return folder, result
