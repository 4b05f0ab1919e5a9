"""The guide way's check on the studio's coarse grid: the check on the [solver] samples_per_segment divided by 10
(each stretch of the claw path sampled 10x that by the check)."""

from __future__ import annotations

from synthesis.core import coarse
from synthesis.kinds.guide_way.check import FINE
from synthesis.kinds.guide_way.check import run_check


def note(spec) -> str:
    return (f"the check on {FINE * coarse.coarser(spec).solver.samples_per_segment} samples per segment (fine: "
            f"{FINE * spec.solver.samples_per_segment})")


COARSE = coarse.by_solver_samples(run_check, note)
