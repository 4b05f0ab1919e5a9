"""Kind fourbar_path: any four-bar coupler point through N target points, timing prescribed or free."""

from synthesis.core.kind import Kind

KIND = Kind(
    name="fourbar_path",
    summary="any four-bar coupler point through N target points, timing prescribed or free",
    spec_model="synthesis.spec.fourbar_path:FourbarPathSpec",
    check="synthesis.fourbar_path.check:run_check",
    figures={"coupler_curve.png": "synthesis.fourbar_path.plots:coupler_curve_figure",
             "coupler_curve.svg": "synthesis.fourbar_path.plots:coupler_curve_figure",
             "linkage.gif": "synthesis.fourbar_path.plots:linkage_animation",
             "paths.csv": "synthesis.fourbar_path.export:write_paths_csv",
             "linkage.dxf": "synthesis.fourbar_path.export:write_linkage_dxf"},
    compare="synthesis.fourbar_path.plots:compare_coupler_curves",
    solving="synthesis.fourbar_path.solve:SOLVING",
    objectives={"sum_squared_distance": "sum of squared distances of the coupler point to the targets, mm^2 "
                                        "([solver] stop_at_objective ends the multistart at the first start, "
                                        "in start order, that reaches it)"},
    bench="synthesis.fourbar_path.bench:bench_cases",
    example="fourbar_path/picking_arc.toml",
    coarse_check="synthesis.fourbar_path.coarse:COARSE",
    poses="synthesis.fourbar_path.poses:POSES",
)
