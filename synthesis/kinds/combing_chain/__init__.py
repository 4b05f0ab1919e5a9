"""Kind combing_chain: the stem-combing chain of seed 002 §四.3 (Shimamoto; eq 12-13, Table 13).

geometry.py  eq 12-13 derived (floats and CasADi symbols) and as printed
check.py, nlp.py, solve.py, plots.py: the kind of the CLI
"""

from synthesis.core.kind import Kind

KIND = Kind(
    name="combing_chain",
    summary="stem-combing chain: chain speed(s) so every plant is combed into a window before the cut "
            "(seed 002 §四.3 eq 12-13)",
    spec_model="synthesis.kinds.combing_chain.spec:CombingChainSpec",
    check="synthesis.kinds.combing_chain.check:run_check",
    figures={"delta_over_beta.png": "synthesis.kinds.combing_chain.plots:delta_figure",
             "delta_over_beta.svg": "synthesis.kinds.combing_chain.plots:delta_figure"},
    compare="synthesis.kinds.combing_chain.plots:compare_figure",
    solving="synthesis.kinds.combing_chain.solve:SOLVING",
    bench="synthesis.kinds.combing_chain:bench_cases",
    objectives={"max_window_margin": "largest smallest margin of the plant angle before the cut to the window, deg",
                "min_chain_speed": "slowest chain(s) keeping every plant in the window: sum of gear speeds, m/s"},
    example="combing_chain/redesign_window_80_100.toml",
    coarse_check="synthesis.kinds.combing_chain.coarse:COARSE",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "combing_chain/redesign_window_80_100.toml",
            "combing_chain/redesign_two_speed.toml",
    ])
