"""The two grids the studio evaluates on: coarse while a slider moves, the check's own (fine) on release.

Fine is ``agrisynth check`` itself.  Coarse is the kind's own :class:`~synthesis.core.kind.CoarseCheck`
(``Kind.coarse_check``): the same rules on fewer samples, with only the facts the page draws; a kind without one
is evaluated by its check on both grids (the page says so).  Each note states the sample counts the grid evaluates.
"""

from __future__ import annotations

from typing import Callable

from synthesis import kinds
from synthesis.core.coarse import ONE_GRID_NOTE
from synthesis.core.kind import CoarseCheck, resolve
from synthesis.result import Result
from synthesis.spec import LoadedSpec

GRIDS = ("coarse", "fine")


def _coarse(kind: str) -> CoarseCheck | None:
    target = kinds.get(kind).coarse_check
    return None if target is None else resolve(target)


def evaluator(kind: str, grid: str) -> Callable[[LoadedSpec], Result]:
    """loaded spec -> Result, on ``grid``."""
    coarse = _coarse(kind)
    if grid == "fine" or coarse is None:
        return kinds.checker(kind)
    return coarse.evaluate


def note(kind: str, grid: str, spec) -> str:
    """What the grid is, in words, for the page."""
    coarse = _coarse(kind)
    if coarse is None:
        return ONE_GRID_NOTE if grid == "coarse" else "agrisynth check's own grid"
    return (coarse.note if grid == "coarse" else coarse.fine_note)(spec)
