"""What a kind's own bench methods hand the bench: :class:`BenchCase` (a problem, its methods, its target) and
:class:`MethodRun` (one run of one method).

They are the contract of ``Kind.bench_cases`` (:mod:`synthesis.core.kind`), so they live below both sides: a kind's
bench plug-in (``synthesis/kinds/<kind>/bench.py``) builds them without importing the bench, and the bench
(:mod:`synthesis.bench.case`) times and reports them -- the engine never imports the bench (docs/ARCHITECTURE.md,
"Layers").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable


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
    #: an iterate against the target, a solver setup the bench replaced): left out of ``wall_s``
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
