"""Benchmarks (not run by default; `pytest -m benchmark`): one local solve and a 32-start multistart."""

from __future__ import annotations

import pytest

from conftest import PLANTING
from synthesis import kinds
from synthesis.core.solve import run_solve
from synthesis.core.kind import Setting
from synthesis.spec import load_spec

pytestmark = pytest.mark.benchmark


def test_bench_one_local_solve(benchmark):
    spec = load_spec(PLANTING / "redesign_from_example1.toml").model
    nlp = kinds.get("planting_fourbar").solving().build(Setting(spec))
    out = benchmark(nlp.solve, 0, nlp.init)
    benchmark.extra_info["iterations"] = out.iterations
    assert out.success


@pytest.mark.parametrize("workers", [1, 2])
def test_bench_32_start_multistart(benchmark, workers):
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    result, _, _ = benchmark.pedantic(run_solve, args=(kinds.get("planting_fourbar"), loaded, 32, 0, workers),
                                      rounds=3, iterations=1)
    assert result.status == "optimal"
