"""The four-bar path's check on the studio's coarse grid: the check on the [solver] samples divided by 10.  Its
path rules read a sample count only for grashof "any" (between the targets); otherwise they are evaluated at the
targets and in closed form, on one grid.  The [dynamics.limits] read [solver] dynamics_samples (over a turn)."""

from __future__ import annotations

from synthesis.core import coarse
from synthesis.core.verdict import FINE
from synthesis.kinds.fourbar_path.check import run_check


def note(spec) -> str:
    if spec.dynamics is not None and spec.dynamics.has_rules():
        path = ("its path rules at the targets and in closed form" if spec.rules.grashof_class != "any" else
                f"{FINE * coarse.coarser(spec).solver.samples} samples per gap between targets (fine: "
                f"{FINE * spec.solver.samples})")
        return (f"the check on {FINE * coarse.coarser(spec).solver.dynamics_samples} crank angles of a turn for the "
                f"[dynamics.limits] (fine: {FINE * spec.solver.dynamics_samples}); {path}")
    if spec.rules.grashof_class != "any":      # path_rules samples between targets only for grashof "any"
        return (f"the check's one grid (grashof = \"{spec.rules.grashof_class}\": its rules are evaluated at the "
                f"targets and in closed form, on no sample count)")
    return (f"the check on {FINE * coarse.coarser(spec).solver.samples} samples per gap between targets (fine: "
            f"{FINE * spec.solver.samples})")


COARSE = coarse.by_solver_samples(run_check, note)
