"""Kind crank_rocker: synthesis of a crank-rocker from K, rocker swing and minimum transmission angle."""

from synthesis.core.kind import Kind

KIND = Kind(
    name="crank_rocker",
    summary="crank-rocker from time ratio K, swing and minimum transmission angle (seed 001 §2.1.3)",
    spec_model="synthesis.kinds.crank_rocker.spec:CrankRockerSpec",
    check="synthesis.kinds.crank_rocker.check:run_check",
    figures={"extremes.png": "synthesis.kinds.crank_rocker.plots:extremes_figure",
             "extremes.svg": "synthesis.kinds.crank_rocker.plots:extremes_figure",
             "paths.csv": "synthesis.kinds.crank_rocker.export:write_paths_csv",
             "linkage.dxf": "synthesis.kinds.crank_rocker.export:write_linkage_dxf"},
    compare="synthesis.kinds.crank_rocker.plots:compare_figure",
    solving="synthesis.kinds.crank_rocker.solve:SOLVING",
    bench="synthesis.kinds.crank_rocker:bench_cases",
    objectives={"min_total_length": "smallest l7 + l8 + l9 + l10, mm",
                "max_transmission_angle": "largest smallest transmission angle over a turn, deg"},
    example="picker/cai2020_crank_rocker_synthesis.toml",
    coarse_check="synthesis.kinds.crank_rocker.coarse:COARSE",
    poses="synthesis.kinds.crank_rocker.poses:POSES",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "picker/cai2020_crank_rocker_synthesis.toml",
            "picker/crank_rocker_max_transmission.toml",
    ])
