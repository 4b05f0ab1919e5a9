"""The studio's solve worker: ``python -m synthesis.studio.worker SPEC OUT STARTS`` runs
:func:`synthesis.runs.solve` on SPEC into OUT with one local worker and sends the run's events to the studio as
JSON lines on its standard output (:func:`message`); everything else the process prints goes to its standard
error.  It ends with the exit code `agrisynth solve` would (docs/ARCHITECTURE.md, "Exit codes"): SIGTERM (the
page's cancel) keeps the finished starts and exits 143.
"""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path
from typing import Any, TextIO

from synthesis import runs
from synthesis.core import interrupt
from synthesis.errors import AgrisynthError
from synthesis.studio.solver import PAGE_MAX_STARTS
from synthesis.runs import events
from synthesis.runs.requests import Outcome, SolveRequest


def message(event) -> dict[str, Any] | None:
    """What the page is told of a run's event: progress (``done`` of ``total``) and a line to show; None: nothing."""
    if isinstance(event, events.SolveStarted):
        return {"total": event.total}
    if isinstance(event, events.StartFinished):
        return {"done": event.done, "total": event.total, "line": event.line()}
    if isinstance(event, (events.Note, events.RunWarning)):
        return {"line": f"note: {event.text}"}
    if isinstance(event, events.ResultWritten):
        return {"line": f"wrote {event.folder}/: status {event.result.status}"}
    if isinstance(event, events.SignalAfterResult):
        return {"line": f"{event.signal_name} arrived once the result was complete; the exit code is the result's"}
    return None


def stopped_line(stopped) -> str:
    if stopped.kept is None:
        return f"interrupted by {stopped.signal_name} before any start finished; nothing written"
    return (f"interrupted by {stopped.signal_name} after {stopped.finished} of {stopped.total} starts: kept them and "
            f"their best (status interrupted)")


class Channel:
    """The event channel to the studio: this process's standard output, which nothing else may write to (the
    descriptor is moved, and standard output made a second standard error)."""

    def __init__(self) -> None:
        self.stream: TextIO = os.fdopen(os.dup(1), "w", buffering=1, encoding="utf-8")
        os.dup2(2, 1)           # a library printing to standard output (IPOPT, CasADi) writes onto standard error
        sys.stdout = sys.stderr

    def send(self, payload: dict[str, Any]) -> None:
        self.stream.write(json.dumps(payload) + "\n")
        self.stream.flush()

    def __call__(self, event) -> None:
        payload = message(event)
        if payload is not None:
            self.send(payload)



def solve(spec: Path, out: Path, starts: int | str, channel: Channel) -> int:
    """The run, its end told on the channel; returns the exit code."""
    try:
        # auto from the page: at most the page's cap of starts in all (the command line's default is 512)
        outcome: Outcome = runs.solve(SolveRequest(spec, out, starts=starts, workers=1,
                                                   max_starts=PAGE_MAX_STARTS if starts == "auto" else None), channel)
    except AgrisynthError as exc:
        channel.send({"error": str(exc), "line": f"error: {exc}"})
        return exc.exit_code
    if outcome.stopped is not None:
        channel.send({"line": stopped_line(outcome.stopped)})
    if outcome.error is not None:
        channel.send({"error": str(outcome.error), "line": f"error: {outcome.error}"})
    return outcome.exit_code


def main(argv: list[str]) -> None:
    interrupt.install(keep_ignored=True)        # a cancel while the run's modules load ends as one during the run
    spec, out = Path(argv[0]), Path(argv[1])
    starts: int | str = "auto" if argv[2] == "auto" else int(argv[2])
    channel = Channel()
    try:
        code = solve(spec, out, starts, channel)
    except (KeyboardInterrupt, ImportError, SystemError) as exc:
        # a signal before the run could keep anything (while its modules load: ImportError, "initialization failed")
        if not isinstance(exc, KeyboardInterrupt) and interrupt.pending() is None:
            raise
        channel.send({"line": f"interrupted by {signal.Signals(interrupt.signal_of(exc)).name} before any start "
                              f"finished; nothing written"})
        code = 128 + interrupt.signal_of(exc)
    sys.exit(code)


if __name__ == "__main__":
    main(sys.argv[1:])
