"""Scale (issue 18's extreme matrix): the crank-rocker library synthesis with every length x 1e-3
(metres instead of mm) and x 1e3, against the same problem in mm.

The rules are angles and a time ratio (scale-free), the objective is the total length, so the
optimum scales exactly.  IPOPT sees every variable at its nominal scale (synthesis.core.ipopt): a box
of width 0.195 m or 1.95e5 is mapped to the same 195 z-units as the mm problem's 195 mm, and the
objective to its own unit power at the start.  What is not mapped: rows in length units (the crank-
rocker's length bounds held as rows) stay x k, and absolute margins of the kind (the crank_rocker
start pull-in of 1 mm, the Grashof slack floor of 1e-6) do not scale, so the library's random starts
differ in z between the three problems; the second test therefore also gives IPOPT the same eight
starts mapped to each unit.
"""

from __future__ import annotations

import math
import re
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

from synthesis.core import ipopt
from synthesis.spec import load_spec

ROOT = Path(__file__).resolve().parents[2]
SYNTHESIS = ROOT / "problems" / "picker" / "cai2020_crank_rocker_synthesis.toml"
#: the mm problem's optimum (tests/test_library.py records the total 435.13428762281086 mm)
MM_OPTIMUM = {"l7": 54.040295283, "l8": 107.627164354, "l9": 133.466827986}
MM_TOTAL = 435.13428762281086
#: start 0 of the mm problem (the spec's own start): Solve_Succeeded in 8 iterations
MM_ITERATIONS = 8


def scaled_spec(tmp_path: Path, k: float) -> Path:
    """The library spec with every length (inits, bounds, the fixed frame) times k."""
    text = SYNTHESIS.read_text()
    text, n = re.subn(r"(l\d+ = \{ init = )([\d.]+), bounds = \[([\d.]+), ([\d.]+)\]",
                      lambda m: f"{m.group(1)}{float(m.group(2)) * k!r}, bounds = [{float(m.group(3)) * k!r}, "
                                f"{float(m.group(4)) * k!r}]", text)
    assert n == 3 and "l10 = 140.0" in text
    path = tmp_path / f"scaled_{k:g}.toml"
    path.write_text(text.replace("l10 = 140.0", f"l10 = {140.0 * k!r}"))
    return path


@pytest.mark.parametrize("k", [1e-3, 1e3])
def test_scaled_lengths_solve_to_the_scaled_design(tmp_path, k, record_property):
    """The library's own multistart (8 starts) in metres (x 1e-3) and x 1e3: the best design / k is the mm
    optimum within 1e-7 relative (IPOPT stops at tol 1e-9 on the objective's own scale, which in metres is
    1e-3 of the mm one and not scaled up: measured 1.4e-8), and start 0 -- the spec's start, the same z as
    in mm -- converges in at most 2 x the mm problem's 8 iterations."""
    sys.path.insert(0, str(ROOT / "tests"))
    from solving import run_solve

    result, reports, _ = run_solve(load_spec(scaled_spec(tmp_path, k)), workers=1)
    assert result.status == "optimal"
    worst = max(abs(result.design[n] / k - v) / v for n, v in MM_OPTIMUM.items())
    assert worst < 1e-7
    assert result.objective["value"] / k == pytest.approx(MM_TOTAL, rel=1e-7)
    iterations = reports[0].outcome.iterations
    assert reports[0].outcome.success and iterations <= 2 * MM_ITERATIONS
    record_property("figure", f"x{k:g}: best design / k within {worst:.0e} relative of the mm optimum; start 0 "
                              f"{iterations} iterations (mm {MM_ITERATIONS}, ratio {iterations / MM_ITERATIONS:.2f}); "
                              f"{sum(r.outcome.success for r in reports)} of {len(reports)} starts converged")


def _same_starts(k_values, scaling: str):
    """Eight random lengths in the mm box (seeded), pulled inside the crank-rocker region and given their
    simulated extremes in mm, then mapped to each unit (lengths x k, angles as they are) and solved by
    each unit's CompiledNLP: {k: [(converged to the optimum, iterations)]}."""
    from synthesis.crank_rocker.nlp import COORDINATES, CrankRockerNLP

    rng = np.random.default_rng(0)
    out = {}
    with ipopt.variable_scaling(scaling), tempfile.TemporaryDirectory() as folder:
        mm = CrankRockerNLP(load_spec(scaled_spec(Path(folder), 1.0)).model)
        starts = []
        for _ in range(8):
            lengths = mm.prepared_start(np.concatenate([rng.uniform(mm.bounds[:3, 0], mm.bounds[:3, 1]), [140.0]]))
            starts.append(np.concatenate([lengths, mm.extremes_guess(lengths)]))
        for k in k_values:
            nlp = CrankRockerNLP(load_spec(scaled_spec(Path(folder), k)).model)
            rows = []
            for i, x in enumerate(starts):
                xk = x.copy()
                xk[:4] *= k
                res = nlp.compiled.solve(i, COORDINATES.coordinates(xk))
                total = float(np.sum(COORDINATES.design(res.x[:6])[:4])) / k
                rows.append((res.success and abs(total - MM_TOTAL) < 1e-6 * MM_TOTAL, res.iterations))
            out[k] = rows
    return out


def test_the_same_starts_in_every_unit_reach_the_optimum(record_property):
    """The same eight starts in mm, metres and x 1e3, IPOPT on the nominally scaled NLP: in each unit at
    least as many starts reach the optimum (1e-6 relative) as in mm, and the median iterations of those
    that do is within 2 x the mm median (the rows in length units still differ by k: 'comparable', not
    'equal').  The figure also gives the raw variables (no nominal scaling) for comparison."""
    ks = [1.0, 1e-3, 1e3]
    nominal = _same_starts(ks, "nominal")
    raw = _same_starts(ks, "none")
    reached = {k: sum(ok for ok, _ in rows) for k, rows in nominal.items()}
    median = {k: statistics.median(it for ok, it in rows if ok) for k, rows in nominal.items()}
    for k in (1e-3, 1e3):
        assert reached[k] >= reached[1.0]
        assert median[k] <= 2 * median[1.0]
    raw_reached = {k: sum(ok for ok, _ in rows) for k, rows in raw.items()}
    record_property("figure", "starts reaching the optimum of 8, nominal (raw): " + ", ".join(
        f"x{k:g} {reached[k]} ({raw_reached[k]}), median {median[k]:g} it (ratio {median[k] / median[1.0]:.2f})"
        for k in ks))


def test_nominal_scale_is_the_unit_power_of_each_box():
    """s = 1000**floor(log10(size) / 3): the mm box of this problem is left alone, its metre and x 1e3
    versions get 1e-3 and 1e3; an unboxed variable follows its start only once a box was scaled."""
    sizes = [0.195, 195.0, 1.95e5, 1.0, 999.9, 1000.0, 1e-3, 0.0, math.inf]
    assert ipopt.unit_power(sizes).tolist() == [1e-3, 1.0, 1e3, 1.0, 1.0, 1e3, 1e-3, 1.0, 1.0]
    lb, ub = np.array([5.0, 1e-6, -4 * math.pi]), np.array([200.0, math.inf, 6 * math.pi])
    w0 = np.array([50.0, 50.0, 1.0])
    assert ipopt.nominal_scale(lb, ub, w0).tolist() == [1.0, 1.0, 1.0]          # mm: nothing to scale
    k = np.array([1e-3, 1e-3, 1.0])
    assert ipopt.nominal_scale(lb * k, ub * k, w0 * k).tolist() == [1e-3, 1e-3, 1.0]   # metres: the slack too
    assert ipopt.nominal_scale(lb, ub, np.array([50.0, 5e4, 1.0])).tolist() == [1.0, 1e3, 1.0]
    with pytest.raises(ValueError):
        with ipopt.variable_scaling("log"):
            pass
