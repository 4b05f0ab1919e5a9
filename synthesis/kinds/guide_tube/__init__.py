"""Guide tubes of seed 001 §2.4: wall angles that make every pot seedling land at the same time.

drag.py   closed forms of straight-line motion with quadratic drag (floats and CasADi symbols)
drop.py   the five-phase drop through one tube (eq 13-23), closed form
slope.py  the analytic derivative dt_z/d(delta) of the closed form (checks CasADi's AD)
ode.py    the same drop integrated with scipy solve_ivp, phase switches as events
printed.py eq 17/19/21 exactly as printed (superposition reading), for the readings study
calibrate.py friction coefficient from a measured landing time
scene.py, check.py, nlp.py, solve.py, plots.py: the guide_tube kind of the CLI
"""

from synthesis.core.kind import Kind

KIND = Kind(
    name="guide_tube",
    summary="guide-tube wall angles for equal landing times (seed 001 §2.4)",
    spec_model="synthesis.kinds.guide_tube.spec:GuideTubeSpec",
    check="synthesis.kinds.guide_tube.check:run_check",
    figures={"drop_times.png": "synthesis.kinds.guide_tube.plots:drop_times_figure",
             "drop_times.svg": "synthesis.kinds.guide_tube.plots:drop_times_figure",
             "drop_profiles.png": "synthesis.kinds.guide_tube.plots:drop_profile_figure",
             "sensitivity.png": "synthesis.kinds.guide_tube.plots:sensitivity_figure"},
    compare="synthesis.kinds.guide_tube.plots:compare_figures",
    solving="synthesis.kinds.guide_tube.solve:SOLVING",
    bench="synthesis.kinds.guide_tube:bench_cases",
    objectives={"nearest": "smallest change of the free wall angles, deg^2",
                "fastest": "earliest landing of tube 1, ms",
                "uniform": "smallest worst plant-position error over the row spacings, mm"},
    example="guide_tube/cai2020_delta2.toml",
    coarse_check="synthesis.kinds.guide_tube.coarse:COARSE",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "guide_tube/cai2020_delta2.toml",
            "guide_tube/fastest_equal_time.toml",
    ])
