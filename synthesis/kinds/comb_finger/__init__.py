"""Kind comb_finger: the eccentric rotating comb fingers of seed 002 §四.3 (eq 14-22, Fig. 26-28).

geometry.py  the front view of Fig. 28b reconstructed, eq 17-22 derived and as printed (floats, CasADi)
check.py, nlp.py, solve.py, plots.py: the kind of the CLI
"""

from synthesis.core.kind import Kind

KIND = Kind(
    name="comb_finger",
    summary="eccentric rotating comb fingers: largest combing angle with root-zone and unit clearances "
            "(seed 002 §四.3 eq 17-22)",
    spec_model="synthesis.kinds.comb_finger.spec:CombFingerSpec",
    check="synthesis.kinds.comb_finger.check:run_check",
    figures={"comb_finger.png": "synthesis.kinds.comb_finger.plots:finger_figure",
             "comb_finger.svg": "synthesis.kinds.comb_finger.plots:finger_figure"},
    compare="synthesis.kinds.comb_finger.plots:compare_figure",
    solving="synthesis.kinds.comb_finger.solve:SOLVING",
    bench="synthesis.kinds.comb_finger:bench_cases",
    objectives={"max_combing_angle": "largest combing angle theta at the machine speed (eq 21), deg"},
    example="comb_finger/redesign_max_combing.toml",
    coarse_check="synthesis.kinds.comb_finger.coarse:COARSE",
    poses="synthesis.kinds.comb_finger.poses:POSES",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "comb_finger/redesign_max_combing.toml",
            "comb_finger/redesign_tip_speed.toml",
    ])
