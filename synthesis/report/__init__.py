"""Reports: the single-run page (report.html, written by check and solve) and the comparison page.

Both are the same page: a run's report is a comparison of one candidate.  Figures come from the
kind's writers (drawn from result.json data only, never re-solving); a figure that cannot be drawn
becomes a note on the page instead of a failed run.
"""

from __future__ import annotations

from pathlib import Path

from synthesis.report.page import render
from synthesis.report.tables import Candidate, candidates
from synthesis.result import Result, atomic_write_text

#: what a figure writer may raise when the result lacks the data it draws (an older or partial result)
MISSING_DATA = (KeyError, IndexError, TypeError, ValueError)


def _caption(name: str) -> str:
    return Path(name).stem.replace("_", " ")


def comparison_figures(cands: list[Candidate], folder: Path) -> tuple[list[tuple[str, str]], list[str]]:
    """Draw the kind's overlay figures of the candidates into ``folder``: ([(file, caption)], notes)."""
    from synthesis import kinds

    writer = kinds.compare_figures(cands[0].result.kind)
    if writer is None:
        return [], []
    try:
        written = writer([c.result for c in cands], folder)
    except MISSING_DATA as exc:
        return [], [f"comparison figures not drawn: the results lack {exc!r}"]
    return [w if isinstance(w, tuple) else (w, _caption(w)) for w in written], []


def run_artifacts(result: Result) -> dict:
    """What a check or solve writes beside result.json: the kind's figures, then report.html."""
    from synthesis import kinds

    figures = kinds.figure_writers(result)
    return {**figures, "report.html": lambda path: write_report(result, path, list(figures))}


def write_report(result: Result, path: Path, figures: list[str]) -> None:
    """report.html of one run, beside its own figures (``figures``) and the kind's overlay figures."""
    cands = candidates([result])
    extra, notes = comparison_figures(cands, path.parent)
    shown = [(f, _caption(f)) for f in figures] + [f for f in extra if f[0] not in figures]
    atomic_write_text(path, render(cands, shown, notes, result.name))
