"""What a run tells while it works: small records handed to the subscriber the caller passes in.

A run (:mod:`synthesis.runs`) never prints: it calls ``emit(event)`` with one of these and goes on.  The command
line draws them (a progress bar, a line per finished start, the summary once the result is written); the studio's
worker sends them to the page through a pipe.  An event handed over inside the run's deferral (``ResultWritten``,
``StartsDone``) is drawn before a signal noted meanwhile is obeyed (docs/ARCHITECTURE.md, "Interrupts").
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class SpecFromLibrary:
    """SPEC named no file here: the library's spec of that name is used (``relative``: as `problems` lists it)."""

    given: Path
    relative: str
    path: Path


@dataclass(frozen=True)
class Note:
    """A word on valid input the user may want to act on (a number that looks like metres for mm)."""

    text: str


@dataclass(frozen=True)
class RunWarning:
    """Something left out of the run, which goes on without it (a kind whose bench cases could not be made)."""

    text: str


@dataclass(frozen=True)
class SolveStarted:
    """The multistart begins: ``total`` starts of spec ``name``."""

    name: str
    total: int


@dataclass(frozen=True)
class StartFinished:
    """One start has finished (``done`` of ``total``): its outcome and the best start so far."""

    start: int
    done: int
    total: int
    objective: float
    verdict: str            # "feasible", or what stands in the way (:func:`violation_text`)
    return_status: str
    iterations: int
    wall_s: float
    best_start: int
    best_objective: float
    best_verdict: str
    #: read back from the interrupted run's starts.jsonl (--resume), not solved by this one
    resumed: bool = False

    def line(self) -> str:
        """The line a piped solve prints for it (and the studio shows)."""
        if self.resumed:        # its solve's seconds were the earlier run's: not said as this run's
            return (f"start {self.start} read back from the run resumed ({self.done}/{self.total}): objective "
                    f"{self.objective:.6g}, {self.verdict}, IPOPT {self.return_status} in {self.iterations} "
                    f"iterations; best so far: start {self.best_start}")
        return (f"start {self.start} finished ({self.done}/{self.total}): objective {self.objective:.6g}, "
                f"{self.verdict}, IPOPT {self.return_status} in {self.iterations} iterations, {self.wall_s:.2f} s; "
                f"best so far: start {self.best_start}")


@dataclass(frozen=True)
class StartsDone:
    """Every start has finished; the result is being written (handed over inside the deferral)."""


@dataclass(frozen=True)
class SolverLog:
    """IPOPT's output of every start (``solve --verbose``); always written to ipopt.log too."""

    text: str


@dataclass(frozen=True)
class ResultWritten:
    """A run's result is in its folder (handed over inside the deferral, so its summary is printed before a signal
    noted meanwhile is obeyed).  ``details``: what the summary says beside the result (``CheckWritten``,
    ``SolveWritten`` of :mod:`synthesis.runs.requests`)."""

    result: Any
    folder: Path
    replaced: bool
    details: Any = None


@dataclass(frozen=True)
class SignalAfterResult:
    """A signal arrived once the result was complete: noted, not obeyed; the exit code stays the result's."""

    signal_name: str
    folder: Path


@dataclass(frozen=True)
class MonteCarloPlan:
    """The tolerance Monte-Carlo re-checks each sample at the nominal point and at ``points`` of the range."""

    samples: int
    points: int


@dataclass(frozen=True)
class BenchStarted:
    """The bench begins: ``total`` steps (runs of methods and the extreme matrix)."""

    total: int


@dataclass(frozen=True)
class BenchStep:
    """The bench's progress: ``what`` is being measured now, or (None) one step is done."""

    what: str | None = None


@dataclass(frozen=True)
class ArtifactWritten:
    """A file outside a run folder was written (a copied spec, a template, a comparison page)."""

    path: Path
    extra: list[Path] = field(default_factory=list)


#: the subscriber a run is given: called with each event, in order, on the run's thread
Subscriber = Callable[[Any], None]


def ignore(event: Any) -> None:
    """A subscriber that wants no events."""


def violation_text(report) -> str:
    """"worst violation 0.93", or for a design whose rules could not all be evaluated (an infinite violation) what
    stands in the way: "no design: <why>" or "entry_angle not evaluated: <note>"."""
    if math.isfinite(report.worst_violation):
        return f"worst violation {report.worst_violation:.3g}"
    if report.why:
        return f"no design: {report.why.rstrip('.')}"
    missing = next((r for r in report.records if r.value is None), None)
    if missing is not None:
        return f"{missing.name} not evaluated" + (f": {missing.note.rstrip('.')}" if missing.note else "")
    return "not evaluated"


def start_finished(report, best, done: int, total: int, resumed: bool = False) -> StartFinished:
    """The event of a finished start from the solve core's reports of it and of the best so far (``resumed``: read
    back from the run resumed)."""
    o = report.outcome
    return StartFinished(o.start, done, total, o.objective, "feasible" if report.satisfied else violation_text(report),
                         o.return_status, o.iterations, o.wall_s, best.outcome.start, best.outcome.objective,
                         "feasible" if best.satisfied else violation_text(best), resumed)
