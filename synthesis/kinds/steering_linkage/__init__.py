"""Kind steering_linkage: the Ackermann steering trapezoid of seed 002 (Hwang, Model-3 peanut combine, Table 12).

table12.py  the published table explained: kingpin spacing, the inconsistent row, the trapezoid fit, radius
check.py    rules on floats or symbols (one function), the given trapezoid over 0 .. the maximum lock
nlp.py      minimax steering error as a smooth epigraph, outer locks as variables closing the loop
solve.py    the solve side (SOLVING); plots.py the figures (from result data only)
"""

from synthesis.core.kind import Kind

KIND = Kind(
    name="steering_linkage",
    summary="Ackermann steering trapezoid: Table 12 explained, minimax steering error (seed 002 Table 12)",
    spec_model="synthesis.kinds.steering_linkage.spec:SteeringSpec",
    check="synthesis.kinds.steering_linkage.check:run_check",
    figures={"steering.png": "synthesis.kinds.steering_linkage.plots:steering_figure",
             "steering.svg": "synthesis.kinds.steering_linkage.plots:steering_figure",
             "paths.csv": "synthesis.kinds.steering_linkage.export:write_paths_csv",
             "linkage.dxf": "synthesis.kinds.steering_linkage.export:write_linkage_dxf"},
    compare="synthesis.kinds.steering_linkage.plots:compare_figure",
    solving="synthesis.kinds.steering_linkage.solve:SOLVING",
    bench="synthesis.kinds.steering_linkage:bench_cases",
    objectives={"min_max_error": "smallest largest |outside lock - Ackermann| over 0 .. the maximum inside lock, deg"},
    example="steering/steering_redesign_40.toml",
    coarse_check="synthesis.kinds.steering_linkage.coarse:COARSE",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "steering/steering_redesign_40.toml",
            "steering/steering_redesign_27.toml",
    ])
