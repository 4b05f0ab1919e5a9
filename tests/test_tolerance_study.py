"""The tolerance study (``pytest -m benchmark``): the planting redesigns of examples 1 to 4, nominal vs
tolerance-robust, Monte-Carlo at +-0.2 mm / +-0.3 deg (seed 0)."""

from __future__ import annotations

from pathlib import Path

import pytest

from synthesis import kinds
from synthesis.spec import load_spec
from synthesis.tolerance.analysis import linearise, monte_carlo
from synthesis.tolerance.design import box_of
from synthesis.tolerance.robust import robust_kind

LIBRARY = Path(__file__).resolve().parents[1] / "problems" / "planting_arm"


@pytest.mark.benchmark
@pytest.mark.parametrize("example", [1, 2, 3, 4])
def test_robust_planting_redesign_passes_99_percent_of_the_samples(example):
    """Each example on 10,000 samples, the issue's count (example 1 about 13 min; example 4 about 6 min: solve
    170 s, Monte-Carlo 150 s on one worker)."""
    samples = 10_000
    rates, objectives = {}, {}
    nominal, robust = f"redesign_from_example{example}", f"robust_redesign_from_example{example}"
    for name in (nominal, robust):
        loaded = load_spec(LIBRARY / f"{name}.toml")
        kind = robust_kind(kinds.get(loaded.kind), loaded.model)
        from synthesis.core.solve import run_solve
        result, _, _ = run_solve(kind, loaded, None, None, 2, lambda r, b: None, None)
        assert result.status == "optimal"
        lin = linearise(kind, loaded.model, result.design)
        box = box_of(lin.dmap, 0.2, 0.3, {})
        rates[name] = monte_carlo(kind, loaded.model, lin.design, lin.dmap, box, samples, seed=0)["pass_rate"]
        objectives[name] = result.objective["value"]
    print(f"\nMonte-Carlo pass rate at +-0.2 mm / +-0.3 deg, {samples} samples (seed 0): {rates}; objective {objectives}")
    assert rates[robust] >= 0.99
    assert rates[nominal] < 0.9
    assert objectives[robust] > objectives[nominal]


@pytest.mark.benchmark
def test_robust_envelope_redesign_passes_99_percent_over_the_speed_range():
    """The tolerance box and the forward-speed range in one spec: 2,000 samples, each re-checked at 0.6 m/s and at
    every 0.01 m/s of 0.50-0.75 (about 20 min on one core).  Measured: 100.00 %, objective 0.642082 with point_gap = 5,
    before the box held the points' order; now 0.643702 (GEOMETRY.md)."""
    from synthesis.core.solve import run_solve
    loaded = load_spec(LIBRARY / "robust_envelope_redesign_from_example1.toml")
    kind = robust_kind(kinds.get(loaded.kind), loaded.model)
    result, _, _ = run_solve(kind, loaded, None, None, 2, lambda r, b: None, None)
    assert result.status == "optimal"
    lin = linearise(kind, loaded.model, result.design)
    box = box_of(lin.dmap, 0.2, 0.3, {})
    mc = monte_carlo(kind, loaded.model, lin.design, lin.dmap, box, 2_000, seed=0)
    print(f"\nover the box and 0.50-0.75 m/s, 2000 samples (seed 0): {mc['pass_rate']:.2%}; objective "
          f"{result.objective['value']:.6f}")
    assert mc["envelope"]["points"] == 26
    assert mc["pass_rate"] >= 0.99
    assert result.objective["value"] > 0.610599       # the price over the robust-only redesign of example 1
