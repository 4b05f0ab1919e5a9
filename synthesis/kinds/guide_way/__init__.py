"""Kind guide_way: the rotary-arm slide guide way of seed 003 (Liang et al.): claw path -> roller-centre line ->
the two walls of the groove, reproduced from the paper's conics and redesigned as a smooth spline."""

from synthesis.core.kind import Kind

KIND = Kind(
    name="guide_way",
    summary="rotary-arm slide guide way: claw path, roller-centre line, groove walls, undercut (seed 003)",
    spec_model="synthesis.kinds.guide_way.spec:GuideWaySpec",
    check="synthesis.kinds.guide_way.check:run_check",
    figures={"guide_way.png": "synthesis.kinds.guide_way.plots:guide_figure",
             "guide_way.svg": "synthesis.kinds.guide_way.plots:guide_figure",
             "cycle.png": "synthesis.kinds.guide_way.plots:cycle_figure",
             "animation.gif": "synthesis.kinds.guide_way.plots:animation",
             "centre_line.csv": "synthesis.kinds.guide_way.export:write_centre_csv",
             "walls.csv": "synthesis.kinds.guide_way.export:write_walls_csv",
             "guide_way.dxf": "synthesis.kinds.guide_way.export:write_dxf"},
    compare="synthesis.kinds.guide_way.plots:compare_figures",
    solving="synthesis.kinds.guide_way.solve:SOLVING",
    bench="synthesis.kinds.guide_way:bench_cases",
    objectives={"smoothness": "the claw path's squared third derivative, relative to the convex fit's"},
    example="guide_way/smooth_redesign.toml",
    explicit_design="synthesis.kinds.guide_way.check:explicit_design",
    coarse_check="synthesis.kinds.guide_way.coarse:COARSE",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "guide_way/smooth_redesign.toml",
    ])
