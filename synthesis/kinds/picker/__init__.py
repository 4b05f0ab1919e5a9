"""Kinds picker_double_crank and picker: the seed-001 seedling picker (double crank + crank-rocker)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    import numpy as np

    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


class PickerDoubleCrank(Kind):
    name = "picker_double_crank"
    summary = "double crank whose clamp point follows the picking arc (seed 001 §2.1.2)"
    objectives = {"sum_of_distances": "seed 001 eq (4): sum of distances of the clamp point to the arc points, mm",
                  "sum_of_squares": "sum of squared distances, mm^2"}
    example = "picker/picker_double_crank_redesign.toml"
    bench_specs = ("picker/picker_double_crank_redesign.toml", "picker/picker_double_crank_retrofit.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.picker.spec import PickerDoubleCrankSpec

        return PickerDoubleCrankSpec

    def check(self, loaded: LoadedSpec) -> Result:
        from synthesis.kinds.picker.check import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.picker.check import headline

        return headline(result)

    def solving(self) -> Solving:
        from synthesis.kinds.picker.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.picker.export import write_double_crank_csv, write_double_crank_dxf
        from synthesis.kinds.picker.plots import path_figure

        return {"path.png": path_figure,
                "path.svg": path_figure,
                "paths.csv": write_double_crank_csv,
                "linkage.dxf": write_double_crank_dxf}

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.picker.plots import compare_figure

        return compare_figure


    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.picker.coarse import DOUBLE_CRANK

        return DOUBLE_CRANK

    def design_affine(self, spec: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The NLP works in Grashof coordinates (three lengths replaced by the slacks of the Grashof rows)."""
        from synthesis.kinds.picker.nlp import COORDINATES

        return COORDINATES.affine(n)


DOUBLE_CRANK = PickerDoubleCrank()


class Picker(Kind):
    name = "picker"
    summary = "double crank and crank-rocker together at 60 r/min: clamp trajectory, pick/drop instants"
    example = "picker/cai2020_picker.toml"

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.picker.spec import PickerSpec

        return PickerSpec

    def check(self, loaded: LoadedSpec) -> Result:
        from synthesis.kinds.picker.combined import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.picker.check import combined_headline

        return combined_headline(result)

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.picker.export import write_picker_csv, write_picker_dxf
        from synthesis.kinds.picker.plots import picker_animation, picker_figure

        return {"trajectory.png": picker_figure,
                "trajectory.svg": picker_figure,
                "animation.gif": picker_animation,
                "paths.csv": write_picker_csv,
                "linkage.dxf": write_picker_dxf}

    def compare_figures(self) -> CompareWriter:
        from synthesis.report.trajectory_overlay import trajectory_overlay

        return trajectory_overlay

    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.picker.coarse import PICKER

        return PICKER


PICKER = Picker()        # evaluated only: the combined mechanism of two solved designs

#: the folder's two kinds, in the order they are listed
KINDS = (DOUBLE_CRANK, PICKER)

