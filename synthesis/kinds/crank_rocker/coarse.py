"""The crank-rocker's check on the studio's coarse grid: the check samples the transmission angle on its own
3600 crank angles; coarse on the [solver] samples_per_turn."""

from __future__ import annotations

from synthesis.core.kind import CoarseCheck
from synthesis.result import Result


def evaluate(loaded) -> Result:
    from synthesis.kinds.crank_rocker.check import evaluate as rules_at, facts, mechanism

    spec = loaded.model
    cr = mechanism(spec)
    rules, q = rules_at(spec, cr, samples=spec.solver.samples_per_turn)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=spec.design_values(), rules=[r.record().to_json() for r in rules], extra=facts(spec, cr, q))


def note(spec) -> str:
    from synthesis.kinds.crank_rocker.check import check_samples

    return (f"the check with [solver] samples_per_turn {spec.solver.samples_per_turn} crank angles "
            f"(fine: {check_samples(spec)})")


COARSE = CoarseCheck(evaluate=evaluate, note=note)
