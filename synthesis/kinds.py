"""What each problem kind provides to the CLI, imported only when a spec of that kind is run."""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Callable

from synthesis.errors import SpecError
from synthesis.result import Result

#: kind -> (module with run_check, module and function writing its figures)
_CHECKERS = {"planting_fourbar": "synthesis.planting.check:run_check",
             "crank_rocker": "synthesis.crank_rocker.check:run_check",
             "picker_double_crank": "synthesis.picker.check:run_check",
             "picker": "synthesis.picker.combined:run_check"}
_SOLVERS = {"planting_fourbar": "synthesis.planting.solve",
            "crank_rocker": "synthesis.crank_rocker.solve",
            "picker_double_crank": "synthesis.picker.solve"}
_FIGURES = {"planting_fourbar": {"trajectory.png": "synthesis.planting.plots:trajectory_figure"},
            "crank_rocker": {"extremes.png": "synthesis.crank_rocker.plots:extremes_figure"},
            "picker_double_crank": {"path.png": "synthesis.picker.plots:path_figure"},
            "picker": {"trajectory.png": "synthesis.picker.plots:picker_figure",
                       "animation.gif": "synthesis.picker.plots:picker_animation"}}
#: kind -> "module:function(results: list[Result], folder: Path) -> list[str]" drawing several
#: candidates of that kind overlaid (baseline first) into ``folder``; returns the file names written
_COMPARE_FIGURES: dict[str, str] = {"crank_rocker": "synthesis.crank_rocker.plots:compare_figure",
                                     "picker_double_crank": "synthesis.picker.plots:compare_figure"}


def _resolve(target: str) -> Callable:
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


def checker(kind: str) -> Callable:
    return _resolve(_CHECKERS[kind])


def solver(kind: str):
    """The kind's solve module (run_solve, baseline_rules, diagnose_infeasible)."""
    if kind not in _SOLVERS:
        raise SpecError(f"kind {kind!r} has nothing to optimise (`agrisynth check` evaluates it); "
                        f"kinds that solve: {', '.join(_SOLVERS)}")
    return importlib.import_module(_SOLVERS[kind])


def figure_writers(result: Result) -> dict[str, Callable[[Path], None]]:
    """filename -> writer(path) for the kind's figures."""
    return {fn: (lambda path, f=_resolve(t): f(result, path)) for fn, t in _FIGURES.get(result.kind, {}).items()}


def compare_figures(kind: str) -> Callable | None:
    """The kind's overlay-figure writer for ``agrisynth compare``, or None if it has none."""
    target = _COMPARE_FIGURES.get(kind)
    return None if target is None else _resolve(target)
