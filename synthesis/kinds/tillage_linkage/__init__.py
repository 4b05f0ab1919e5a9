"""Kind tillage_linkage: the distorted rotary tillage linkage of seed 002 (Hwang, §四.2, eq 3-11, Figs. 18-20).

printed.py  eq 3-11 as printed (our reading of the OCR), held against the geometry and against AD
check.py    rules on floats or symbols (one function), the given linkage over a crank turn
nlp.py      extremes and soil entry/exit as NLP variables with exact structural rows
solve.py    the solve side (SOLVING); plots.py the figures (from result data only)
"""

from synthesis.core.kind import Kind

KIND = Kind(
    name="tillage_linkage",
    summary="distorted rotary tillage linkage: crank, bar through a roller pair, tool path (seed 002 eq 3-11)",
    spec_model="synthesis.kinds.tillage_linkage.spec:TillageSpec",
    check="synthesis.kinds.tillage_linkage.check:run_check",
    figures={"tillage.png": "synthesis.kinds.tillage_linkage.plots:tillage_figure",
             "tillage.svg": "synthesis.kinds.tillage_linkage.plots:tillage_figure",
             "paths.csv": "synthesis.kinds.tillage_linkage.export:write_paths_csv",
             "linkage.dxf": "synthesis.kinds.tillage_linkage.export:write_linkage_dxf"},
    compare="synthesis.kinds.tillage_linkage.plots:compare_figure",
    solving="synthesis.kinds.tillage_linkage.solve:SOLVING",
    bench="synthesis.kinds.tillage_linkage:bench_cases",
    objectives={"min_bar_length": "shortest tillage bar c meeting every rule, mm",
                "max_margin": "largest smallest normalised rule margin (the design deepest inside every rule)"},
    example="tillage/tillage_redesign.toml",
    coarse_check="synthesis.kinds.tillage_linkage.coarse:COARSE",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "tillage/tillage_redesign.toml",
    ])
