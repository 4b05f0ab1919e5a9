"""Benchmarks (not run by default; `pytest -m benchmark`): one clamp-cam NLP solve, a 32-start
multistart, and the optimised law's convex fit."""

from __future__ import annotations

import math

import pytest

from conftest import LIBRARY
from synthesis.core.kind import Setting
from synthesis.kinds.clamp_cam.solve import SOLVING
from solving import run_solve
from synthesis.spec import load_spec

pytestmark = pytest.mark.benchmark
SPEC = LIBRARY / "clamp_cam" / "opening_cam_redesign.toml"


def test_bench_one_local_solve(benchmark):
    nlp = SOLVING.build(Setting(load_spec(SPEC).model))
    out = benchmark(nlp.solve, 0, nlp.init)
    benchmark.extra_info["iterations"] = out.iterations
    assert out.success


@pytest.mark.parametrize("workers", [1, 2])
def test_bench_32_start_multistart(benchmark, workers):
    result, _, _ = benchmark.pedantic(run_solve, args=(load_spec(SPEC), 32, 0, workers), rounds=3, iterations=1)
    assert result.status == "optimal"


@pytest.mark.parametrize("spans", [16, 32, 64])
def test_bench_optimised_law_fit(benchmark, spans):
    from synthesis.kinds.clamp_cam.bspline_law import fit_optimised_law

    law = benchmark(fit_optimised_law, 10.0, {"rise": 40.0, "return": 14.0}, 2 * math.pi, "acceleration", spans)
    benchmark.extra_info["ratio_to_cycloidal"] = law.ratio_to_cycloidal["rise"]
    assert law.ratio_to_cycloidal["rise"] < 0.7
