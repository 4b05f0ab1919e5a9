"""Reports: the single-run page (report.html, written by check and solve) and the comparison page.

Both are the same page: a run's report is a comparison of one candidate.  Figures come from the
kind's writers (drawn from result.json data only, never re-solving); a figure that cannot be drawn
becomes a note on the page instead of a failed run.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from synthesis import kinds
from synthesis.errors import NothingToDraw
from synthesis.report.drawing import Drawn, draw_all
from synthesis.report.page import render
from synthesis.report.tables import Candidate, candidates
from synthesis.result import Result, atomic_write_text


def has_dynamics(result: Result) -> bool:
    """Whether the result holds a driven linkage's inverse dynamics (an input torque over the crank angle): the
    shared dynamics figures draw those; a cam follower's contact dynamics, under the same key, are its kind's own."""
    dyn = (result.extra or {}).get("dynamics")
    return isinstance(dyn, dict) and "input_torque_Nm" in dyn


def _caption(name: str) -> str:
    return Path(name).stem.replace("_", " ")


def comparison_figures(cands: list[Candidate], folder: Path) -> tuple[list[tuple[str, str]], list[str]]:
    """Draw the kind's overlay figures of the candidates into ``folder``, and their dynamics where any has them:
    ([(file, caption)], notes)."""
    # figures name each candidate by its column label, which is unique even when spec names repeat
    labelled = [dataclasses.replace(c.result, name=c.label) for c in cands]
    figures, notes = _kind_overlays(labelled, folder)
    if any(has_dynamics(r) for r in labelled):
        # the inverse dynamics, the same figure for every kind that has them (docs/ARCHITECTURE.md "Dynamics")
        from synthesis.report.dynamics_plots import dynamics_overlay

        try:
            dynamics_overlay(labelled, folder / "dynamics.png")
            figures.append(("dynamics.png", "input torque, shaking force and shaking moment over the crank angle, "
                                            "every candidate with a [dynamics] table"))
        except Exception as exc:    # noqa: BLE001 - a figure is never worth losing the page: say why instead
            notes.append(f"dynamics.png not drawn: {type(exc).__name__}: {exc}")
    return figures, notes


def _kind_overlays(results: list[Result], folder: Path) -> tuple[list[tuple[str, str]], list[str]]:
    writer = kinds.compare_figures(results[0].kind)
    if writer is None:
        return [], []
    try:
        written = writer(results, folder)
    except Exception as exc:    # noqa: BLE001 - a figure is never worth losing the page: say why instead
        # NothingToDraw is the kind's own word on why (e.g. no candidate has a design its model could evaluate);
        # anything else is data the figures need and did not find
        guess = ("" if isinstance(exc, NothingToDraw) else " (the results lack data the figures need, e.g. a result "
                 "from an older agrisynth or edited by hand)")
        return [], [f"comparison figures not drawn: {type(exc).__name__}: {exc}{guess}"]
    return [w if isinstance(w, tuple) else (w, _caption(w)) for w in written], []


def run_artifacts(result: Result, files: dict | None = None, given_rules: list | None = None, *,
                  figures: bool = True) -> dict:
    """What a check or solve writes beside result.json: ``files`` (e.g. ipopt.log), the kind's figures,
    then report.html, which shows the figures and links the other files; ``given_rules`` (a solve) the rule
    table of the spec's given design, shown beside the solution's.  ``figures=False`` (an interrupted run, which
    must be kept and ended within seconds of the signal: the figures take 3 to 7 s, an animation most of it): no
    figure, and the page says why.

    A figure that fails is left out and named on the page: it must never cost the run its result.
    """
    written: list[str] = []
    failed: list[str] = []
    said: list[str] = []            # library warnings while drawing (matplotlib's): for the run's log

    def keep(drawn: list[Drawn]) -> None:
        for d in drawn:
            if d.error is None:
                said.append(d.said)
                written.append(d.name)
            else:
                failed.append(f"{d.name} not written: {d.error}")

    def guarded(name: str, writer):
        return lambda path: keep(draw_all({name: writer}, path.parent, cores=1))

    def together(writers: dict) -> dict:
        """Every writer drawn at once, side by side (synthesis.report.drawing), when the run folder asks for the
        first of them; the others are then already written."""
        pending = [True]

        def write(path: Path) -> None:
            if pending:
                pending.clear()
                keep(draw_all(writers, path.parent))
        return {name: write for name in writers}

    def report(path: Path) -> None:
        _log_drawing_warnings(path.parent, "".join(said), written)
        write_report(result, path, written, failed, given_rules)

    if not figures:
        failed.append("no figures: the run was interrupted; `agrisynth solve SPEC --resume RUN_DIR` finishes it and "
                      "draws them")
        return {**{name: guarded(name, w) for name, w in (files or {}).items()}, "report.html": report}
    writers = {**(files or {}), **kinds.figure_writers(result)}
    if isinstance((result.extra or {}).get("envelope"), dict):
        # an operating envelope: each rule that changes over the range, against the condition
        from synthesis.tolerance.envelope import plot

        writers["envelope.png"] = lambda path: plot(result, path)
    if has_dynamics(result):
        # a [dynamics] table: input torque, power and shaking force over a turn (docs/ARCHITECTURE.md "Dynamics")
        from synthesis.report.dynamics_plots import dynamics_figure

        writers["dynamics.png"] = lambda path: dynamics_figure(result, path)
    artifacts = together(writers)
    artifacts["report.html"] = report
    return artifacts


#: the run's log, where library warnings go: a solve's ipopt.log, else warnings.log
RUN_LOGS = ("ipopt.log", "warnings.log")


def _log_drawing_warnings(folder: Path, text: str, written: list[str]) -> None:
    """Append what the libraries said while the figures were drawn to the run's log (written already, in the
    run's staging folder), or start warnings.log with it: never onto the terminal."""
    if not text:
        return
    log = next((name for name in RUN_LOGS if name in written), None)
    if log is None:
        log = "warnings.log"
        (folder / log).write_text(text)
        written.append(log)
    else:
        with open(folder / log, "a") as out:
            out.write(f"\n# library warnings while drawing the figures\n{text}")


def write_report(result: Result, path: Path, figures: list[str], notes: list[str] = (),
                 given_rules: list | None = None) -> None:
    """report.html of one run, beside its own figures (``figures``): the kind's figures of this one design.
    The comparison overlays (several candidates in one plot) belong to ``agrisynth compare`` only."""
    cands = [dataclasses.replace(c, given_rules=given_rules) for c in candidates([result])]
    shown = [(f, _caption(f)) for f in figures]
    atomic_write_text(path, render(cands, shown, list(notes), result.name))
