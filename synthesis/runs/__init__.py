"""The runs: what each agrisynth command does, beyond parsing its options and printing (docs/ARCHITECTURE.md,
"Layers").

Each run is a plain function taking a typed request (:mod:`.requests`) and a subscriber, called with the
progress events it hands over (:mod:`.events`), and returning an :class:`~.requests.Outcome` (its exit code, the
result, where it was written).  The command line (:mod:`synthesis.cli`) draws the events with rich; the studio's
solve worker sends them to the page.  Nothing here prints, parses options or knows click, rich or the studio.

    check(CheckRequest, emit)          :mod:`.checking`
    solve(SolveRequest, emit)          :mod:`.solving`  (the interrupted run kept in one place)
    tolerance(ToleranceRequest, emit)  :mod:`.tolerancing`
    bench(BenchRequest, emit)          :mod:`.benching`
    compare(CompareRequest, emit)      :mod:`.comparing`

A run's folder is opened, written and discarded in one place (:mod:`.output`).  The runs are imported on first
use (each pulls in the engine it runs: casadi for check and solve), so ``import synthesis.runs`` stays light.
"""

from __future__ import annotations

import importlib

from synthesis.runs.requests import (BadRequest, BenchRequest, CheckRequest, CompareRequest, Outcome, SolveRequest,
                                     ToleranceRequest)

#: run name -> the module defining it, imported when the run is first asked for
_RUNS = {"check": "checking", "solve": "solving", "tolerance": "tolerancing", "bench": "benching",
         "compare": "comparing"}


def __getattr__(name: str):
    if name in _RUNS:
        return getattr(importlib.import_module(f"synthesis.runs.{_RUNS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["BadRequest", "BenchRequest", "CheckRequest", "CompareRequest", "Outcome", "SolveRequest",
           "ToleranceRequest", *_RUNS]
