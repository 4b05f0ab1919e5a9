"""The combing chain's check on the studio's coarse grid.  The check samples 181 plant angles x 51 machine speeds
per gear and explains the paper's published figures; coarse: the [solver] beta_samples x speed_samples, and only
the curves the page draws."""

from __future__ import annotations

from synthesis.core.kind import CoarseCheck
from synthesis.result import Result


def evaluate(loaded) -> Result:
    from synthesis.kinds.combing_chain.check import curves, evaluate as rules_at

    spec = loaded.model
    design = spec.design_values()
    rules, _ = rules_at(spec, design, spec.solver.beta_samples, spec.solver.speed_samples)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra={"curves": curves(spec, design)})


def note(spec) -> str:
    from synthesis.kinds.combing_chain.check import CHECK_BETA_SAMPLES, CHECK_SPEED_SAMPLES

    return (f"the check's rules on [solver] beta_samples {spec.solver.beta_samples} x speed_samples "
            f"{spec.solver.speed_samples} (fine: {CHECK_BETA_SAMPLES} x {CHECK_SPEED_SAMPLES}), only the curves drawn")


COARSE = CoarseCheck(evaluate=evaluate, note=note)
