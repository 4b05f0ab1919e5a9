"""Kind planting_fourbar: the four-bar planting arm of seed 000, claw tip through P1-P6."""

from synthesis.core.kind import Kind

KIND = Kind(
    name="planting_fourbar",
    summary="four-bar planting arm, claw through P1-P6 (seed 000)",
    spec_model="synthesis.spec.planting:PlantingFourbarSpec",
    check="synthesis.planting.check:run_check",
    figures={"trajectory.png": "synthesis.planting.plots:trajectory_figure"},
    compare="synthesis.planting.compare_plots:overlay_figures",
    solving="synthesis.planting.solve:SOLVING",
    objectives={"nearest": "smallest change from the given design (squared, relative to the bounds)",
                "robust": "largest smallest normalised rule margin (measured on the fine grid)",
                "smooth": "smallest peak claw acceleration over a turn, mm/s^2"},
    example="planting_arm/redesign_from_example1.toml",
)
