"""The rotary_planetary check on the studio's coarse grid: the check reads its rules on 10x the [solver]
samples_per_turn and in_soil_samples (the solve's re-check grid); coarse on those samples themselves."""

from __future__ import annotations

from synthesis.core.kind import CoarseCheck
from synthesis.kinds.rotary_planetary.check import check_grid, facts
from synthesis.kinds.rotary_planetary.check import evaluate as rules_at
from synthesis.result import Result


def evaluate(loaded) -> Result:
    spec = loaded.model
    design = spec.design_values()
    rules, train, angles = rules_at(spec, design, spec.solver.samples_per_turn, spec.solver.in_soil_samples)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra=facts(spec, train, angles))


def note(spec) -> str:
    fine, soil = check_grid(spec)
    return (f"the check with [solver] samples_per_turn {spec.solver.samples_per_turn} carrier angles and "
            f"in_soil_samples {spec.solver.in_soil_samples} (fine: {fine} and {soil})")


COARSE = CoarseCheck(evaluate=evaluate, note=note)
