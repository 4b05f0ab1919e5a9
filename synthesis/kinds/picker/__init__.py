"""Kinds picker_double_crank and picker: the seed-001 seedling picker (double crank + crank-rocker)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    import numpy as np

    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/picker/parts.py)."""
    from synthesis.kinds.picker import parts

    return parts


class PickerDoubleCrank(Kind):
    name = "picker_double_crank"
    summary = "double crank whose clamp point follows the picking arc (seed 001 §2.1.2)"
    objectives = {"sum_of_distances": "seed 001 eq (4): sum of distances of the clamp point to the arc points, mm",
                  "sum_of_squares": "sum of squared distances, mm^2",
                  "min_peak_torque": "smallest peak |input torque| on AB over the working swing, N m ([dynamics] and "
                                     "[rules] max_arc_error needed)",
                  "min_peak_shaking_force": "smallest peak shaking force on the frame over the working swing, N "
                                            "([dynamics] and [rules] max_arc_error needed)",
                  "min_peak_shaking_moment": "smallest peak |shaking moment| on the frame over the working swing, "
                                             "about A, N m ([dynamics] and [rules] max_arc_error needed)"}
    example = "picker/picker_double_crank_redesign.toml"
    bench_specs = ("picker/picker_double_crank_redesign.toml", "picker/picker_double_crank_retrofit.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.picker.spec import PickerDoubleCrankSpec

        return PickerDoubleCrankSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"path.png": _parts().path_figure,
                "path.svg": _parts().path_figure,
                "paths.csv": _parts().write_double_crank_csv,
                "linkage.dxf": _parts().write_double_crank_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figure


    def coarse_check(self) -> CoarseCheck:
        return _parts().DOUBLE_CRANK

    def design_affine(self, spec: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The NLP works in Grashof coordinates (three lengths replaced by the slacks of the Grashof rows)."""
        return _parts().COORDINATES.affine(n)


DOUBLE_CRANK = PickerDoubleCrank()


class Picker(Kind):
    name = "picker"
    summary = "double crank and crank-rocker together at 60 r/min: clamp trajectory, pick/drop instants"
    example = "picker/cai2020_picker.toml"

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.picker.spec import PickerSpec

        return PickerSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().combined_run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().combined_headline(result)

    def figures(self) -> dict[str, FigureWriter]:
        return {"trajectory.png": _parts().picker_figure,
                "trajectory.svg": _parts().picker_figure,
                "animation.gif": _parts().picker_animation,
                "paths.csv": _parts().write_picker_csv,
                "linkage.dxf": _parts().write_picker_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().trajectory_overlay

    def coarse_check(self) -> CoarseCheck:
        return _parts().PICKER


PICKER = Picker()        # evaluated only: the combined mechanism of two solved designs

#: the folder's two kinds, in the order they are listed
KINDS = (DOUBLE_CRANK, PICKER)

