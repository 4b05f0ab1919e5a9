"""The coarse grid of a kind's check: what ``agrisynth studio`` evaluates while a slider moves.

Each kind says how its check gets cheaper in its :class:`~synthesis.core.kind.CoarseCheck` (``Kind.coarse_check``):
most checks evaluate their sampled rules on 10x the ``[solver]`` sample counts (the fine re-check grid), and
their coarse grid is the same check with every ``[solver]`` sample count divided by :data:`COARSENING` (not below
the least the spec model allows), i.e. on the optimiser's own grid (:func:`by_solver_samples`); a check with its
grid built in, or with facts that do not depend on the design, has its own trimmed evaluation; a check that reads
no sample count has one grid (:func:`one_grid`).  The fine grid is always ``agrisynth check`` itself.
"""

from __future__ import annotations

from typing import Any, Callable

from synthesis.core.kind import CoarseCheck
from synthesis.spec import LoadedSpec

#: sample counts of the check divided by this while dragging (the check's fine grid is 10x the solver's)
COARSENING = 10
ONE_GRID_NOTE = "the check's one grid (this kind's check has no coarser one)"


def sample_fields(spec) -> dict[str, tuple[int, int, int]]:
    """[solver] field -> (value, least allowed, multiple of) for every sample count of the spec."""
    solver = getattr(spec, "solver", None)
    if solver is None:
        return {}
    out = {}
    for name, info in type(solver).model_fields.items():
        value = getattr(solver, name)
        if "samples" in name and isinstance(value, int) and not isinstance(value, bool):
            least = next((m.ge for m in info.metadata if hasattr(m, "ge")), 1)
            step = next((m.multiple_of for m in info.metadata if hasattr(m, "multiple_of")), 1)
            out[name] = (value, int(least), int(step))
    return out


def coarser(spec):
    """The spec with every [solver] sample count divided by COARSENING (not below its least, a multiple of its step)."""
    changes = {}
    for name, (value, least, step) in sample_fields(spec).items():
        coarse = max(least, value // COARSENING)
        changes[name] = max(least, coarse - coarse % step) if step > 1 else coarse
    if not changes:
        return spec
    return spec.model_copy(update={"solver": spec.solver.model_copy(update=changes)})


def solver_samples_note(spec) -> str:
    """What the coarse grid is when nothing more specific is known: each [solver] sample count and its coarse one."""
    fields = sample_fields(spec)
    if not fields:
        return ONE_GRID_NOTE
    coarse = coarser(spec).solver
    return "the check with " + ", ".join(f"[solver] {n} {v} -> {getattr(coarse, n)}" for n, (v, _, _) in fields.items())


def by_solver_samples(check: Callable[[Any], Any], note: Callable[[Any], str] = solver_samples_note) -> CoarseCheck:
    """The coarse grid of a check that samples on 10x the [solver] counts: the same check on the coarser spec.
    ``check``: the kind's check (loaded spec -> Result)."""
    def evaluate(loaded):
        if not sample_fields(loaded.model):
            return check(loaded)
        return check(LoadedSpec(coarser(loaded.model), loaded.path, loaded.sha256))
    return CoarseCheck(evaluate=evaluate, note=note)


def one_grid(check: Callable[[Any], Any]) -> CoarseCheck:
    """A check whose grid is fixed in the kind (no [solver] sample count reaches it): evaluated as it is."""
    return CoarseCheck(evaluate=check, note=lambda spec: ONE_GRID_NOTE)


def of_kind(kind) -> CoarseCheck:
    """The kind's coarse grid: its own (``Kind.coarse_check``), else its check with every [solver] sample count
    divided by :data:`COARSENING` (:func:`by_solver_samples`; one grid when the spec has no sample count)."""
    own = kind.coarse_check()
    return own if own is not None else by_solver_samples(kind.check)
