"""Kind planting_fourbar: the four-bar planting arm of seed 000, claw tip through P1-P6."""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import FixedBy, Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, ResultTable, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/planting/parts.py)."""
    from synthesis.kinds.planting import parts

    return parts


class PlantingFourbar(Kind):
    name = "planting_fourbar"
    summary = "four-bar planting arm, claw through P1-P6 (seed 000)"
    objectives = {"nearest": "smallest change from the given design (squared, relative to the bounds)",
                  "robust": "largest smallest normalised rule margin (measured on the fine grid)",
                  "smooth": "smallest peak claw acceleration over a turn, mm/s^2",
                  "min_peak_torque": "smallest peak |input torque| over a turn, N m ([dynamics] needed)",
                  "min_peak_shaking_force": "smallest peak shaking force on the frame over a turn, N ([dynamics] "
                                            "needed)",
                  "min_peak_shaking_moment": "smallest peak |shaking moment| on the frame over a turn, about the "
                                             "crank pivot, N m ([dynamics] needed)"}
    example = "planting_arm/redesign_from_example1.toml"
    bench_specs = ("planting_arm/redesign_from_example1.toml", "planting_arm/redesign_from_example3.toml")
    #: with [soil] analysis_depth the soil is placed that far above the lowest point: the depth is that number
    fixed_by = {"planting_depth": FixedBy("[soil] analysis_depth", "[rules] depth")}

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.planting.spec import PlantingFourbarSpec

        return PlantingFourbarSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        """Entry angle, depth and hole, the seedling pick, the point rules' misses and, with [key_poses], each
        pose's miss."""
        return _parts().headline(result)

    def result_tables(self, result: Result) -> list[ResultTable]:
        return _parts().result_tables(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"trajectory.png": _parts().trajectory_figure,
                "trajectory.svg": _parts().trajectory_figure,
                "kinematics.png": _parts().kinematics_of_one,
                "linkage.png": _parts().linkage_of_one,
                "animation.gif": _parts().animation_of_one,
                "paths.csv": _parts().write_paths_csv,
                "linkage.dxf": _parts().write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().overlay_figures

    def bench_studies(self) -> dict:
        return {"derivative_error": _parts().derivative_error_rows}

    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE

    def poses(self) -> Poses:
        return _parts().POSES


KIND = PlantingFourbar()
