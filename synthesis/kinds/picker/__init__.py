"""Kinds picker_double_crank and picker: the seed-001 seedling picker (double crank + crank-rocker)."""

from synthesis.core.kind import Kind

DOUBLE_CRANK = Kind(
    name="picker_double_crank",
    summary="double crank whose clamp point follows the picking arc (seed 001 §2.1.2)",
    spec_model="synthesis.kinds.picker.spec:PickerDoubleCrankSpec",
    check="synthesis.kinds.picker.check:run_check",
    figures={"path.png": "synthesis.kinds.picker.plots:path_figure",
             "path.svg": "synthesis.kinds.picker.plots:path_figure",
             "paths.csv": "synthesis.kinds.picker.export:write_double_crank_csv",
             "linkage.dxf": "synthesis.kinds.picker.export:write_double_crank_dxf"},
    compare="synthesis.kinds.picker.plots:compare_figure",
    solving="synthesis.kinds.picker.solve:SOLVING",
    bench="synthesis.kinds.picker:double_crank_bench_cases",
    objectives={"sum_of_distances": "seed 001 eq (4): sum of distances of the clamp point to the arc points, mm",
                "sum_of_squares": "sum of squared distances, mm^2"},
    example="picker/picker_double_crank_redesign.toml",
    coarse_check="synthesis.kinds.picker.coarse:DOUBLE_CRANK",
)

PICKER = Kind(        # evaluated only: the combined mechanism of two solved designs
    name="picker",
    summary="double crank and crank-rocker together at 60 r/min: clamp trajectory, pick/drop instants",
    spec_model="synthesis.kinds.picker.spec:PickerSpec",
    check="synthesis.kinds.picker.combined:run_check",
    figures={"trajectory.png": "synthesis.kinds.picker.plots:picker_figure",
             "trajectory.svg": "synthesis.kinds.picker.plots:picker_figure",
             "animation.gif": "synthesis.kinds.picker.plots:picker_animation",
             "paths.csv": "synthesis.kinds.picker.export:write_picker_csv",
             "linkage.dxf": "synthesis.kinds.picker.export:write_picker_dxf"},
    compare="synthesis.report.trajectory_overlay:trajectory_overlay",
    example="picker/cai2020_picker.toml",
    coarse_check="synthesis.kinds.picker.coarse:PICKER",
)


def double_crank_bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "picker/picker_double_crank_redesign.toml",
            "picker/picker_double_crank_retrofit.toml",
    ])
