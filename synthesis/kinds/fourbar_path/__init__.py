"""Kind fourbar_path: any four-bar coupler point through N target points, timing prescribed or free."""

from synthesis.core.kind import Kind

KIND = Kind(
    name="fourbar_path",
    summary="any four-bar coupler point through N target points, timing prescribed or free",
    spec_model="synthesis.kinds.fourbar_path.spec:FourbarPathSpec",
    check="synthesis.kinds.fourbar_path.check:run_check",
    figures={"coupler_curve.png": "synthesis.kinds.fourbar_path.plots:coupler_curve_figure",
             "coupler_curve.svg": "synthesis.kinds.fourbar_path.plots:coupler_curve_figure",
             "linkage.gif": "synthesis.kinds.fourbar_path.plots:linkage_animation",
             "paths.csv": "synthesis.kinds.fourbar_path.export:write_paths_csv",
             "linkage.dxf": "synthesis.kinds.fourbar_path.export:write_linkage_dxf"},
    compare="synthesis.kinds.fourbar_path.plots:compare_coupler_curves",
    solving="synthesis.kinds.fourbar_path.solve:SOLVING",
    objectives={"sum_squared_distance": "sum of squared distances of the coupler point to the targets, mm^2 "
                                        "([solver] stop_at_objective ends the multistart at the first start, "
                                        "in start order, that reaches it)"},
    bench="synthesis.kinds.fourbar_path.bench:bench_cases",
    example="fourbar_path/picking_arc.toml",
    coarse_check="synthesis.kinds.fourbar_path.coarse:COARSE",
    poses="synthesis.kinds.fourbar_path.poses:POSES",
)
