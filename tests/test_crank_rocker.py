"""crank_rocker (seed 001 §2.1.3): the published lengths, the closed form of eq 8-10, the NLP on the
simulated mechanism, and the kinematics they rest on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import LIBRARY
from synthesis.kinds.crank_rocker.check import evaluate, mechanism, run_check
from synthesis.kinds.crank_rocker.closed_form import residuals, solve_paper_equations
from solving import diagnose_infeasible, recheck_rules, run_solve
from synthesis.kinematics.rocker_drive import (CrankRocker, acute, extreme_positions, quick_return, rocker_curve,
                                              transmission_angles_deg)
from synthesis.spec import load_spec

PICKER = LIBRARY / "picker"
#: seed 001 §2.1.3: K = 1.25, psi = 50 deg, gamma_min = 40 deg, l10 = 140 mm -> l7, l8, l9 (mm)
PUBLISHED = {"l7": 54.0, "l8": 107.6, "l9": 133.5}
#: half the last printed digit: l7 is printed to 1 mm (54), l8 and l9 to 0.1 mm (107.6, 133.5)
LENGTH_TOLERANCE = {"l7": 0.5, "l8": 0.05, "l9": 0.05}


def simulated(cr: CrankRocker) -> tuple[float, float, float]:
    """K, swing (deg) and minimum transmission angle (deg, 0.1 deg grid) of the simulated mechanism."""
    q = quick_return(cr)
    return q.time_ratio, math.degrees(q.swing), float(acute(transmission_angles_deg(cr, 3600)).min())


def test_published_lengths_simulate_to_the_published_requirements():
    k, psi, gmin = simulated(CrankRocker(54.0, 107.6, 133.5, 140.0))
    assert k == pytest.approx(1.25, abs=0.005)
    assert psi == pytest.approx(50.0, abs=0.1)
    assert gmin >= 40.0 - 0.1
    # what the printed (rounded) lengths do, pinned: K 1.25006, psi 49.951 deg, gamma_min 40.012 deg
    assert (k, psi, gmin) == pytest.approx((1.250055, 49.9506, 40.0119), abs=2e-4)


def test_extremes_are_stationary_and_bound_the_rocker_angle():
    cr = CrankRocker(54.0, 107.6, 133.5, 140.0)
    ex = extreme_positions(cr)
    at = rocker_curve(cr, np.array([ex.phi_folded, ex.phi_extended]))
    assert np.abs(at["dbeta"]).max() < 1e-12
    dense = rocker_curve(cr, np.linspace(0, 2 * np.pi, 20001))["beta"]
    assert dense.max() <= max(ex.beta_folded, ex.beta_extended) + 1e-12
    assert dense.min() >= min(ex.beta_folded, ex.beta_extended) - 1e-12
    # folded: |GE| = l8 - l7, extended: |GE| = l8 + l7 (textbook dead centres, used here only as a check)
    g_e = np.hypot(*at["tip"])
    assert g_e == pytest.approx([107.6 - 54.0, 107.6 + 54.0], abs=1e-9)


def test_rocker_derivative_by_ad_matches_central_differences():
    cr = CrankRocker(54.0, 107.6, 133.5, 140.0)
    phi = np.linspace(0.1, 6.2, 25)
    h = 1e-6
    fd = (rocker_curve(cr, phi + h)["beta"] - rocker_curve(cr, phi - h)["beta"]) / (2 * h)
    assert rocker_curve(cr, phi)["dbeta"] == pytest.approx(fd, abs=1e-7)


def test_closed_form_reproduces_the_published_lengths():
    designs = solve_paper_equations(1.25, 50.0, 40.0, 140.0)
    valid = [d for d in designs if d.min_transmission_deg is not None and d.min_transmission_deg >= 40.0 - 1e-6]
    shortest = valid[0]
    for name, value in PUBLISHED.items():
        assert getattr(shortest, name) == pytest.approx(value, abs=LENGTH_TOLERANCE[name])
    # the paper's eq (8)-(10) hold at the root, and the simulated mechanism agrees with them
    z = (shortest.l7, shortest.l8, shortest.l9, math.radians(shortest.theta1_deg))
    assert np.abs(residuals(z, 1.25, math.radians(50), math.radians(40), 140.0)).max() < 1e-10
    assert shortest.time_ratio == pytest.approx(1.25, abs=1e-9)
    assert shortest.swing_deg == pytest.approx(50.0, abs=1e-9)
    assert shortest.theta1_deg == pytest.approx(22.44, abs=0.01)       # printed as theta1 = 22 deg
    # the other root with gamma_min = 40 deg is longer; a third root meets eq (10) only, its true minimum
    # transmission angle (crank against the frame) is far below 40 deg
    assert len(valid) == 2 and valid[1].total_length > shortest.total_length + 5
    assert any(d.min_transmission_deg is not None and d.min_transmission_deg < 30 for d in designs)


@pytest.mark.slow
def test_nlp_reproduces_the_published_lengths_and_the_closed_form():
    loaded = load_spec(PICKER / "cai2020_crank_rocker_synthesis.toml")
    result, _, _ = run_solve(loaded, starts=4, workers=1)
    assert result.status == "optimal"
    d = result.design
    for name, value in PUBLISHED.items():
        assert d[name] == pytest.approx(value, abs=LENGTH_TOLERANCE[name])
    closed = result.extra["closed_form"]["shortest_valid"]
    for name in PUBLISHED:
        assert d[name] == pytest.approx(closed[name], abs=1e-3)
    # verified by simulating the returned lengths, independently of the solver
    k, psi, gmin = simulated(mechanism(loaded.model, d))
    assert k == pytest.approx(1.25, abs=0.005)
    assert psi == pytest.approx(50.0, abs=0.1)
    assert gmin >= 40.0 - 0.1
    rules = recheck_rules(loaded.model, d)
    assert all(r.record().satisfied for r in rules)


def test_largest_minimum_transmission_angle_is_where_the_eq10_roots_merge():
    loaded = load_spec(PICKER / "crank_rocker_max_transmission.toml")
    result, _, _ = run_solve(loaded, starts=3, workers=1)
    assert result.status == "optimal"
    best = result.objective["value"]
    k, psi, gmin = simulated(mechanism(loaded.model, result.design))
    assert gmin == pytest.approx(best, abs=1e-3)
    assert (k, psi) == pytest.approx((1.25, 50.0), abs=1e-6)
    assert best > 40.0
    # independent of the NLP: eq (8)-(10) have valid roots just below the optimum and none just above
    def valid_roots(g):
        return [x for x in solve_paper_equations(1.25, 50.0, g, 140.0)
                if x.min_transmission_deg is not None and x.min_transmission_deg >= g - 1e-6]
    assert len(valid_roots(best - 0.01)) == 2
    assert valid_roots(best + 0.01) == []


def test_check_of_a_crank_that_cannot_turn_reports_the_rules_unevaluated():
    loaded = load_spec(PICKER / "cai2020_crank_rocker.toml")
    cr = CrankRocker(150.0, 107.6, 133.5, 140.0)          # crank longer than the frame: no full turn
    rules, q = evaluate(loaded.model, cr)
    records = {r.name: r.record() for r in rules}
    assert q is None
    assert not records["grashof_crank_rocker"].satisfied
    assert records["time_ratio"].value is None and "cannot make a full turn" in records["time_ratio"].note


def test_check_result_facts():
    result = run_check(load_spec(PICKER / "cai2020_crank_rocker.toml"))
    m = result.extra["motion"]
    assert result.all_satisfied
    assert m["strokes_deg"]["folded_to_extended"] == pytest.approx(160.0, abs=0.01)     # 180 - theta, eq (8)
    assert m["extreme_crank_angle_deg"] == pytest.approx(20.0, abs=0.01)
    assert m["min_transmission_at_crank_deg"] == pytest.approx(0.0, abs=1e-9)         # eq (10): crank along AG


def test_a_crank_too_short_to_find_the_extremes_is_not_evaluated_not_a_crash(tmp_path):
    """Found by the fuzz test: l7 = 5e-324 mm passes Grashof, but the rocker has no extremes to root-find.
    A spec file can no longer hold such a number (the loader refuses subnormal magnitudes); a design that
    reaches the kinematics some other way gets K, swing and transmission reported as not evaluated, with the
    reason, instead of a ValueError."""
    from synthesis.errors import SpecError
    from synthesis.kinematics.rocker_drive import CrankRocker

    text = (PICKER / "cai2020_crank_rocker_synthesis.toml").read_text()
    path = tmp_path / "tiny.toml"
    path.write_text(text.replace("l7 = { init = 50.0, bounds = [5.0, 200.0] }", "l7 = 5e-324"))
    assert "l7 = 5e-324" in path.read_text()
    with pytest.raises(SpecError, match=r"links.l7: 4.94066e-324 is below the smallest magnitude"):
        load_spec(path)
    spec = load_spec(PICKER / "cai2020_crank_rocker_synthesis.toml").model
    rules, q = evaluate(spec, CrankRocker(5e-324, 120.0, 120.0, 140.0, spec.branch))
    records = {r.name: r.record() for r in rules}
    assert q is None
    for name in ("time_ratio", "rocker_swing", "min_transmission_angle"):
        assert records[name].value is None and not records[name].satisfied
        assert "extreme positions cannot be found" in records[name].note + records[name].where


@pytest.mark.slow
def test_a_start_whose_fixed_frame_moved_is_no_design_and_never_reported_as_one(tmp_path):
    """The lengths' bounds are rows in the Grashof coordinates: a start IPOPT stops infeasible may leave them.  On
    requirements no crank-rocker meets (K = 1, swing 0.01 deg, transmission >= 89.99 deg) every start ended with the
    frame l10, fixed at 140 mm, at 161.37 mm, and the result showed that design's rules as if it were the spec's."""
    from synthesis.core.coordinates import outside_bounds

    text = (LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").read_text()
    for old, new in (("time_ratio = 1.25", "time_ratio = 1.0"), ("rocker_swing = 50.0", "rocker_swing = 0.01"),
                     ("min_transmission_angle = 40.0", "min_transmission_angle = 89.99")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "extreme.toml"
    path.write_text(text)
    result, reports, _ = run_solve(load_spec(path), starts=8, workers=1)
    assert result.status in ("infeasible", "failed") and not any(r.satisfied for r in reports)
    for r in reports:
        moved = abs(r.outcome.design["l10"] - 140.0) > 1e-6 * 140.0
        assert (r.why is not None and r.why.startswith("l10 = ") and "outside its fixed value 140" in r.why) \
            == moved, (r.outcome.design, r.why)
        assert moved or r.why is None
    assert any(abs(r.outcome.design["l10"] - 140.0) > 1.0 for r in reports)      # the case this test is about
    # its solved.toml keeps the spec's l10 = 140: its header no longer promises the solve's rule table
    from synthesis.spec.solved import solved_toml

    header = solved_toml(load_spec(path), result).splitlines()[2]
    assert abs(result.design["l10"] - 140.0) > 1.0              # every start drifted: so did the one reported
    assert "NOTE: the solve's design is no design of this spec (l10 = " in header
    assert "where the spec fixes 140" in header and "evaluates exactly" not in header
    box = np.array([[5.0, 50.0], [5.0, 200.0], [5.0, 200.0], [140.0, 140.0]])
    assert outside_bounds(("l7", "l8", "l9", "l10"), box, {"l7": 5.0 - 1e-7, "l10": 140.0 + 1e-5}) is None
    assert outside_bounds(("l7", "l8", "l9", "l10"), box, {"l7": 4.99}).startswith("l7 = 4.99 lies 0.01 outside its bounds")



@pytest.mark.slow
def test_requirements_no_crank_rocker_meets_are_diagnosed_as_the_transmission_rule_missing_by_the_best_gap(tmp_path):
    """K = 1.4, swing 45 deg, gamma_min >= 45 deg, frame 200 mm (a practitioner's trial): the best any crank-rocker
    reaches at that K and swing is about 35.14 deg.  The elastic re-solve from the given design stopped on an
    invalid number (it shrank the swing to nothing) and the run was called "a solver failure, not an infeasible
    rule set"; re-solved from the starts' designs it converges and names the rule, missing by 45 - gamma*.
    gamma* here is the max_transmission_angle objective's answer on the same K, swing and frame: another NLP."""
    text = (LIBRARY / "picker" / "crank_rocker_max_transmission.toml").read_text()
    for old, new in (("time_ratio = 1.25", "time_ratio = 1.4"), ("rocker_swing = 50.0", "rocker_swing = 45.0"),
                     ("l10 = 140.0", "l10 = 200.0"), ("bounds = [5.0, 200.0]", "bounds = [5.0, 300.0]")):
        assert old in text
        text = text.replace(old, new)
    best = tmp_path / "best.toml"
    best.write_text(text.replace("min_transmission_angle = 40.0", "min_transmission_angle = 20.0"))
    result, _, _ = run_solve(load_spec(best), starts=8, workers=1)
    assert result.status == "optimal"
    gamma_star = next(r["value"] for r in result.rules if r["name"] == "min_transmission_angle")
    assert 34.0 < gamma_star < 36.0
    asked = tmp_path / "asked.toml"
    asked.write_text(text.replace("min_transmission_angle = 40.0", "min_transmission_angle = 45.0")
                     .replace('name = "max_transmission_angle"', 'name = "min_total_length"'))
    loaded = load_spec(asked)
    result, reports, _ = run_solve(loaded, starts=16, workers=1)
    assert result.status == "infeasible"
    assert result.elastic["relaxed"] == ["min_transmission_angle"]
    assert result.elastic["slacks"]["min_transmission_angle"] == pytest.approx(45.0 - gamma_star, abs=0.02)
    error = str(diagnose_infeasible(loaded, result, reports))
    message = " ".join(error.split())
    assert "Rules that conflict" in message and "min_transmission_angle (misses its limit by 9.8" in message
    # the run keeps the message, and its report shows it under the verdict
    assert result.solver["diagnosis"] == error
    from synthesis.report import run_artifacts
    from synthesis.result import write_run

    folder, _ = write_run(tmp_path / "out", result, run_artifacts(result, {}))
    page = (folder / "report.html").read_text()
    assert "<p class='diagnosis'>no start satisfies every rule" in page and "misses its limit by 9.8" in page
    # the answer column is not "solved": it is the least violated start's design (an independent trial)
    assert page.count("<th>least violated (infeasible)</th>") >= 2 and "<th>solved</th>" not in page


def test_a_fixed_length_given_back_through_the_grashof_slacks_is_the_specs_to_the_bit():
    """l10 = 140 mm fixed: the NLP holds it as a row on l7 + (s_frame + s_coupler) / 2, whose rounding gave a start's
    design 139.99999999999997 (its starts row, and solved.toml had that start won).  A value within rounding of the
    fixed one is the fixed one; one IPOPT left further off (1e-9 mm) stays, for the verdict to judge."""
    from synthesis import kinds
    from synthesis.core.kind import Setting
    from synthesis.kinds.crank_rocker.nlp import COORDINATES

    loaded = load_spec(PICKER / "crank_rocker_max_transmission.toml")
    solving = kinds.get("crank_rocker").solving()
    nlp = solving.build(Setting(loaded.model, 0, solving.prepare(loaded.model), solver=False), False)
    assert [tuple(b) for b in nlp.bounds][3] == (140.0, 140.0)
    rng = np.random.default_rng(0)
    off_by_rounding = 0
    for _ in range(200):
        lengths = np.array([rng.uniform(30, 60), rng.uniform(100, 140), rng.uniform(110, 150), 140.0])
        z = np.concatenate([COORDINATES.coordinates(np.concatenate([lengths, [0.0, 1.0]]))])
        raw = float(COORDINATES.design(z)[3])
        off_by_rounding += raw != 140.0
        assert nlp.design(z)["l10"] == 140.0 and abs(raw - 140.0) <= 1e-13 * 140.0
    assert off_by_rounding > 0          # the map does round: the case is exercised
    z = COORDINATES.coordinates(np.array([50.0, 120.0, 130.0, 140.0 + 1e-9, 0.0, 1.0]))
    assert nlp.design(z)["l10"] == pytest.approx(140.0 + 1e-9, abs=1e-12) and nlp.design(z)["l10"] != 140.0


def test_the_solve_s_re_check_reads_a_sampled_peak_on_the_check_s_grid_at_least():
    """The solve passed crank_rocker_torque_limited's answer at 0.29999997 N m (re-checked on 10 x 72 samples) and
    `check` of its solved.toml failed it at 0.30000409 (3,600 samples): the two verdicts on one design differed.  The
    re-check reads at least the check's grid: every rule's value is the check's, to the bit."""
    from types import SimpleNamespace

    from synthesis.core.kind import Setting
    from synthesis.kinds.crank_rocker.solve import recheck

    loaded = load_spec(LIBRARY / "picker" / "crank_rocker_torque_limited.toml")
    design = {"l7": 50.99, "l8": 126.69, "l9": 129.72, "l10": 140.0}
    rules = recheck(Setting(loaded.model), SimpleNamespace(design=design)).rules
    checked = evaluate(loaded.model, mechanism(loaded.model, design))[0]
    assert [(r.name, r.record().value) for r in rules] == [(r.name, r.record().value) for r in checked]
    assert "peak_input_torque" in [r.name for r in rules]


def test_the_peak_back_off_is_capped_and_check_reads_the_solve_s_grid():
    """The (72 / n)^2 share of a peak's limit passed the limit itself at 10 samples (the kind takes 8): the solve was
    refused ("limits closer together than the back-off allows").  crank_rocker caps it at 2 %; above 360 samples per
    turn check reads the re-check's 10 x grid, not 3,600."""
    from types import SimpleNamespace

    from synthesis.dynamics.linkage import DYNAMICS_BACKOFF_AT_72, peak_backoff
    from synthesis.kinds.crank_rocker.check import CHECK_SAMPLES, check_samples

    rule = SimpleNamespace(name="peak_input_torque")
    capped = peak_backoff(10, lambda r, limit: 0.0, most=DYNAMICS_BACKOFF_AT_72)
    assert capped(rule, 0.3) == pytest.approx(0.02 * 0.3) and peak_backoff(10, lambda r, l: 0.0)(rule, 0.3) > 0.3
    assert peak_backoff(144, lambda r, l: 0.0, most=0.02)(rule, 0.3) == pytest.approx(0.005 * 0.3)
    loaded = load_spec(LIBRARY / "picker" / "crank_rocker_torque_limited.toml")
    assert check_samples(loaded.model) == CHECK_SAMPLES
    wide = loaded.model.model_copy(update={"solver": loaded.model.solver.model_copy(update={"samples_per_turn": 400})})
    assert check_samples(wide) == 4000
    run = run_check(loaded)
    assert run.extra["motion"]["min_transmission_angle_deg"] == pytest.approx(
        next(r["value"] for r in run.rules if r["name"] == "min_transmission_angle"), abs=1e-12)
