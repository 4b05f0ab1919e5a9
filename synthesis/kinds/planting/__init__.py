"""Kind planting_fourbar: the four-bar planting arm of seed 000, claw tip through P1-P6."""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import FixedBy, Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


class PlantingFourbar(Kind):
    name = "planting_fourbar"
    summary = "four-bar planting arm, claw through P1-P6 (seed 000)"
    objectives = {"nearest": "smallest change from the given design (squared, relative to the bounds)",
                  "robust": "largest smallest normalised rule margin (measured on the fine grid)",
                  "smooth": "smallest peak claw acceleration over a turn, mm/s^2"}
    example = "planting_arm/redesign_from_example1.toml"
    bench_specs = ("planting_arm/redesign_from_example1.toml", "planting_arm/redesign_from_example3.toml")
    #: with [soil] analysis_depth the soil is placed that far above the lowest point: the depth is that number
    fixed_by = {"planting_depth": FixedBy("[soil] analysis_depth", "[rules] depth")}

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.planting.spec import PlantingFourbarSpec

        return PlantingFourbarSpec

    def check(self, loaded: LoadedSpec) -> Result:
        from synthesis.kinds.planting.check import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.planting.check import headline

        return headline(result)

    def solving(self) -> Solving:
        from synthesis.kinds.planting.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.planting.compare_plots import animation_of_one, kinematics_of_one, linkage_of_one
        from synthesis.kinds.planting.export import write_linkage_dxf, write_paths_csv
        from synthesis.kinds.planting.plots import trajectory_figure

        return {"trajectory.png": trajectory_figure,
                "trajectory.svg": trajectory_figure,
                "kinematics.png": kinematics_of_one,
                "linkage.png": linkage_of_one,
                "animation.gif": animation_of_one,
                "paths.csv": write_paths_csv,
                "linkage.dxf": write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.planting.compare_plots import overlay_figures

        return overlay_figures

    def bench_studies(self) -> dict:
        return {"derivative_error": derivative_error_rows}

    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.planting.coarse import COARSE

        return COARSE

    def poses(self) -> Poses:
        from synthesis.kinds.planting.poses import POSES

        return POSES


KIND = PlantingFourbar()



#: seed 000 §5.1: mean errors of its central-difference scheme against the analytic values (speed, acceleration)
PRINTED_DERIVATIVE_ERRORS = {1.0: (1.48, 4.94), 0.2: (0.64, 1.49)}


def derivative_error_rows() -> list[dict]:
    """Seed 000's central-difference scheme (eq. 8-14) against CasADi's exact derivatives, production
    design of example 1 (Table 1), mean over 360 crank angles, at the paper's two steps; both the
    literal tan^-1 directions and quadrant-correct ones (:mod:`synthesis.kinds.planting.finite_difference`)."""

    from synthesis.kinds.planting.finite_difference import mean_relative_errors
    from synthesis.kinds.planting.scene import PlantingScene
    from synthesis.kinds.planting.spec import PlantingFourbarSpec
    from synthesis.library import LIBRARY
    from synthesis.spec import load_spec

    spec = load_spec(LIBRARY / "planting_arm/taiwan_example1.toml").model
    assert isinstance(spec, PlantingFourbarSpec)
    scene = PlantingScene.from_spec(spec)
    rows = []
    for step, (speed_printed, acc_printed) in PRINTED_DERIVATIVE_ERRORS.items():
        for scheme in ("atan", "atan2"):
            e = mean_relative_errors(scene.design, scene.motion, step, scheme=scheme)
            rows.append({"design": "taiwan_example1", "step_deg": step, "scheme": scheme,
                         "speed_error_pct": 100 * e["speed_magnitude"],
                         "acceleration_magnitude_error_pct": 100 * e["acceleration_magnitude"],
                         "acceleration_vector_error_pct": 100 * e["acceleration_vector"],
                         "printed_speed_pct": speed_printed, "printed_acceleration_pct": acc_printed})
    return rows
