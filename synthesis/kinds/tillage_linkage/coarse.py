"""The tillage linkage's check on the studio's coarse grid.  The check also measures, at the design, how far the
paper's printed equations 3-11 are from the constructed geometry (four fifths of its time); that is a fact about
the paper, not a rule, so the coarse grid leaves it out: the rules are the check's, on the [solver] samples (the
check's are 10x), with the curve and the poses the page draws, and with a [dynamics] table the check's facts.dynamics
(the studio's torque and shaking charts)."""

from __future__ import annotations

import math

from synthesis.core.kind import CoarseCheck
from synthesis.result import Result

#: the poses drawn: one every this many degrees of crank (the check's facts "positions")
POSE_STEP_DEG = 45.0


def evaluate(loaded) -> Result:
    from synthesis.kinds.tillage_linkage.check import curves, dynamics_of, evaluate as rules_at, joints, params

    spec = loaded.model
    design = spec.design_values()
    rules, motion = rules_at(spec, design, spec.solver.samples, spec.solver.soil_samples)
    machine, trajectory = curves(spec, design, motion)
    a, b, c, th = params(design)
    poses = [{"crank_deg": k * POSE_STEP_DEG,
              **{n: list(v) for n, v in joints(math.radians(k * POSE_STEP_DEG), a, b, c, th).items()}}
             for k in range(int(360 / POSE_STEP_DEG))]
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], trajectory=trajectory,
                  extra={"curve": machine, "positions": poses, **dynamics_of(spec, design)})


def note(spec) -> str:
    return (f"the check's rules on [solver] samples {spec.solver.samples} and soil_samples "
            f"{spec.solver.soil_samples} (fine: 10x), without the printed-equation residuals")


COARSE = CoarseCheck(evaluate=evaluate, note=note)
