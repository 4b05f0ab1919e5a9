"""fourbar_path, grashof = "any": linkages whose crank only rocks -- their intervals of
motion, the screen laying open target arcs onto them, and the configuration form of the NLP (natural.py), regular
where the crank is at a dead position.  The figures: problems/fourbar_path/INEXACT.md."""

from __future__ import annotations

import math

import numpy as np
import pytest

from synthesis.core.executor import latin_hypercube_starts
from synthesis.kinds.fourbar_path import screen
from synthesis.kinds.fourbar_path.check import evaluate
from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.kinds.fourbar_path.inexact import BEST_KNOWN, best_known_designs, inexact_spec
from synthesis.kinds.fourbar_path.nlp import PathNLP
from synthesis.kinds.fourbar_path.starts import arc_fractions, shape_of
from synthesis.kinds.fourbar_path.kinematics import BRANCHES, VARIABLES


def _closes(shape: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Whether the loop of a normalised shape closes at each crank angle, by the construction's NaN."""
    d = {"r1": 1.0, "r2": shape[1], "r3": shape[2], "r4": shape[3], "rcx": shape[4], "rcy": shape[5],
         "x0": 0.0, "y0": 0.0, "theta0": 0.0}
    return np.isfinite(joint_positions(d, theta, 1)["P"])


def test_the_rocking_intervals_are_where_the_loop_closes():
    """For 300 random shapes of any class, the intervals of screen.rocking_runs are exactly the crank angles where
    the construction closes the loop (on a 20,000-point turn, away from each interval's ends by the grid's step);
    a shape whose crank turns fully has none."""
    rng = np.random.default_rng(5)
    shapes = screen.sample_rocking_shapes(rng, 300)
    which, first, last = screen.rocking_runs(shapes)
    theta = np.linspace(0.0, 2.0 * math.pi, 20000, endpoint=False)
    step = theta[1]
    rocking = 0
    for k, shape in enumerate(shapes):
        closes = _closes(shape, theta)
        mine = which == k
        inside = np.zeros_like(closes)
        near_end = np.zeros_like(closes)
        for a, b in zip(first[mine], last[mine]):
            rel = (theta - a) % (2.0 * math.pi)
            inside |= rel <= (b - a)
            gap = np.minimum(np.abs((theta - a + math.pi) % (2 * math.pi) - math.pi),
                             np.abs((theta - b + math.pi) % (2 * math.pi) - math.pi))
            near_end |= gap < 2 * step
        if not mine.any():
            assert closes.all() or not closes.any()      # a full turn, or no assembly at all
            continue
        rocking += 1
        assert np.array_equal(closes[~near_end], inside[~near_end]), k
    assert rocking > 50


def test_the_screen_lays_an_open_arc_onto_a_rocking_linkages_range_of_motion(monkeypatch):
    """Targets on a non-Grashof linkage's coupler curve (12 points of its range of motion, ends included, turned by
    -25 deg, scaled by 30 and shifted): with that shape among the rocking candidates the screen's best design is it,
    residual ~0, with the scale and turn recovered -- the open-curve correspondences and nearest-point rounds."""
    true = np.array([1.0, 0.9, 1.3, 1.8, 1.5, 0.2])       # s + l > p + q: the crank rocks
    which, first, last = screen.rocking_runs(true[None, :])
    assert len(which) == 1
    theta = screen.run_angles(first, last, screen.GRID)[0]
    d = {"r1": 1.0, "r2": true[1], "r3": true[2], "r4": true[3], "rcx": true[4], "rcy": true[5], "x0": 0.0,
         "y0": 0.0, "theta0": 0.0}
    curve = joint_positions(d, theta, BRANCHES["open"])["P"]
    k = np.linspace(0, screen.GRID - 1, 12).round().astype(int)
    a_true = 30.0 * np.exp(1j * math.radians(-25.0))
    z = a_true * curve[k] + (100.0 + 50.0j)
    targets = np.column_stack([z.real, z.imag])
    bounds = np.array([[1.5, 300.0]] * 4 + [[-300.0, 300.0]] * 2 + [[-500.0, 700.0]] * 2 + [[0.0, 360.0]])
    others = screen.sample_rocking_shapes
    monkeypatch.setattr(screen, "ROCKING", 50)
    monkeypatch.setattr(screen, "sample_rocking_shapes",
                        lambda rng, n: np.vstack([true[None, :], others(rng, n - 1)]))
    designs, residuals = screen.screen(targets, bounds, BRANCHES["open"], "any", (1.0, -1.0), False,
                                       arc_fractions(targets, False), seed=0, shapes=200)
    assert residuals[0] == pytest.approx(0.0, abs=1e-6)
    assert designs[0][:6] == pytest.approx(30.0 * true, rel=1e-6)
    assert designs[0][8] == pytest.approx(360.0 - 25.0, abs=1e-5)


@pytest.mark.slow
def test_the_configuration_form_is_the_closed_form_where_its_rows_hold():
    """At a crank-rocker's crank angles with the coupler angles of the closed form (the spec's assembly), the
    configuration form's closure rows are zero, its assembly rows <= 0, and its path error is the crank-angle
    form's: the two forms are one problem wherever the closure and sign rows hold."""
    spec = inexact_spec("stroke_lift14").model
    nlp = PathNLP(spec, seed=0)
    form = nlp.configuration
    assert form is not None
    rng = np.random.default_rng(2)
    design = np.array([40.0, 12.0, 38.0, 30.0, 25.0, 18.0, 80.0, 40.0, 10.0])
    theta = np.sort(rng.uniform(0.0, 2.0 * math.pi, len(spec.targets.points)))
    psi = np.unwrap(form.psi_of(design, theta))
    w = np.concatenate([nlp.nominal(design), theta])
    closure, side = (np.asarray(v).ravel() for v in form.rows(np.concatenate([w, psi])))
    assert np.abs(closure).max() < 1e-12 and side.max() < 0.0
    assert float(form.fit(np.concatenate([w, psi]))) == pytest.approx(float(nlp.fit(w, 1.0)), rel=1e-12)
    # the other assembly: the same crank angles, the closed form's crossed coupler angles break the sign rows
    local = dict(zip(VARIABLES, design), x0=0.0, y0=0.0, theta0=0.0)
    crossed = joint_positions(local, theta, -form.branch)
    closure, side = (np.asarray(v).ravel() for v in
                     form.rows(np.concatenate([w, np.angle(crossed["B"] - crossed["A"])])))
    assert np.abs(closure).max() < 1e-12 and side.min() > 0.0


@pytest.mark.slow
def test_the_configuration_form_converges_where_the_crank_reaches_its_dead_positions():
    """dwell_arc15's best known design has its first and last targets at the crank's dead positions (the ends of its
    one interval of motion).  From that design with its links 1 % off (seeded) and placed as a screened start is
    (StartMaker.finish), the configuration form converges -- Solve_Succeeded in under 100 iterations -- to the best known
    objective, every rule holding on the kind's fine-grid check; the crank-angle form, whose coupler point has a
    square-root singularity there, does not converge from the same start (a failed step; max_iter from all 12 starts
    of 0.5-2 % measured with IPOPT's default scaling: INEXACT.md)."""
    spec = inexact_spec("dwell_arc15").model
    nlp = PathNLP(spec, seed=0)
    rec = best_known_designs()["dwell_arc15"]
    best = np.array([rec["design"][n] for n in VARIABLES])
    _, first, last = screen.rocking_runs(shape_of(best))
    inset = 1e-6                                  # rocking_runs' ends lie this far inside the dead positions
    assert math.radians(rec["crank_deg"][0]) == pytest.approx(first[0] - inset, abs=1e-9)
    assert math.radians(rec["crank_deg"][-1]) == pytest.approx(last[0] + inset, abs=1e-9)
    moved = best.copy()
    moved[:6] *= np.exp(0.01 * np.random.default_rng(0).standard_normal(6))
    _, start = nlp.starts.finish(moved, 3)
    w0 = np.concatenate([nlp.nominal(start.design), start.theta])
    out = nlp.configuration.solve(0, w0, start.design, start.sign)
    assert out.return_status == "Solve_Succeeded" and out.iterations < 100
    design = dict(zip(VARIABLES, nlp.design_of(out.x[:9])))
    crank = list(np.degrees(out.x[9:]))
    ev = evaluate(spec, design, crank, timing="solved", direction="ccw" if start.sign > 0 else "cw")
    assert ev.sum_sq == pytest.approx(BEST_KNOWN["dwell_arc15"], rel=1e-7)
    assert all(r.record().satisfied for r in ev.rules)
    angle = nlp.compiled.solve(0, w0, p=start.sign)
    assert angle.return_status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def _solved_start(spec, seed: int, index: int):
    """Start ``index`` of a 64-start run of ``spec`` with ``seed`` (its Latin-hypercube row), solved by PathNLP."""
    nlp = PathNLP(spec, seed=seed)
    rows = latin_hypercube_starts(nlp.bounds, nlp.init, 64, seed)
    return nlp.solve(index, rows[index])


def _kept_from_the_configuration_form(spec, out):
    """Assert that ``out`` kept the configuration form's resume or polish and ends Solve_Succeeded with every rule
    holding on the fine grid; return the check's evaluation."""
    assert out.details["resumed"]["form"] == "configuration" and out.details["resumed"]["kept"] is True
    assert out.return_status == "Solve_Succeeded"
    ev = evaluate(spec, out.design, out.details["crank_deg"], timing="solved", direction=out.details["direction"])
    assert all(r.record().satisfied for r in ev.rules)
    return ev


@pytest.mark.slow
def test_a_closed_loop_start_the_crank_angle_form_does_not_finish_is_polished_in_the_configuration_form():
    """kidney25 (closed loop, grashof "any", seed 0): start 45 ends without converging in the crank-angle form; the
    configuration form takes it on from there and converges (Solve_Succeeded) at the best known objective, its
    details saying so; the design holds every rule on the fine grid."""
    spec = inexact_spec("kidney25").model
    out = _solved_start(spec, 0, 45)
    _kept_from_the_configuration_form(spec, out)
    assert out.objective == pytest.approx(BEST_KNOWN["kidney25"], rel=1e-8)


def test_the_recheck_reads_a_crank_direction_the_spec_fixes():
    """A start's details carry the direction it was solved in; where the spec fixes one, the re-check holds the
    spec's.  dwell_arc15's best known design meets its ordered targets counter-clockwise: re-checked for a spec
    that says clockwise, its sequence rule fails, whatever direction the start's details claim."""
    from types import SimpleNamespace

    from synthesis.core.kind import Setting
    from synthesis.kinds.fourbar_path.solve import recheck
    from synthesis.kinds.fourbar_path.inexact import inexact_data
    from synthesis.spec.common import validate
    from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

    rec = best_known_designs()["dwell_arc15"]
    for direction, holds in (("counter_clockwise", True), ("clockwise", False)):
        data = inexact_data("dwell_arc15")
        data["rules"]["direction"] = direction
        spec = validate(FourbarPathSpec, data, prefix="fourbar_path")
        outcome = SimpleNamespace(design=rec["design"], details={"crank_deg": rec["crank_deg"], "direction": "ccw"})
        checked = recheck(Setting(spec), outcome)
        sequence = [r.record() for r in checked.rules if r.record().name == "sequence"]
        assert len(sequence) == 1 and sequence[0].satisfied is holds


@pytest.mark.slow
def test_a_closed_loops_max_iter_start_is_resumed_in_the_crank_angle_form(monkeypatch):
    """kidney25 with max_iter 60 (seed 0): start 3 reaches max_iter near the reference and is resumed once in the
    crank-angle form (its details name no form), within RESUME_ITERATIONS; kept only if it converged no higher."""
    from synthesis.kinds.fourbar_path import nlp as path_nlp

    spec = inexact_spec("kidney25", {"max_iter": 60}).model
    nlp = PathNLP(spec, seed=0)
    rows = latin_hypercube_starts(nlp.bounds, nlp.init, 64, 0)
    resumed = nlp.solve(3, rows[3])
    assert "form" not in resumed.details["resumed"]
    assert "resumed from where it reached max_iter" in resumed.raw.log
    assert resumed.details["resumed"]["iterations"] <= path_nlp.RESUME_ITERATIONS
    if resumed.details["resumed"]["kept"]:
        assert resumed.return_status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
        assert resumed.objective == pytest.approx(resumed.details["resumed"]["path_error_mm2"], rel=1e-12)
    else:
        assert resumed.return_status == "Maximum_Iterations_Exceeded"


@pytest.mark.slow
def test_a_polish_stopped_by_its_iteration_cap_keeps_the_starts_own_answer(monkeypatch):
    """kidney25 (seed 0): start 45 ends unconverged in the crank-angle form and its configuration-form polish
    converges at the best known (test above).  Stopped after POLISH_ITERATIONS = 5 without converging, the polish is
    not kept: the start's answer, status and objective are those of the crank-angle form alone (the same as with a
    polish of 0 iterations), far above the best known; the iterations count both runs.  (Written on these invariants,
    not on one IPOPT trajectory: the crank-angle form's last status differs between machines.)"""
    from synthesis.kinds.fourbar_path import nlp as path_nlp

    spec = inexact_spec("kidney25").model
    nlp = PathNLP(spec, seed=0)
    rows = latin_hypercube_starts(nlp.bounds, nlp.init, 64, 0)
    monkeypatch.setattr(path_nlp, "POLISH_ITERATIONS", 0)
    alone = nlp.solve(45, rows[45])
    assert alone.details["resumed"] == {"return_status": "User_Requested_Stop", "iterations": 0, "kept": False,
                                        "path_error_mm2": alone.details["resumed"]["path_error_mm2"],
                                        "form": "configuration"}
    assert alone.return_status not in ("Solve_Succeeded", "User_Requested_Stop", "Maximum_Iterations_Exceeded")
    monkeypatch.setattr(path_nlp, "POLISH_ITERATIONS", 5)
    capped = nlp.solve(45, rows[45])
    assert capped.details["resumed"]["iterations"] == 5
    assert capped.details["resumed"]["return_status"] == "User_Requested_Stop"
    assert capped.details["resumed"]["kept"] is False
    assert capped.return_status == alone.return_status
    assert capped.objective == alone.objective > 1.05 * BEST_KNOWN["kidney25"]
    assert capped.iterations == alone.iterations + 5
    assert "polished in the configuration form: User_Requested_Stop, not kept (did not converge)" in capped.raw.log


@pytest.mark.slow
def test_the_polish_at_a_change_point_starts_with_a_larger_barrier_parameter(monkeypatch):
    """kidney25, seed 2, start 35: the crank-angle form ends with a failed step on the change point (target 0 at crank
    180 deg, r1 + r2 = r3 + r4: the links in line).  The polish (POLISH_MU_INIT 1e-2) converges there, Solve_Succeeded
    at the best known; started with the starts' barrier parameter (1e-6) it leaves the point and is not kept."""
    from synthesis.kinds.fourbar_path import nlp as path_nlp

    spec = inexact_spec("kidney25").model
    out = _solved_start(spec, 2, 35)
    _kept_from_the_configuration_form(spec, out)
    assert out.objective == pytest.approx(BEST_KNOWN["kidney25"], rel=1e-8)
    d = out.design
    assert d["r1"] + d["r2"] == pytest.approx(d["r3"] + d["r4"], rel=1e-7)
    assert out.details["crank_deg"][0] == pytest.approx(180.0, abs=0.01)
    monkeypatch.setattr(path_nlp, "POLISH_MU_INIT", None)
    before = _solved_start(spec, 2, 35)
    assert before.details["resumed"]["kept"] is False and before.return_status == "Error_In_Step_Computation"
    assert before.details["resumed"]["path_error_mm2"] > 100 * BEST_KNOWN["kidney25"]


@pytest.mark.slow
def test_an_open_arcs_max_iter_start_resumes_in_the_configuration_form_for_its_own_iteration_budget():
    """stroke_lift14 (open arc, grashof "any", seed 1): start 43 reaches max_iter in the configuration form and its
    resume converges after more than RESUME_ITERATIONS (150, the crank-angle form's budget, which would have stopped
    it: the run is the same up to there) and within CONFIGURATION_RESUME_ITERATIONS, below the max_iter answer
    (0.259043 mm^2), Solve_Succeeded, every rule holding."""
    from synthesis.kinds.fourbar_path import nlp as path_nlp

    spec = inexact_spec("stroke_lift14").model
    out = _solved_start(spec, 1, 43)
    ev = _kept_from_the_configuration_form(spec, out)
    resumed = out.details["resumed"]
    assert path_nlp.RESUME_ITERATIONS < resumed["iterations"] <= path_nlp.CONFIGURATION_RESUME_ITERATIONS
    assert out.iterations == spec.solver.max_iter + resumed["iterations"]
    assert out.objective == pytest.approx(0.258968442580562, rel=1e-7)
    assert ev.sum_sq == pytest.approx(out.objective, rel=1e-9)


@pytest.mark.slow
def test_a_rocking_screened_start_follows_its_own_order_or_the_direction_the_spec_fixes():
    """dwell_arc15's screened starts whose crank only rocks: with direction "either" each start's direction is the
    order of its crank angles within its interval of motion (not the cw / ccw alternation of the unscreened starts);
    with "clockwise" every one is clockwise."""
    from synthesis.kinds.fourbar_path.inexact import inexact_data
    from synthesis.kinds.fourbar_path.starts import StartMaker
    from synthesis.spec.common import validate
    from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

    for direction in ("either", "clockwise"):
        data = inexact_data("dwell_arc15")
        data["rules"]["direction"] = direction
        maker = StartMaker(validate(FourbarPathSpec, data, prefix="fourbar_path"), 0)
        designs, _ = maker.screened
        rocking = 0
        for rank in range(1, 41):
            design = designs[rank - 1]
            if not len(screen.rocking_runs(shape_of(design))[0]):
                continue
            rocking += 1
            _, start = maker.finish(design, rank)
            order = 1.0 if start.theta[-1] >= start.theta[0] else -1.0
            assert start.sign == (order if direction == "either" else -1.0), rank
        assert rocking >= 10
