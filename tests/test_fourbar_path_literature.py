"""fourbar_path on the literature's target sets: the transcribed published linkages, the source's
convention against ours, the specs, a 16-start solve against the best published linkage, the bench's cases.
Sources and readings: synthesis/kinds/fourbar_path/literature.py, problems/fourbar_path/LITERATURE.md."""

from __future__ import annotations

import math

import numpy as np
import pytest

from solving import run_solve
from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.kinds.fourbar_path.literature import (BEST_KNOWN, LENGTH_FLOOR, NAMES, PROBLEMS, best_published,
                                               evaluate_competitor, literature_data, literature_spec)
from synthesis.kinds.fourbar_path.kinematics import VARIABLES


def _hcdj(name):
    return next(c for c in PROBLEMS[name].competitors if c.label.startswith("HCDJ"))


def _source_point(values, theta2):
    """The source's coupler point (REPO Objf*.m / CheckCASE*.m, line by line): theta3 from the half-angle
    tangent with the minus root, the coupler point in the crank frame, turned by theta0, shifted to (x0, y0)."""
    r1, r2, r3, r4, rcx, rcy, x0, y0, t0 = values
    k1, k4, k5 = r1 / r2, r1 / r3, (r4 ** 2 - r1 ** 2 - r2 ** 2 - r3 ** 2) / (2 * r3 * r2)
    d = math.cos(theta2) - k1 + k4 * math.cos(theta2) + k5
    e = -2 * math.sin(theta2)
    f = k1 + (k4 - 1) * math.cos(theta2) + k5
    t3 = (2 * np.arctan((-e - np.sqrt(complex(e * e - 4 * d * f))) / (2 * d))).real
    cx = r2 * math.cos(theta2) + rcx * math.cos(t3) - rcy * math.sin(t3)
    cy = r2 * math.sin(theta2) + rcx * math.sin(t3) + rcy * math.cos(t3)
    return complex(math.cos(t0) * cx - math.sin(t0) * cy + x0, math.sin(t0) * cx + math.cos(t0) * cy + y0)


def _angles(name, c):
    p = PROBLEMS[name]
    return np.array(p.crank_rad if p.crank_rad is not None else c.crank_rad, dtype=float)


def _objective(name, values, theta, branch):
    """Sum of squared distances with the textbook construction (the tests' oracle), angles in rad."""
    d = dict(zip(VARIABLES[:8], values[:8]))
    d["theta0"] = math.degrees(values[8])
    p = joint_positions(d, theta, branch)["P"]
    t = np.array([complex(*q) for q in PROBLEMS[name].points])
    return float(np.sum(np.abs(p - t) ** 2))


def _half_ulp(v: float, digits: int = 8) -> float:
    """Half a unit in the last place of v printed with ``digits`` significant digits (the sources' %.7e)."""
    return 0.0 if v == 0 else 0.5 * 10.0 ** (math.floor(math.log10(abs(v))) - (digits - 1))


@pytest.mark.parametrize("name", NAMES)
def test_hcdj_linkage_reproduces_its_recorded_objective_within_the_rounding_of_its_digits(name):
    """HCDJ's best linkage (x_best_HCDJ_Case*.txt, 8 significant digits) scored with our objective equals the
    objective its authors recorded for it (Records_HCDJ_Case*.txt, 8 significant digits) to within what the
    rounding of the printed digits can move it: sum |df/dx_i| * half-ulp(x_i) (first order, central differences)
    plus half an ulp of the recorded figure."""
    c = _hcdj(name)
    score = evaluate_competitor(name, c)
    theta = _angles(name, c)
    x = np.array(list(c.values) + list(theta), dtype=float)
    free = [isinstance(PROBLEMS[name].bounds[n], list) for n in VARIABLES] + [PROBLEMS[name].crank_rad is None] * len(theta)

    def f(v):
        return _objective(name, v[:9], v[9:], c.branch)

    h = 1e-7
    grad = np.array([(f(x + h * e) - f(x - h * e)) / (2 * h) for e in np.eye(len(x))])
    bound = float(np.sum(np.abs(grad) * [(_half_ulp(v) if fr else 0.0) for v, fr in zip(x, free)]))
    bound += _half_ulp(c.published_error)
    assert score.objective == pytest.approx(f(x), rel=1e-9)     # check.evaluate = the oracle
    assert abs(score.objective - c.published_error) <= bound
    expected = {"arc5_timed": (1.9239387e-06, 1.9239227e-06), "semicircle6_timed": (1.2162125, 1.2162122),
                "ellipse10": (4.2014343e-04, 4.2014375e-04)}[name]
    assert (score.objective, c.published_error) == pytest.approx(expected, rel=1e-7)


def test_the_sources_formula_is_our_open_branch_for_every_competitor():
    """Every transcribed linkage: the source's coupler point (its own formula) equals our construction's on the
    open branch to 1e-9 at each target (1e-12 but for the two near-degenerate semicircle linkages, r2 ~ r3, near
    their toggle at 180 deg, where both formulae lose digits: 5e-10) -- but one, column 4 of CheckCase5, which the
    source's formula puts 436 units^2 off and our crossed branch 0.00297 (a linkage of the other assembly)."""
    crossed = []
    for name in NAMES:
        t = np.array([complex(*q) for q in PROBLEMS[name].points])
        for c in PROBLEMS[name].competitors:
            theta = _angles(name, c)
            source = np.array([_source_point(c.values, a) for a in theta])
            d = dict(zip(VARIABLES[:8], c.values[:8]))
            d["theta0"] = math.degrees(c.values[8])
            ours = joint_positions(d, theta, 1)["P"]
            if c.branch == 1:
                assert np.max(np.abs(ours - source)) < 1e-9, (name, c.label)
            else:
                crossed.append(c.label)
                assert float(np.sum(np.abs(source - t) ** 2)) == pytest.approx(436.41122, rel=1e-6)
                assert evaluate_competitor(name, c).objective == pytest.approx(0.0029668428, rel=1e-7)
    assert crossed == ["CheckCase5 column 4"]


def test_published_linkages_scored_with_our_objective_and_rules():
    """The competitors' objectives (the problem's units^2) and rule verdicts as the bench reports them."""
    got = {(n, c.label): evaluate_competitor(n, c) for n in NAMES for c in PROBLEMS[n].competitors}
    expect = {("arc5_timed", "Cabrera et al. 2002"): 1.8270339e-06,
              ("arc5_timed", "Kunjur & Krishnamurty"): 9.5264032e-04,
              ("arc5_timed", "MUMSA"): 1.2840007e-06, ("arc5_timed", "IOA"): 4.2704392e-06,
              ("semicircle6_timed", "CheckCASE4 column 3"): 2.5803556,
              ("semicircle6_timed", "CheckCASE4 column 4"): 1.2162211,
              ("ellipse10", "CheckCase5 column 1"): 4.7664687e-03,
              ("ellipse10", "CheckCase5 column 3"): 4.0199221e-04}
    for key, value in expect.items():
        assert got[key].objective == pytest.approx(value, rel=1e-7), key
    # every rule holds for all but HCDJ's semicircle linkage: its printed digits break Grashof by 8e-7
    broken = {k for k, s in got.items() if not s.rules_hold}
    assert broken == {("semicircle6_timed", "HCDJ (Nguyen-Van et al. 2022)")}
    grashof = next(r.record() for r in got[("semicircle6_timed", "HCDJ (Nguyen-Van et al. 2022)")].evaluation.rules
                   if r.name == "grashof")
    assert grashof.margin == pytest.approx(-8e-7, abs=1e-9)
    # column 6 of CheckCASE4 has r1 = 60, r4 = 58.1 past the problem's 50: out of the running
    assert got[("semicircle6_timed", "CheckCASE4 column 6")].outside == ["r1", "r4"]
    best = {n: (best_published(n).competitor.label, best_published(n).objective) for n in NAMES}
    assert best == {"arc5_timed": ("MUMSA", pytest.approx(1.2840007e-06, rel=1e-7)),
                    "semicircle6_timed": ("CheckCASE4 column 4", pytest.approx(1.2162211, rel=1e-7)),
                    "ellipse10": ("CheckCase5 column 3", pytest.approx(4.0199221e-04, rel=1e-7))}
    # free timing: at the nearest points of the coupler curve instead of the published angles
    near = evaluate_competitor("ellipse10", "CheckCase5 column 3", "nearest")
    assert near.objective == pytest.approx(4.0199211e-04, rel=1e-7) and near.rules_hold


def test_the_specs_validate_with_the_sources_ranges_timing_and_rules():
    for name in NAMES:
        spec = literature_spec(name).model
        p = PROBLEMS[name]
        assert spec.targets.points == [tuple(map(float, q)) for q in p.points]
        assert spec.timed == (p.crank_rad is not None)
        assert spec.rules.grashof_class == "crank_rocker" and spec.rules.order and spec.rules.transmission_angle is None
        assert spec.branch == "open"
        for n in ("r1", "r2", "r3", "r4"):
            assert spec.linkage.__getattribute__(n).bounds[0] == LENGTH_FLOOR
    a = literature_spec("arc5_timed").model
    assert a.targets.crank_deg == pytest.approx([30, 45, 60, 75, 90], abs=1e-12)
    assert all(literature_data("arc5_timed")["linkage"][n] == 0.0 for n in ("x0", "y0", "theta0"))
    assert a.bounds_array()[:6] == [(LENGTH_FLOOR, 50.0)] * 4 + [(-50.0, 50.0)] * 2
    s = literature_spec("semicircle6_timed").model
    assert s.targets.crank_deg == pytest.approx([30, 60, 90, 120, 150, 180], abs=1e-12)
    e = literature_spec("ellipse10").model
    assert e.targets.crank_deg is None and e.bounds_array() == [(LENGTH_FLOOR, 80.0)] * 4 + [(-80.0, 80.0)] * 4 + [(0.0, 360.0)]
    assert e.targets.points[0] == e.targets.points[-1]           # the closed loop's first point repeated last
    assert set(BEST_KNOWN) == set(NAMES)


@pytest.mark.slow
def test_16_starts_with_every_rule_reach_the_best_published_linkage():
    """16 starts, seed 0, one worker: each problem's best is at or below every published linkage (rules holding
    on the fine grid) and at the best known of the recorded 64- and 512-start runs."""
    for name in NAMES:
        result, _, _ = run_solve(literature_spec(name, {"starts": 16}), workers=1)
        best = result.objective["value"]
        assert result.status in ("optimal", "feasible") and result.fine_grid_worst_violation == 0.0
        assert best <= best_published(name).objective
        assert best <= _hcdj(name).published_error
        assert best == pytest.approx(BEST_KNOWN[name], rel=1e-6)
    # the margins: arc5 42 % below the best published (1.284e-6), the others at the published optimum
    assert BEST_KNOWN["arc5_timed"] / best_published("arc5_timed").objective == pytest.approx(0.57755, abs=1e-4)


def test_the_bench_runs_the_published_linkage_beside_the_solvers():
    from synthesis.kinds.fourbar_path.bench import DE_EQUAL_BUDGET, bench_cases, literature_cases

    cases = literature_cases(0)
    assert [c.problem for c in cases] == [f"literature_{n}" for n in NAMES]
    for c in cases:
        assert list(c.methods) == ["ipopt_multistart", "differential_evolution", DE_EQUAL_BUDGET, "published"]
        assert c.single_runs == {"published"}
        assert c.tolerance(c.best_known) == pytest.approx(1e-6 * c.best_known)
    run = cases[0].methods["published"](BEST_KNOWN["arc5_timed"])
    assert run.objective == pytest.approx(1.2840007e-06, rel=1e-7) and run.worst_violation == 0.0
    assert run.trace == [(0.0, run.objective)] and run.details["competitor"] == "MUMSA"
    # scored, not solved: the bench prints its status instead of a time ratio
    assert run.details["return_status"].startswith("not run")
    assert run.details["all_competitors"]["HCDJ (Nguyen-Van et al. 2022)"]["objective"] == pytest.approx(1.9239387e-06,
                                                                                                         rel=1e-7)
    names = [c.problem for c in bench_cases(None, 0)]
    assert [n for n in names if n.startswith("literature_")] == [f"literature_{n}" for n in NAMES]
