"""Issue 20 study (``pytest -m benchmark``): the planting redesign of example 1, nominal vs tolerance-robust,
Monte-Carlo at +-0.2 mm / +-0.3 deg over 10,000 samples (seed 0)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from synthesis import kinds
from synthesis.spec import load_spec
from synthesis.tolerance.analysis import linearise, monte_carlo
from synthesis.tolerance.design import box_of
from synthesis.tolerance.robust import robust_kind

LIBRARY = Path(__file__).resolve().parents[1] / "problems" / "planting_arm"


@pytest.mark.benchmark
def test_robust_planting_redesign_passes_99_percent_of_10000_samples():
    rates, objectives = {}, {}
    for name in ("redesign_from_example1", "robust_redesign_from_example1"):
        loaded = load_spec(LIBRARY / f"{name}.toml")
        kind = robust_kind(kinds.get(loaded.kind), loaded.model)
        from synthesis.core.solve import run_solve
        result, _, _ = run_solve(kind, loaded, None, None, 2, lambda r, b: None, None)
        assert result.status == "optimal"
        lin = linearise(kind, loaded.model, result.design)
        box = box_of(lin.dmap, 0.2, 0.3, {})
        rates[name] = monte_carlo(kind, loaded.model, lin.design, lin.dmap, box, 10_000, seed=0)["pass_rate"]
        objectives[name] = result.objective["value"]
    print(f"\nMonte-Carlo pass rate at +-0.2 mm / +-0.3 deg, 10,000 samples (seed 0): {rates}; objective {objectives}")
    assert rates["robust_redesign_from_example1"] >= 0.99
    assert rates["redesign_from_example1"] < 0.9
    assert objectives["robust_redesign_from_example1"] > objectives["redesign_from_example1"]
