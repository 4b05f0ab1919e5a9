"""The steering linkage's check on the studio's coarse grid.  The check also explains the paper's Table 12
(least-squares fits of the published rows, about nine tenths of its time); that explanation does not depend on
the design, so the coarse grid leaves it out of the facts: the rules are the check's, on the [solver] lock
samples (the check's are 10x)."""

from __future__ import annotations

from synthesis.core import coarse
from synthesis.core.kind import CoarseCheck
from synthesis.core.verdict import FINE
from synthesis.result import Result


def evaluate(loaded) -> Result:
    from synthesis.kinds.steering_linkage.check import evaluate as rules_at, facts

    spec = coarse.coarser(loaded.model)
    design = spec.design_values()
    rules, trace = rules_at(spec, design, FINE * spec.solver.samples)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra=facts(spec, design, trace, {}))


def note(spec) -> str:
    # lock_grid: samples + 1 locks, the check's on 10x the [solver] samples
    return (f"the check on {FINE * coarse.coarser(spec).solver.samples + 1} inside locks (fine: "
            f"{FINE * spec.solver.samples + 1}), without its Table 12 explanation")


COARSE = CoarseCheck(evaluate=evaluate, note=note)
