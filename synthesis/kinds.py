"""What each problem kind provides to the CLI, imported only when a spec of that kind is run."""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from synthesis.errors import SpecError
from synthesis.result import Result

@dataclass(frozen=True)
class KindEntry:
    """Where a kind's code lives, as "module:function" strings, so nothing is imported until it runs."""

    checker: str                      # run_check(loaded) -> Result
    solver: str | None                # module with run_solve, baseline_rules, diagnose_infeasible; None: check only
    figures: dict[str, str]           # file name -> writer(result, path): figures and exports of one run
    compare: str | None = None        # (results, folder) -> [file names]: candidates overlaid, baseline first


_KINDS = {
    "planting_fourbar": KindEntry(
        checker="synthesis.planting.check:run_check",
        solver="synthesis.planting.solve",
        figures={"trajectory.png": "synthesis.planting.plots:trajectory_figure"},
        compare="synthesis.planting.compare_plots:overlay_figures"),
    "guide_tube": KindEntry(
        checker="synthesis.guide_tube.check:run_check",
        solver="synthesis.guide_tube.solve",
        figures={"drop_times.png": "synthesis.guide_tube.plots:drop_times_figure",
                 "drop_profiles.png": "synthesis.guide_tube.plots:drop_profile_figure",
                 "sensitivity.png": "synthesis.guide_tube.plots:sensitivity_figure"},
        compare="synthesis.guide_tube.plots:compare_figures"),
    "clamp_cam": KindEntry(
        checker="synthesis.clamp_cam.check:run_check",
        solver="synthesis.clamp_cam.solve",
        figures={"motion.png": "synthesis.clamp_cam.plots:motion_figure",
                 "profile.png": "synthesis.clamp_cam.plots:profile_figure",
                 "profile.csv": "synthesis.clamp_cam.export:write_csv",
                 "profile.dxf": "synthesis.clamp_cam.export:write_dxf"},
        compare="synthesis.clamp_cam.plots:compare_figure"),
    "crank_rocker": KindEntry(
        checker="synthesis.crank_rocker.check:run_check",
        solver="synthesis.crank_rocker.solve",
        figures={"extremes.png": "synthesis.crank_rocker.plots:extremes_figure"},
        compare="synthesis.crank_rocker.plots:compare_figure"),
    "picker_double_crank": KindEntry(
        checker="synthesis.picker.check:run_check",
        solver="synthesis.picker.solve",
        figures={"path.png": "synthesis.picker.plots:path_figure"},
        compare="synthesis.picker.plots:compare_figure"),
    "picker": KindEntry(       # evaluated only: the combined mechanism of two solved designs
        checker="synthesis.picker.combined:run_check",
        solver=None,
        figures={"trajectory.png": "synthesis.picker.plots:picker_figure",
                 "animation.gif": "synthesis.picker.plots:picker_animation"},
        compare="synthesis.report.trajectory_overlay:trajectory_overlay"),
    "fourbar_path": KindEntry(
        checker="synthesis.fourbar_path.check:run_check",
        solver="synthesis.fourbar_path.solve",
        figures={"coupler_curve.png": "synthesis.fourbar_path.plots:coupler_curve_figure",
                 "linkage.gif": "synthesis.fourbar_path.plots:linkage_animation"},
        compare="synthesis.fourbar_path.plots:compare_coupler_curves"),
}


def _resolve(target: str) -> Callable:
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


def checker(kind: str) -> Callable:
    return _resolve(_KINDS[kind].checker)


def solver(kind: str):
    """The kind's solve module (run_solve, baseline_rules, diagnose_infeasible)."""
    if _KINDS[kind].solver is None:
        solvable = [k for k, entry in _KINDS.items() if entry.solver is not None]
        raise SpecError(f"kind {kind!r} has nothing to optimise (`agrisynth check` evaluates it); "
                        f"kinds that solve: {', '.join(solvable)}")
    return importlib.import_module(_KINDS[kind].solver)


def figure_writers(result: Result) -> dict[str, Callable[[Path], None]]:
    """filename -> writer(path) for the kind's figures."""
    return {fn: (lambda path, f=_resolve(t): f(result, path)) for fn, t in _KINDS[result.kind].figures.items()}


def compare_figures(kind: str) -> Callable | None:
    """The kind's overlay-figure writer for ``agrisynth compare``, or None if it has none."""
    target = _KINDS[kind].compare
    return None if target is None else _resolve(target)
