"""One verdict for every kind that solves: the same status semantics and exit-3 messages.

For each solving kind: a feasible rule set capped at one IPOPT iteration (no start converges, no
returned design meets the rules) is ``failed``, never ``infeasible``; an unreachable rule set is
``infeasible`` and the elastic re-solve names the rule that was made unreachable; a spec with nothing
free is bad input (exit 2).  result.json carries the elastic diagnosis the message is made from.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from types import SimpleNamespace

import pytest

from conftest import LIBRARY, PLANTING
from solving import agrisynth, diagnose_infeasible, run_solve
from synthesis import kinds
from synthesis.core.verdict import ElasticDiagnosis, StartReport, status_of, unsatisfied_error
from synthesis.errors import SpecError
from synthesis.spec import load_spec

#: spec, text replacements, starts: feasible rule sets whose given design misses a rule, capped at one
#: IPOPT iteration, so that no start converges and no returned design meets the rules
CAPPED = {
    "crank_rocker": ("picker/cai2020_crank_rocker_synthesis.toml",
                     [("l7 = { init = 50.0", "l7 = { init = 150.0"), ("l9 = { init = 120.0", "l9 = { init = 30.0"),
                      ("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "picker_double_crank": ("picker/picker_double_crank_redesign.toml",
                            [("min_transmission_angle = 40.0", "min_transmission_angle = 80.0"),
                             ("max_iter = 1500", "max_iter = 1")], 2),
    "clamp_cam": ("clamp_cam/opening_cam_redesign.toml", [("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "guide_tube": ("guide_tube/cai2020_delta2.toml",
                   [("angle = { init = 41,", "angle = { init = 65,"), ("[solver]\n", "[solver]\nmax_iter = 1\n")], 3),
    "steering_linkage": ("steering/steering_redesign_40.toml",
                         [("min_transmission_angle = 25.0", "min_transmission_angle = 30.0"),
                          ("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "tillage_linkage": ("tillage/tillage_redesign.toml",
                        [("c = { init = 500.0", "c = { init = 300.0"), ("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "planting_fourbar": ("planting_arm/redesign_from_example1.toml", [("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    # this run used to end "infeasible", all five rules named on an unconverged elastic re-solve
    "fourbar_path": ("fourbar_path/picking_arc.toml", [("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "guide_way": ("guide_way/smooth_redesign.toml", [("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "combing_chain": ("combing_chain/redesign_window_80_100.toml", [("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "comb_finger": ("comb_finger/redesign_max_combing.toml",
                    [("root_clearance = 30.0", "root_clearance = 45.0"), ("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
}

#: spec, replacements making one rule unreachable, the rule the diagnosis must name, starts
UNREACHABLE = {
    "crank_rocker": ("picker/cai2020_crank_rocker_synthesis.toml",
                     [("min_transmission_angle = 40.0", "min_transmission_angle = 89.0")],
                     "min_transmission_angle", 2),
    # the redesign frees x_a within [0, 150] mm (the retrofit keeps it at 25 mm: refused before any start, as a rule
    # no design variable moves: tests/test_pinned.py)
    "picker_double_crank": ("picker/picker_double_crank_redesign.toml", [("x_a_min = 0.0", "x_a_min = 400.0")],
                            "frame_point_x_a", 2),
    "clamp_cam": ("clamp_cam/opening_cam_redesign.toml",
                  [("base_radius = { init = 50.0, bounds = [20.0, 150.0] }",
                    "base_radius = { init = 25.0, bounds = [20.0, 30.0] }")], "pressure_angle", 2),
    # both tubes free (cai2020_delta2 gives tube I as numbers: its free fall is refused before any start)
    "guide_tube": ("guide_tube/uniform_spacing.toml", [("min_free_fall = 0 ", "min_free_fall = 900 ")],
                   "free_fall_height", 2),
    "steering_linkage": ("steering/steering_redesign_40.toml",
                         [("min_transmission_angle = 25.0", "min_transmission_angle = 80.0")],
                         "tie_rod_transmission_angle", 2),
    "tillage_linkage": ("tillage/tillage_redesign.toml", [("min_rearward_speed = 0.05", "min_rearward_speed = 3.0")],
                        "rearward_in_soil", 2),
    # an unreachable P1-P3 distance must be named among the conflicting rules
    "planting_fourbar": ("planting_arm/redesign_from_example1.toml",
                         [("[solver]\n", "[rules]\np1p3 = [200, 210]\n\n[solver]\n")], "p1p3_distance", 2),
    "fourbar_path": ("fourbar_path/picking_arc.toml",
                     [("transmission_angle = [40, 140]", "transmission_angle = [89.9, 90.1]")], "transmission_angle_min", 2),
    # a pressure angle of at most 30 deg outside the fold window no smooth path here keeps (60 deg is met: the NLP
    # holds the rule at the window's edges).  The cap is raised: the elastic re-solve's iterations differ between
    # machines (the same build of IPOPT, other floating-point paths), and the case tests the diagnosis, not the
    # machine.  (Here: 43 s; 40 deg 70 s, 50 deg 92 s; a 50 or 300 mm roller margin 170-185 s.)  One start: since
    # a start the arm cannot drive is moved onto the key points (GuideNLP.drivable_start), start 1 runs its 2000
    # iterations instead of stopping at its first evaluation (the case took 114 s), and the diagnosis is start 0's.
    "guide_way": ("guide_way/smooth_redesign.toml", [("max_pressure_angle = 85.0", "max_pressure_angle = 30.0"),
                                                    ("[solver]\n", "[solver]\nmax_iter = 2000\n")],
                  "pressure_angle", 1),
    # one chain speed cannot serve 0.4-0.62 m/s: the corner (beta 110, V_s 0.62) conflicts with (beta 70, V_s 0.4)
    "combing_chain": ("combing_chain/redesign_window_80_100.toml",
                      [("machine_speed = [0.4, 0.55]", "machine_speed = [0.4, 0.62]")], "window_top", 2),
    "comb_finger": ("comb_finger/redesign_max_combing.toml", [("root_clearance = 30.0", "root_clearance = 300.0")],
                    "root_clearance", 2),
}

#: spec whose every design variable is fixed (a published design), per solving kind
NOTHING_FREE = {
    "crank_rocker": "picker/cai2020_crank_rocker.toml",
    "picker_double_crank": "picker/cai2020_double_crank.toml",
    "clamp_cam": "clamp_cam/opening_cam.toml",
    "guide_tube": "guide_tube/cai2020_tubes.toml",
    "steering_linkage": "steering/hwang_model3_steering.toml",
    "tillage_linkage": "tillage/hwang_tillage_baseline.toml",
    "planting_fourbar": "planting_arm/taiwan_example1.toml",
    "guide_way": "guide_way/liang_2z.toml",
    "combing_chain": "combing_chain/kubota_hc500.toml",
    "comb_finger": "comb_finger/peanut_baseline.toml",
}


def edited_spec(tmp_path: Path, source: str, replacements: list[tuple[str, str]]) -> Path:
    text = (LIBRARY / source).read_text()
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    if any("max_iter = 1\n" in new for _, new in replacements) and "max_iter = 1\n" not in text:
        text = re.sub(r"max_iter = \d+\n", "max_iter = 1\n", text)
    path = tmp_path / Path(source).name
    path.write_text(text)
    return path


#: solving kinds with no published design in the library yet (nothing to refuse as "nothing free"): the rotary
#: planetary train (problems/rotary_planetary/NOTES.md says why none is reproduced)
NO_PUBLISHED_DESIGN = {"rotary_planetary"}


def test_every_solving_kind_is_covered():
    solving = {k.name for k in kinds.all_kinds() if k.solves}
    assert set(NOTHING_FREE) | {"planting_fourbar", "fourbar_path"} | NO_PUBLISHED_DESIGN == solving


@pytest.mark.parametrize("kind", [pytest.param(k, marks=pytest.mark.slow) if k == "guide_way" else k
                                  for k in sorted(CAPPED)])
def test_no_start_converged_is_failed_not_infeasible(tmp_path, kind):
    source, replacements, starts = CAPPED[kind]
    loaded = load_spec(edited_spec(tmp_path, source, replacements))
    assert loaded.kind == kind
    result, reports, _ = run_solve(loaded, starts=starts, workers=1)
    assert not any(r.outcome.success for r in reports)
    assert not any(r.satisfied for r in reports)
    assert result.status == "failed"
    assert result.elastic is not None and result.elastic["relaxed"] == []
    message = str(diagnose_infeasible(loaded, result, reports))
    assert message.startswith(f"IPOPT found no design that satisfies every rule: 0 of the {starts} starts converged")
    assert re.search(r"IPOPT said: (Maximum_Iterations_Exceeded|Invalid_Number_Detected)", message)
    # no elastic re-solve converged (nor did any start): nothing says the rules can be met together
    assert "Whether the rules can be met together is not known" in message and "[solver] max_iter" in message
    assert "Rules that conflict" not in message and "not an infeasible rule set" not in message


#: the kinds whose UNREACHABLE rule is still missed re-solved alone from the elastic design, every other rule relaxed;
#: in the others it is met alone and another rule is what it conflicts with (fourbar_path: a transmission window
#: [89.9, 90.1] deg, the minimum alone can be met; tillage: its bar-slot angle gives way for the rearward speed;
#: combing_chain: one speed cannot serve both corners of the window)
OUT_OF_REACH = {"clamp_cam", "comb_finger", "crank_rocker", "guide_tube", "picker_double_crank", "planting_fourbar",
                "steering_linkage"}
UNKNOWN_ALONE: set[str] = set()
#: guide_way's re-solve alone has been machine-dependent: on one machine a 300 mm roller margin's wandered off to a
#: worse local minimum and proved nothing (None), on another it stayed out of reach.  Any is a true statement of its
#: run; the test holds whichever it is to its meaning (still missed alone: named out of reach; met alone: not)
EITHER_ALONE = {"guide_way"}


#: the solves of seconds (guide_way's a minute, started first)
UNREACHABLE_MARKS = {"guide_way": [pytest.mark.slow, pytest.mark.long], "planting_fourbar": [pytest.mark.slow]}


@pytest.mark.parametrize("kind", [pytest.param(k, marks=UNREACHABLE_MARKS.get(k, [])) for k in sorted(UNREACHABLE)])
def test_unreachable_rule_is_infeasible_and_named(tmp_path, kind):
    source, replacements, rule, starts = UNREACHABLE[kind]
    loaded = load_spec(edited_spec(tmp_path, source, replacements))
    result, reports, _ = run_solve(loaded, starts=starts, workers=1)
    assert result.status == "infeasible"
    elastic = result.elastic
    assert elastic["converged"] and elastic["relaxed"]
    assert any(name.startswith(rule) for name in elastic["conflicting"]), elastic
    # every rule given up on is re-solved alone: known, or None where that re-solve proves nothing
    assert set(elastic["alone"]) == set(elastic["relaxed"])
    if kind in EITHER_ALONE:
        alone = elastic["alone"][rule]
        assert alone is None or (alone > 0) == (rule in elastic["out_of_reach"]), elastic
    else:
        assert (kind in UNKNOWN_ALONE) == any(alone is None for alone in elastic["alone"].values()), elastic
        assert (kind in OUT_OF_REACH) == any(name.startswith(rule) for name in elastic["out_of_reach"]), elastic
    message = str(diagnose_infeasible(loaded, result, reports))
    lead = "Rules out of reach" if elastic["out_of_reach"] == elastic["relaxed"] else "Rules that conflict"
    assert lead in message and rule in message
    for name in elastic["out_of_reach"]:
        assert f"still by {elastic['alone'][name]:.3g}" in message and "re-solved alone from there" in message


@pytest.mark.parametrize("kind", sorted(NOTHING_FREE))
def test_nothing_free_is_bad_input(kind):
    loaded = load_spec(LIBRARY / NOTHING_FREE[kind])
    with pytest.raises(SpecError, match="solve needs at least one free"):
        run_solve(loaded, starts=1, workers=1)


def test_failed_run_exits_3_with_result_and_message(tmp_path):
    source, replacements, starts = CAPPED["guide_tube"]
    path = edited_spec(tmp_path, source, replacements)
    proc = agrisynth("solve", str(path), "--out", str(tmp_path / "out"), "--starts", str(starts), "--workers", "1",
                     cwd=tmp_path, timeout=300)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    err = " ".join(proc.stderr.split())
    assert "IPOPT found no design" in err and "Maximum_Iterations_Exceeded" in err
    data = json.loads((tmp_path / "out" / "cai2020_delta2" / "result.json").read_text())
    assert data["schema_version"] == 5
    assert data["status"] == "failed" and data["elastic"]["relaxed"] == []


def _report(start: int, status: str, success: bool) -> StartReport:
    return StartReport(SimpleNamespace(start=start, return_status=status, success=success), False, 0.3)


def test_status_and_message_follow_the_elastic_verdict():
    """The verdicts on one set of unsatisfied starts: the elastic re-solve relaxes a rule (infeasible),
    converges without slack (failed: the rules are compatible), or does not converge (failed, even if it
    left slacks: an unconverged relaxation proves nothing)."""
    reports = [_report(0, "Maximum_Iterations_Exceeded", False), _report(1, "Invalid_Number_Detected", False),
               _report(2, "Maximum_Iterations_Exceeded", False)]
    units, scales = {"gap": "mm", "angle": "deg"}, {"gap": 1.0, "angle": 10.0}
    conflict = ElasticDiagnosis("Solve_Succeeded", True, {"gap": 2.5, "angle": 1e-9}, units, scales, ["angle"])
    compatible = ElasticDiagnosis("Solve_Succeeded", True, {"gap": 1e-9, "angle": 1e-8}, units, scales)
    stuck = ElasticDiagnosis("Maximum_Iterations_Exceeded", False, {"gap": 7.0, "angle": 3.0}, units, scales)
    assert status_of(reports[0], conflict) == "infeasible"
    assert conflict.conflicting == ["gap", "angle"]
    assert status_of(reports[0], compatible) == "failed"
    assert status_of(reports[0], stuck) == "failed" and stuck.relaxed == [] and stuck.conflicting == []
    assert status_of(reports[0], None) == "failed"
    converged_once = reports[:2] + [_report(2, "Solve_Succeeded", True)]     # a converged design between samples

    def message(elastic, status, reps=reports):
        return str(unsatisfied_error(status, ["gap"], reps, elastic, samples_hint="[solver] samples"))

    m = message(conflict, "infeasible")
    assert "Rules that conflict" in m and "gap (misses its limit by 2.5 mm)" in m
    assert "they conflict with angle (binding there)" in m
    assert "IPOPT said: Maximum_Iterations_Exceeded x2, Invalid_Number_Detected" in m
    m = message(compatible, "failed")
    assert m.startswith("IPOPT found no design") and "an elastic re-solve needs no slack" in m
    assert "not an infeasible rule set" in m and "Violated at the best start: gap" in m
    m = message(stuck, "failed")
    assert "did not converge either (Maximum_Iterations_Exceeded)" in m and "Rules that conflict" not in m
    m = message(compatible, "failed", converged_once)
    assert "Violated between samples: gap" in m and "Raise [solver] samples" in m
    # the violations named are the best start's: "between samples" only when that start converged
    m = str(unsatisfied_error("failed", ["gap"], converged_once, compatible, samples_hint="[solver] samples",
                              best=converged_once[0]))
    assert m.startswith("IPOPT found no design") and "between samples" not in m
    m = str(unsatisfied_error("failed", ["gap"], converged_once, compatible, samples_hint="[solver] samples",
                              best=converged_once[2]))
    assert "Violated between samples: gap" in m


def test_a_satisfied_best_start_is_optimal_only_at_solve_succeeded():
    for status, expected in (("Solve_Succeeded", "optimal"), ("Solved_To_Acceptable_Level", "feasible"),
                             ("Infeasible_Problem_Detected", "feasible"), ("Maximum_Iterations_Exceeded", "feasible")):
        converged = status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")      # CasADi's success
        best = StartReport(SimpleNamespace(start=0, return_status=status, success=converged), True, 0.0)
        assert status_of(best, None) == expected


def test_optimal_needs_the_kept_stage_to_have_converged():
    """A multi-stage kind may keep an earlier stage's design (success False) while the last stage's IPOPT
    said Solve_Succeeded: that design was not converged to, so the run is feasible, not optimal."""
    best = StartReport(SimpleNamespace(start=0, return_status="Solve_Succeeded", success=False), True, 0.0)
    assert status_of(best, None) == "feasible"


def test_a_rule_value_that_is_not_a_number_is_an_infinite_violation():
    import math

    import numpy as np

    from synthesis.constraints.base import Rule
    from synthesis.core.verdict import Recheck, report_of

    def recheck(outcome):
        return Recheck([Rule("gap", np.array([1.0, float("nan")]), 0.0, None, "mm", 1.0)])

    rep = report_of(SimpleNamespace(start=0, objective=1.0, details={}), recheck)
    assert not rep.satisfied and rep.worst_violation == math.inf
    assert rep.records[0].value is None and "not a number" in rep.records[0].note


@pytest.mark.slow
def test_a_tolerance_box_no_design_can_hold_fails_instead_of_passing(tmp_path):
    """steering_redesign_40 with a +-60 mm / +-15 deg box (wider than half the arm's range): the nominal
    rules hold at the best start, the linearised worst cases do not -> failed, exit 3, named."""
    text = (LIBRARY / "steering" / "steering_redesign_40.toml").read_text()
    path = tmp_path / "robust.toml"
    path.write_text(text + "\n[tolerance]\nlength = 60.0\nangle = 15.0\nsamples = 50\nseed = 0\n")
    proc = agrisynth("solve", str(path), "--out", str(tmp_path / "out"), "--starts", "2", "--workers", "1",
                     cwd=tmp_path, timeout=300)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    err = " ".join(proc.stderr.split())
    assert "@tolerance" in err and "does not keep its promise" in err and "Traceback" not in proc.stderr
    data = json.loads((tmp_path / "out" / "steering_redesign_40" / "result.json").read_text())
    assert data["status"] == "failed"
    assert any(r["name"].endswith("@tolerance") and not r["satisfied"] for r in data["rules"])


@pytest.mark.parametrize("relative, box", [("guide_tube/uniform_spacing.toml", "angle = 0.3"),
                                          ("fourbar_path/picking_arc.toml", "length = 0.05\nangle = 0.05"),
                                          # its design variables enter only an epigraph's rows and Grashof coordinates
                                          ("picker/picker_double_crank_redesign.toml", "length = 0.1\nangle = 0.1")])
@pytest.mark.slow
def test_guide_tube_and_fourbar_path_hold_their_rules_in_a_tolerance_box(tmp_path, relative, box):
    """Kinds whose NLP is not in the spec's own variables take a tolerance box too: guide_tube (its NLP names the
    angles I, II; the spec delta_I, delta_II) and fourbar_path (its NLP in units of the targets' size: the box is
    mapped by d = offset + scale z).  The answer holds every rule at its linearised worst case in the box, and its
    seeded Monte-Carlo over the box (the kind's nonlinear re-check) passes every sample."""
    path = tmp_path / "robust.toml"
    path.write_text((LIBRARY / relative).read_text() + f"\n[tolerance]\n{box}\nsamples = 20\nseed = 0\n")
    result, _, _ = run_solve(load_spec(path), starts=1, workers=1)
    held = [r for r in result.rules if r["name"].endswith("@tolerance")]
    assert held and all(r["satisfied"] and r["margin"] >= 0 for r in held), held
    # each worst case is read at the answer (fourbar_path: at its crank angles, not a start's guesses), so it is never
    # better than the rule's own margin there, and equal where the box cannot move it (the targets' order)
    nominal = {r["name"]: r["margin"] for r in result.rules if not r["name"].endswith("@tolerance")}
    for r in held:
        assert r["margin"] <= nominal[r["name"].removesuffix("@tolerance")] + 1e-9, r
    assert {r["name"].removesuffix("@tolerance") for r in held} == {r["name"] for r in result.rules
                                                                  if not r["name"].endswith("@tolerance")}
    mc = result.to_json()["facts"]["tolerance"]["monte_carlo"]
    assert mc["samples"] == 20 and mc["pass_rate"] == 1.0
    assert result.status in ("optimal", "feasible")


def test_a_tolerance_box_on_a_fixed_variable_the_nlp_takes_as_a_number_is_bad_input(tmp_path):
    """guide_tube's cai2020_delta2 fixes tube I at 45 deg (its calibration angle), which its NLP takes as a
    number: a [tolerance] box (on both angles) cannot be held there -- exit 2 saying so, not a wrong solve."""
    path = tmp_path / "robust.toml"
    path.write_text((LIBRARY / "guide_tube" / "cai2020_delta2.toml").read_text() + "\n[tolerance]\nangle = 0.3\n")
    with pytest.raises(SpecError, match="takes a fixed one as a number"):
        run_solve(load_spec(path), starts=1, workers=1)


@pytest.mark.slow
def test_a_tolerance_on_a_fixed_fourbar_path_variable_is_refused_not_dropped(tmp_path):
    """fourbar_path computes with a fixed variable's number: its tolerance would be held nowhere.  Refused, naming it
    and the fix; written {init = v, bounds = [v, v]} it is a decision entry the box applies to."""
    text = (LIBRARY / "fourbar_path" / "picking_arc.toml").read_text()
    assert "r1 = {init = 110, bounds = [20, 200]}" in text
    box = "\n[tolerance]\nlength = 0.5\nangle = 0.05\nsamples = 20\n"
    fixed = tmp_path / "fixed.toml"
    fixed.write_text(text.replace("r1 = {init = 110, bounds = [20, 200]}", "r1 = 130") + box)
    with pytest.raises(SpecError, match=r"cannot hold the tolerance of r1: .*\{init = v, bounds = \[v, v\]\}"):
        run_solve(load_spec(fixed), starts=1, workers=1)
    pinned = tmp_path / "pinned.toml"
    pinned.write_text(text.replace("r1 = {init = 110, bounds = [20, 200]}", "r1 = {init = 130, bounds = [130, 130]}")
                      + box)
    result, _, _ = run_solve(load_spec(pinned), starts=1, workers=1)
    assert result.design["r1"] == 130.0
    assert all(r["satisfied"] for r in result.rules if r["name"].endswith("@tolerance"))


@pytest.mark.slow
def test_a_robust_grashof_any_path_is_held_and_read_on_the_spec_s_samples(tmp_path):
    """grashof = "any" holds closure and transmission between the targets (exactly, at each gap's extremes: the
    rows' crank angles are functions of the targets' ones).  Under a tolerance box the whole problem is solved and
    read at the answer's crank angles: every @tolerance row holds and is no better than its rule's own margin
    there."""
    text = (LIBRARY / "fourbar_path" / "picking_arc.toml").read_text()
    assert 'grashof = "crank_rocker"' in text
    path = tmp_path / "any.toml"
    # 8 samples per gap for the check and re-check (the default 36 makes this a slower test)
    path.write_text(text.replace('grashof = "crank_rocker"', 'grashof = "any"').replace("seed = 0", "seed = 0\nsamples = 8")
                    + "\n[tolerance]\nlength = 0.5\nangle = 0.05\nsamples = 20\nseed = 0\n")
    loaded = load_spec(path)
    assert loaded.model.solver.samples == 8
    result, _, _ = run_solve(loaded, starts=1, workers=1)
    nominal = {r["name"]: r["margin"] for r in result.rules if not r["name"].endswith("@tolerance")}
    held = [r for r in result.rules if r["name"].endswith("@tolerance")]
    assert {r["name"].removesuffix("@tolerance") for r in held} == set(nominal)
    for r in held:
        assert r["satisfied"] and 0 <= r["margin"] <= nominal[r["name"].removesuffix("@tolerance")] + 1e-9, r
    assert result.status in ("optimal", "feasible")


@pytest.mark.slow
def test_a_signal_while_the_answer_is_finished_keeps_every_start(tmp_path, monkeypatch):
    """Ctrl-C after every start finished, while the kind finishes the answer (a robust solve's Monte-Carlo check,
    the slow part of one): the run keeps its starts and their best as an interrupted result (exit 130, --resume),
    and the interrupted result's finish does not start the Monte-Carlo again."""
    from synthesis.core import interrupt
    from synthesis.tolerance import analysis

    path = tmp_path / "robust.toml"
    path.write_text((LIBRARY / "picker" / "picker_double_crank_redesign.toml").read_text()
                    + "\n[tolerance]\nlength = 0.1\nangle = 0.1\nsamples = 50\n")
    calls = []

    def interrupted_check(*args, **kwargs):
        calls.append(1)
        interrupt.simulate()             # the signal handler records the signal, then raises
        raise KeyboardInterrupt

    monkeypatch.setattr(interrupt, "_pending", None)
    from synthesis.tolerance import robust

    monkeypatch.setattr(analysis, "monte_carlo", interrupted_check)
    monkeypatch.setattr(robust, "monte_carlo", interrupted_check)       # robust's own name of it (imported there)
    with pytest.raises(interrupt.Interrupted) as caught:
        run_solve(load_spec(path), starts=2, workers=1)
    kept, reports, _ = caught.value.partial
    assert caught.value.exit_code == 130 and len(reports) == 2 and len(calls) == 1
    assert kept.status == "interrupted"
    assert kept.to_json()["facts"]["tolerance"]["monte_carlo"]["samples"] == 0


def test_at_bounds_names_the_free_variables_on_a_bound_by_their_result_names():
    """The infeasible message's "sits at its lower bound" list: a free variable within 1e-6 of its range from a bound
    (IPOPT stops a hair inside), a fixed one never; a kind whose result.json names its variables otherwise (guide_tube:
    delta_<tube>) gives those names (NLP.design_names), else the list was silently empty."""
    import numpy as np

    from synthesis.core.kind import Setting
    from synthesis.core.solve import at_bounds

    box = [[0.0, 1.0], [0.0, 1.0], [2.0, 2.0], [-5.0, 5.0]]
    design = {"a": 1e-7, "b": 0.5, "c": 2.0, "d": 5.0 - 1e-6}
    assert at_bounds(["a", "b", "c", "d"], box, design) == [{"name": "a", "side": "lower", "bound": 0.0},
                                                             {"name": "d", "side": "upper", "bound": 5.0}]
    kind = kinds.solving_kind("guide_tube")
    spec = load_spec(LIBRARY / "guide_tube" / "cai2020_delta2.toml").model
    nlp = kind.solving().build(Setting(spec, 0, kind.solving().prepare(spec)), True)
    design = nlp.design(np.asarray(nlp.bounds, float)[:, 0])          # every free angle at its lower bound
    assert [b["name"] for b in at_bounds(nlp.design_names, nlp.bounds, design)] == list(nlp.design_names)
    assert set(nlp.design_names) <= set(design)


def test_a_start_line_names_what_stands_in_the_way_of_an_infinite_violation():
    """The terminal printed "worst violation inf" for a start with a rule not evaluated and no reason at all."""
    from synthesis.constraints import not_evaluated
    from synthesis.runs.events import violation_text as _violation_text

    outcome = SimpleNamespace(start=11, return_status="Solve_Succeeded", success=True)
    missing = not_evaluated("p1p3_distance", 100, 120, "mm", "machine frame", "P1 not found: the claw does not cross")
    assert _violation_text(StartReport(outcome, False, 0.93)) == "worst violation 0.93"
    assert (_violation_text(StartReport(outcome, False, math.inf, records=[missing.record()]))
            == "p1p3_distance not evaluated: P1 not found: the claw does not cross")
    assert (_violation_text(StartReport(outcome, False, math.inf, why="l10 = 161.37 lies 21 outside its fixed value"))
            == "no design: l10 = 161.37 lies 21 outside its fixed value")


def test_the_elastic_points_are_the_kinds_choice_then_the_other_then_the_least_violated_each_once():
    """A review found three identical elastic re-solves (starts that ended on one design) and the best start left
    out for kinds that relax from the given design."""
    import numpy as np

    from synthesis.core.kind import KindNLP
    from synthesis.core.solve import elastic_points

    def report(start: int, violation: float, design: dict, why=None) -> StartReport:
        return StartReport(SimpleNamespace(start=start, design=design, details={}), False, violation, why=why)

    same = {"a": 2.0, "b": 3.0}
    reports = [report(0, 5.0, {"a": 9.0, "b": 9.0}), report(1, 0.5, same), report(2, 0.7, dict(same)),
               report(3, 0.6, {"a": 4.0, "b": 4.0}), report(4, math.inf, {"a": 7.0, "b": 7.0}, why="no design"),
               report(5, 0.8, {"a": 5.0, "b": 5.0})]
    run = SimpleNamespace(reports=reports, best=reports[1])
    class TwoVariables(KindNLP):
        names, init, bounds = ["a", "b"], np.array([1.0, 1.0]), np.array([[0.0, 10.0], [0.0, 10.0]])

        def solve(self, start, x_design):
            raise AssertionError("the elastic points are chosen without a solve")
    nlp = TwoVariables()
    given = elastic_points(SimpleNamespace(elastic_from="given"), run, nlp)
    assert [list(p) for p in given] == [[1.0, 1.0], [2.0, 3.0], [4.0, 4.0], [5.0, 5.0]]   # start 2 = start 1
    best = elastic_points(SimpleNamespace(elastic_from="best"), run, nlp)
    assert [list(p) for p in best] == [[2.0, 3.0], [4.0, 4.0], [5.0, 5.0], [9.0, 9.0]]          # given: 5th
    assert all(isinstance(p, np.ndarray) for p in best)


def test_a_limit_of_minus_zero_reads_as_zero():
    """tillage's rearward-motion limit is stored as -0.0 (a negated 0): the tables read "<= -0"."""
    from synthesis.constraints.base import limit_text

    assert limit_text((None, -0.0)) == "<= 0"
    assert limit_text((-0.0, 1.5)) == "[0, 1.5]"
    assert limit_text((-2.0, None)) == ">= -2"
    assert limit_text((None, None)) == "-"


def test_a_rule_the_spec_fixes_is_named_with_its_field_not_the_bounds():
    """An elastic diagnosis giving up on a rule no design variable moves (elastic.fixed_by, from core.pinned): the
    exit-3 message names the spec field that fixes it where it would blame the bounds or the mechanism."""
    reports = [_report(0, "Infeasible_Problem_Detected", False)]
    units, scales = {"planting_depth": "mm", "gap": "mm"}, {"planting_depth": 5.0, "gap": 1.0}
    elastic = ElasticDiagnosis("Solve_Succeeded", True, {"planting_depth": 15.0, "gap": 2.0}, units, scales,
                               alone={"planting_depth": 15.0, "gap": 2.0},
                               fixed={"planting_depth": "[soil] analysis_depth"})
    assert elastic.out_of_reach == ["planting_depth", "gap"]
    message = str(unsatisfied_error("infeasible", ["planting_depth", "gap"], reports, elastic,
                                    samples_hint="[solver] samples"))
    assert ("planting_depth (misses its limit by 15 mm; still by 15 mm re-solved alone from there, every other rule "
            "relaxed: [soil] analysis_depth fixes it (no design variable moves it), not the other rules)") in message
    assert ("gap (misses its limit by 2 mm; still by 2 mm re-solved alone from there, every other rule relaxed: near "
            "that design the variable bounds or the mechanism hold it back, not the other rules)") in message
    data = elastic.to_json()
    assert data["fixed_by"] == {"planting_depth": "[soil] analysis_depth"}
    assert ElasticDiagnosis.from_json(data).fixed == elastic.fixed
    assert "fixed_by" not in ElasticDiagnosis("Solve_Succeeded", True, {"gap": 2.0}, units, scales).to_json()


@pytest.mark.slow         # about 20 s: four starts, the elastic re-solve and a check
def test_check_of_the_elastic_design_fails_the_rules_the_diagnosis_gives_up_on_and_no_other(tmp_path):
    """redesign_from_example1 asking 3 m/s at P2: the diagnosis gives up on p2_speed alone, while `check elastic.toml`
    failed transmission_angle_min too, by 4.5e-7 deg (held 1e-8 of its scale inside its limit by the elastic form,
    less than what separates IPOPT's rows from the check's reading).  Likewise p4p6_min 80 mm: entry_angle and
    p1p2p3_collinearity failed by 8.4e-7 deg and 1.2e-7 deg beside the two rules given up on."""
    from solving import agrisynth

    text = (PLANTING / "redesign_from_example1.toml").read_text()
    for name, rules, given_up in (("slow_p2", "p2_speed_min = 3.0", ["p2_speed"]),
                                  ("long_hole", "p4p6_min = 80.0", ["p4p6_distance", "transmission_angle_min"])):
        spec = tmp_path / f"{name}.toml"
        spec.write_text(text.replace('name = "redesign_from_example1"', f'name = "{name}"').replace(
            "[soil]", f"[rules]\n{rules}\n\n[soil]", 1))
        solved = agrisynth("solve", str(spec), "--starts", "4", "--workers", "1", "--out", str(tmp_path))
        assert solved.returncode == 3, solved.stderr
        result = json.loads((tmp_path / name / "result.json").read_text())
        assert result["elastic"]["relaxed"] == given_up
        checked = agrisynth("check", str(tmp_path / name / "elastic.toml"), "--out", str(tmp_path))
        assert checked.returncode == 1, checked.stderr
        rules_at = json.loads((tmp_path / f"{name}_elastic-check" / "result.json").read_text())["rules"]
        assert sorted(r["name"] for r in rules_at if not r["satisfied"]) == sorted(given_up)


@pytest.mark.slow         # about 15 s: four starts, the elastic re-solve and a check
def test_the_rules_the_elastic_design_misses_between_the_samples_are_named(tmp_path):
    """rotary_planetary's smooth loop asked a 700 mm loop (it reaches 462): the relaxation gives up on
    trajectory_height, and holds pair_ratio, pitch_curve_concavity and pitch_normal_angle on their limits at the NLP's
    72 samples a turn -- between them they miss, and `check elastic.toml` failed them while the message said they
    hold.  Now the message and result.json (elastic.missed_between_samples) name them, with the check's misses."""
    from solving import agrisynth

    text = (LIBRARY / "rotary_planetary" / "smooth_loop_redesign.toml").read_text()
    spec = tmp_path / "tall.toml"
    spec.write_text(text.replace('name = "smooth_loop_redesign"', 'name = "tall"').replace(
        "planting_depth = [15.0, 45.0]", "planting_depth = [15.0, 20.0]").replace(
        "trajectory_height_min = 260.0", "trajectory_height_min = 700.0"))
    solved = agrisynth("solve", str(spec), "--starts", "4", "--workers", "1", "--out", str(tmp_path))
    assert solved.returncode == 3, solved.stderr
    elastic = json.loads((tmp_path / "tall" / "result.json").read_text())["elastic"]
    assert elastic["relaxed"] == ["trajectory_height"]
    between = elastic.get("missed_between_samples") or {}
    assert between and "On the check's finer grid its design also misses" in solved.stderr
    checked = agrisynth("check", str(tmp_path / "tall" / "elastic.toml"), "--out", str(tmp_path))
    rules = json.loads((tmp_path / "tall_elastic-check" / "result.json").read_text())["rules"]
    failing = {r["name"]: -r["margin"] for r in rules if not r["satisfied"]}
    assert set(failing) == {"trajectory_height", *between}
    assert all(between[n]["miss"] == pytest.approx(failing[n], rel=1e-9) for n in between)
    units = {r["name"]: r["unit"] for r in rules}
    assert all(between[n]["unit"] == units[n] for n in between)


@pytest.mark.slow         # about 5 s
def test_a_rule_given_up_on_at_an_operating_point_is_not_said_missed_between_samples(tmp_path):
    """The guide tube's mu envelope asking a 2 mm spacing error: the relaxation gives up on spacing_error@mu=...
    (the NLP's names), and the check reads spacing_error and spacing_error@envelope -- which were named as rules the
    elastic design 'also misses between the NLP's samples'.  A rule is matched by its base name."""
    from solving import agrisynth

    text = (LIBRARY / "guide_tube" / "uniform_spacing_mu_envelope.toml").read_text()
    assert "\nmax_spacing_error = 6 " in text
    spec = tmp_path / "tight.toml"
    spec.write_text(text.replace("\nmax_spacing_error = 6 ", "\nmax_spacing_error = 2 "))
    solved = agrisynth("solve", str(spec), "--workers", "1", "--out", str(tmp_path))
    assert solved.returncode == 3, solved.stderr
    name = json.loads((tmp_path / "uniform_spacing_mu_envelope" / "result.json").read_text())
    elastic = name["elastic"]
    assert any(r.startswith("spacing_error@mu=") for r in elastic["relaxed"])
    assert "missed_between_samples" not in elastic and "between the NLP's samples" not in solved.stderr
