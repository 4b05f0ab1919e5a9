"""Kind crank_rocker: synthesis of a crank-rocker from K, rocker swing and minimum transmission angle."""

from synthesis.core.kind import Kind

KIND = Kind(
    name="crank_rocker",
    summary="crank-rocker from time ratio K, swing and minimum transmission angle (seed 001 §2.1.3)",
    spec_model="synthesis.spec.crank_rocker:CrankRockerSpec",
    check="synthesis.crank_rocker.check:run_check",
    figures={"extremes.png": "synthesis.crank_rocker.plots:extremes_figure"},
    compare="synthesis.crank_rocker.plots:compare_figure",
    solving="synthesis.crank_rocker.solve:SOLVING",
    objectives={"min_total_length": "smallest l7 + l8 + l9 + l10, mm",
                "max_transmission_angle": "largest smallest transmission angle over a turn, deg"},
    example="picker/cai2020_crank_rocker_synthesis.toml",
)
