"""The two grids the studio evaluates on: coarse while a slider moves, the check's own (fine) on release.

Fine is ``agrisynth check`` itself.  Coarse is the kind's :class:`~synthesis.core.kind.CoarseCheck`
(:func:`synthesis.core.coarse.of_kind`): its own (``Kind.coarse_check``), the same rules on fewer samples with only
the facts the page draws, else its check with every ``[solver]`` sample count divided by 10.  Each note states the
sample counts the grid evaluates.
"""

from __future__ import annotations

from typing import Callable

from synthesis import kinds
from synthesis.core.coarse import of_kind
from synthesis.core.kind import CoarseCheck
from synthesis.result import Result
from synthesis.spec import LoadedSpec

GRIDS = ("coarse", "fine")


def _coarse(kind: str) -> CoarseCheck:
    return of_kind(kinds.get(kind))


def evaluator(kind: str, grid: str) -> Callable[[LoadedSpec], Result]:
    """loaded spec -> Result, on ``grid``."""
    if grid == "fine":
        return kinds.checker(kind)
    return _coarse(kind).evaluate


def note(kind: str, grid: str, spec) -> str:
    """What the grid is, in words, for the page."""
    coarse = _coarse(kind)
    return (coarse.note if grid == "coarse" else coarse.fine_note)(spec)
