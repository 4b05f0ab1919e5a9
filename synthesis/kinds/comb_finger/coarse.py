"""The comb finger's check on the studio's coarse grid: the check on the [solver] turn_samples divided by 10,
which is its one grid while 10x those samples stay below the check's least 3600 turn angles."""

from __future__ import annotations

from synthesis.core import coarse
from synthesis.kinds.comb_finger.check import run_check


def note(spec) -> str:
    from synthesis.kinds.comb_finger.check import fine_samples

    ours, theirs = fine_samples(coarse.coarser(spec)), fine_samples(spec)
    if ours == theirs:                 # the check samples at least CHECK_TURN_SAMPLES, whatever [solver] says
        return (f"the check's one grid ({theirs} finger turn angles: it does not go below that for [solver] "
                f"turn_samples {spec.solver.turn_samples})")
    return f"the check on {ours} finger turn angles (fine: {theirs})"


COARSE = coarse.by_solver_samples(run_check, note)
