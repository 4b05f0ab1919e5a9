"""What each problem kind provides to the CLI, imported only when a spec of that kind is run."""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Callable

from synthesis.result import Result

#: kind -> (module with run_check, module and function writing its figures)
_CHECKERS = {"planting_fourbar": "synthesis.planting.check:run_check",
             "fourbar_path": "synthesis.fourbar_path.check:run_check"}
_SOLVERS = {"planting_fourbar": "synthesis.planting.solve",
            "fourbar_path": "synthesis.fourbar_path.solve"}
_FIGURES = {"planting_fourbar": {"trajectory.png": "synthesis.planting.plots:trajectory_figure"},
            "fourbar_path": {"coupler_curve.png": "synthesis.fourbar_path.plots:coupler_curve_figure",
                             "linkage.gif": "synthesis.fourbar_path.plots:linkage_animation"}}
#: kind -> "module:function(results: list[Result], folder: Path) -> list[str]" drawing several
#: candidates of that kind overlaid (baseline first) into ``folder``; returns the file names written
_COMPARE_FIGURES: dict[str, str] = {"fourbar_path": "synthesis.fourbar_path.plots:compare_coupler_curves"}


def _resolve(target: str) -> Callable:
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


def checker(kind: str) -> Callable:
    return _resolve(_CHECKERS[kind])


def solver(kind: str):
    """The kind's solve module (run_solve, baseline_rules, diagnose_infeasible)."""
    return importlib.import_module(_SOLVERS[kind])


def figure_writers(result: Result) -> dict[str, Callable[[Path], None]]:
    """filename -> writer(path) for the kind's figures."""
    return {fn: (lambda path, f=_resolve(t): f(result, path)) for fn, t in _FIGURES.get(result.kind, {}).items()}


def compare_figures(kind: str) -> Callable | None:
    """The kind's overlay-figure writer for ``agrisynth compare``, or None if it has none."""
    target = _COMPARE_FIGURES.get(kind)
    return None if target is None else _resolve(target)
