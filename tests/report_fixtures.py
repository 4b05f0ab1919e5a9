"""Run folders of real planting results for the report tests: what `agrisynth check` writes, in-process."""

from __future__ import annotations

from pathlib import Path

from synthesis import kinds
from synthesis.spec import design_info
from synthesis.report import run_artifacts
from synthesis.result import Result, write_run
from synthesis.spec import load_spec


def checked_run(spec: Path, out: Path) -> tuple[Path, Result]:
    loaded = load_spec(spec)
    result = design_info.attach(kinds.checker(loaded.kind)(loaded), loaded.model)     # as `agrisynth check` does
    folder, _ = write_run(out, result, run_artifacts(result))
    return folder, result
