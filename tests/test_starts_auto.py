"""solver.confidence in every solve's result and ``--starts auto`` (synthesis/core/confidence.py, core/solve.py
AutoStarts; docs/ARCHITECTURE.md "result.json")."""

from __future__ import annotations

import json

import pytest

from conftest import LIBRARY
from solving import agrisynth, interrupted_auto_run
from synthesis import kinds
from synthesis.core import startlog
from synthesis.core.kind import Setting
from synthesis.core.solve import AutoStarts, _not_uniform, run_solve
from synthesis.kinds import solve_spec
from synthesis.result import RUN_MARKER, file_sums
from synthesis.spec import load_spec

TOY = """kind = "toy_disc"
name = "toy"
x = {{ init = 0.0, bounds = [-20.0, 20.0] }}
y = {{ init = 1.0, bounds = [-20.0, 20.0] }}
radius = 10.0
y_min = -5.0
target = [30.0, 40.0]
[solver]
starts = {starts}
"""


@pytest.fixture
def toy():
    import toy_kind

    kinds.register(toy_kind.KIND)
    yield toy_kind.KIND
    kinds.unregister("toy_disc")


def _toy(tmp_path, starts="20"):
    path = tmp_path / "toy.toml"
    path.write_text(TOY.format(starts=starts))
    return load_spec(path)


def test_the_toy_kinds_one_optimum_gives_the_closed_form_statement(tmp_path, toy):
    """The toy (nearest point of a disc to a target outside it) has one optimum; every one of 20 starts reaches it:
    W = 1, N = 20, so P(best is global) = (N - W - 1) / (N - 1) = 18/19, E[K] = W (N - 1) / (N - W - 2) = 19/17,
    unseen basin share W (W + 1) / (N (N - 1)) = 2/380, and the stopping rule holds (19/17 - 1 < 0.5)."""
    result, _, _ = run_solve(toy, _toy(tmp_path), workers=1)
    stated = json.loads(json.dumps(result.to_json()))["solver"]["confidence"]
    assert result.to_json()["schema_version"] == 5
    assert (stated["starts_counted"], stated["distinct_optima"], stated["starts_at_best"]) == (20, 1, 20)
    assert stated["probability_best_is_global"] == pytest.approx(18 / 19, rel=1e-15)
    assert stated["expected_optima"] == pytest.approx(19 / 17, rel=1e-15)
    assert stated["unseen_basin_share"] == pytest.approx(2 / 380, rel=1e-15)
    assert stated["stopping_rule_met"] is True and stated["distinct_designs"] == 1
    assert stated["optima"] == [{"objective": stated["optima"][0]["objective"], "starts": 20, "first_start": 0,
                                 "designs": 1}]
    assert stated["optima"][0]["objective"] == pytest.approx(40.0**2, rel=1e-7) and stated["assumptions_not_met"] == []


@pytest.mark.slow
def test_a_library_spec_with_two_local_optima_says_how_many_and_how_sure():
    """picker_double_crank_redesign's 8 starts (problems/picker) all converge with every rule held, at two objective
    values: 0.0978 mm (starts 3.., 4 starts, at two designs) and 0.2113 mm (4 starts from start 0).  N = 8, W = 2:
    P(best is global) = 5/7, E[K] = 2 x 7 / 4 = 3.5, unseen share 6/56; the rule is not met (1.5 unseen)."""
    result, _, _ = solve_spec(load_spec(LIBRARY / "picker" / "picker_double_crank_redesign.toml"), workers=1)
    stated = result.solver["confidence"]
    assert (stated["starts_counted"], stated["distinct_optima"], stated["starts_at_best"]) == (8, 2, 4)
    assert stated["probability_best_is_global"] == pytest.approx(5 / 7, rel=1e-15)
    assert stated["expected_optima"] == pytest.approx(3.5, rel=1e-15) and stated["stopping_rule_met"] is False
    assert stated["unseen_basin_share"] == pytest.approx(6 / 56, rel=1e-15) and stated["distinct_designs"] == 3
    assert [(o["starts"], o["first_start"], o["designs"]) for o in stated["optima"]] == [(4, 3, 2), (4, 0, 1)]
    assert stated["optima"][0]["objective"] == pytest.approx(0.09784125335134168, rel=1e-9)
    assert stated["optima"][1]["objective"] == pytest.approx(0.211294181602809, rel=1e-6)


def test_a_flat_valley_of_equal_objectives_is_one_optimum_not_eight():
    """comb_finger's largest combing angle depends on alpha alone: its 8 starts end at 8 designs of one objective
    (to 1e-9).  Counted per design the estimate would say P(global) undefined and expect ever more optima; counted per
    objective value it is one optimum reached by all 8: P = 6/7, and the note says why."""
    result, _, _ = solve_spec(load_spec(LIBRARY / "comb_finger" / "redesign_tip_speed.toml"), workers=1)
    stated = result.solver["confidence"]
    assert (stated["starts_counted"], stated["distinct_optima"], stated["distinct_designs"]) == (8, 1, 8)
    assert stated["probability_best_is_global"] == pytest.approx(6 / 7, rel=1e-15)
    assert stated["assumptions_not_met"] == ["8 optima at distinct designs share 1 objective value (a flat valley or "
                                             "symmetric optima): counted as one optimum per value"]


def test_fourbar_path_says_its_starts_are_not_uniform():
    """A kind that builds its own (screened) starts: the statement names the assumption it breaks."""
    loaded = load_spec(LIBRARY / "fourbar_path" / "picking_arc.toml")
    solving = kinds.get("fourbar_path").solving()
    nlp = solving.build(Setting(loaded.model, 0, solving.prepare(loaded.model)), False)
    assert "the kind builds its own starts (screened), not uniform in the box" in _not_uniform(nlp)


def test_auto_stops_by_the_rule_on_a_unimodal_problem_after_the_minimum_and_equals_that_many_fixed_starts(tmp_path,
                                                                                                          toy):
    """One optimum: the first batch (16 starts, all converged) meets the rule (E[unseen] = 15/13 - 1 < 0.5) with the
    minimum of 16 converged; the answer is --starts 16's to the bit."""
    loaded = _toy(tmp_path)
    auto, _, _ = run_solve(toy, loaded, workers=1, auto=AutoStarts())
    fixed, _, _ = run_solve(toy, loaded, starts=16, workers=1)
    assert auto.solver["auto"]["stopped_by"] == "rule" and auto.solver["auto"]["batches"] == [16]
    assert auto.solver["starts"] == 16 == auto.solver["starts_run"]
    assert auto.objective["value"] == fixed.objective["value"] and auto.design == fixed.design
    assert auto.solver["confidence"] == fixed.solver["confidence"]
    assert [s["objective"] for s in auto.starts] == [s["objective"] for s in fixed.starts]


def test_auto_below_its_minimum_grows_by_whole_batches_and_stops_at_the_fixed_run_of_its_total(tmp_path, toy):
    """min_converged 20 is not met by the first batch of 16: the second batch is the whole --starts 32 run (its own
    Latin hypercube), start 0 carried; every start of the first batch is reported to on_start, then 32 more."""
    loaded = _toy(tmp_path)
    batches, seen = [], []
    auto, _, _ = run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20),
                           on_batch=lambda total, nested: batches.append(total),
                           on_start=lambda report, best: seen.append(report.outcome.start))
    fixed, _, _ = run_solve(toy, loaded, starts=32, workers=1)
    assert batches == [16, 32] and auto.solver["auto"]["batches"] == [16, 32]
    assert seen == list(range(16)) + list(range(32))
    assert auto.solver["auto"]["stopped_by"] == "rule" and auto.solver["starts"] == 32
    assert auto.objective["value"] == fixed.objective["value"] and auto.design == fixed.design
    assert [s["design"] for s in auto.starts] == [s["design"] for s in fixed.starts]


def _combing(tmp_path, starts: str):
    """comb_finger's redesign_max_combing (an 8-start solve of a tenth of a second) with [solver] starts = STARTS."""
    text = (LIBRARY / "comb_finger" / "redesign_max_combing.toml").read_text()
    assert "\nstarts = 8\n" in text
    spec = tmp_path / "combing.toml"
    spec.write_text(text.replace("\nstarts = 8\n", f"\nstarts = {starts}\n"))
    return spec


def test_auto_stops_by_max_starts(tmp_path):
    """--starts auto --max-starts 8: one batch of 8 (7 Latin-hypercube starts and the given design): not the 16
    converged starts the rule needs, so the budget stops it -- through the command line, result.json says so.  The
    8 starts end at 5 designs of one combing angle: one optimum, P = 6/7."""
    spec = _combing(tmp_path, "4")
    run = agrisynth("solve", spec, "--starts", "auto", "--max-starts", "8", "--workers", "1", "--out", tmp_path / "o")
    assert run.returncode == 0, run.stderr
    data = json.loads((tmp_path / "o" / "redesign_max_combing" / "result.json").read_text())
    assert data["solver"]["auto"] == {"stopped_by": "max_starts", "batches": [8], "max_starts": 8,
                                      "time_limit_s": None, "min_converged": 16, "first": 16}
    assert data["solver"]["starts"] == 8 and data["solver"]["confidence"]["starts_counted"] == 8
    said = " ".join(run.stdout.split())
    assert "confidence: 1 distinct optimum in 8 converged starts, best reached by 8; P(best is global) ~ 0.86" in said
    assert "--starts auto: 8 starts, stopped by max_starts" in said
    assert "global optimum (how sure)" in (tmp_path / "o" / "redesign_max_combing" / "report.html").read_text()


def test_a_spec_may_ask_for_auto_and_budgets_need_auto(tmp_path):
    spec = _combing(tmp_path, '"auto"')
    loaded = load_spec(spec)
    assert loaded.model.solver.starts_auto and loaded.model.solver.starts == 8      # the kind's default
    run = agrisynth("solve", spec, "--max-starts", "8", "--workers", "1", "--out", tmp_path / "o")
    assert run.returncode == 0, run.stderr
    assert json.loads((tmp_path / "o" / "redesign_max_combing" / "result.json").read_text())["solver"]["auto"][
        "stopped_by"] == "max_starts"
    spec = _combing(tmp_path, "4")
    run = agrisynth("solve", spec, "--max-starts", "8", "--workers", "1", "--out", tmp_path / "p")
    assert run.returncode == 2 and "--max-starts and --time-limit are budgets of --starts auto" in run.stderr
    run = agrisynth("solve", spec, "--starts", "often", "--workers", "1", "--out", tmp_path / "p")
    assert run.returncode == 2 and "'often' is neither a whole number" in run.stderr


def test_auto_gives_the_same_answer_and_count_on_one_and_two_workers(tmp_path, toy):
    loaded = _toy(tmp_path)
    one, _, _ = run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20))
    two, _, _ = run_solve(toy, loaded, workers=2, auto=AutoStarts(min_converged=20))
    assert one.solver["auto"] == two.solver["auto"] and one.solver["starts"] == two.solver["starts"] == 32
    assert one.objective["value"] == two.objective["value"] and one.design == two.design
    assert one.solver["confidence"] == two.solver["confidence"]


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_an_interrupted_auto_run_resumed_gives_the_uninterrupted_answer(tmp_path):
    """The run folder of an auto run cut after 5 starts of its first batch (its starts.jsonl: header, the batch's
    line, 5 starts) is finished by --resume: the same answer, statement and count."""
    spec = _combing(tmp_path, "4")
    whole = agrisynth("solve", spec, "--starts", "auto", "--workers", "1", "--out", tmp_path / "whole")
    assert whole.returncode == 0, whole.stderr
    folder = tmp_path / "whole" / "redesign_max_combing"
    lines = (folder / startlog.FILENAME).read_text().splitlines()
    assert json.loads(lines[1]) == {startlog.BATCH: 16}
    (folder / startlog.FILENAME).write_text("\n".join(lines[:7]) + "\n")
    # as an interrupted run's own commit would record it: the marker's sum of the starts.jsonl it wrote
    marker = json.loads((folder / RUN_MARKER).read_text())
    marker["sha256"].update(file_sums(folder, [startlog.FILENAME]))
    (folder / RUN_MARKER).write_text(json.dumps(marker) + "\n")
    before = json.loads((folder / "result.json").read_text())
    resumed = agrisynth("solve", spec, "--resume", folder, "--workers", "1")
    assert resumed.returncode == 0, resumed.stderr
    after = json.loads((folder / "result.json").read_text())
    assert "resumed: 5 finished start(s)" in " ".join(resumed.stdout.split())
    assert before["solver"]["auto"]["batches"] == [16]
    for key in ("confidence", "auto", "starts", "best_start"):
        assert after["solver"][key] == before["solver"][key]
    assert after["objective"]["value"] == before["objective"]["value"] and after["design"] == before["design"]


def test_a_resumed_auto_run_continues_the_batch_it_was_in(tmp_path, toy):
    """Core: an auto run stopped inside its second batch (32) resumes there with that batch's finished starts: the
    first batch is not solved again and the answer is the uninterrupted one."""
    loaded = _toy(tmp_path)
    kept = []
    whole, _, _ = run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20), record=kept.append)
    second = {out.start: out for out in kept[16:16 + 7]}
    seen = []
    resumed, _, _ = run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20), finished=second,
                              resumed_batch=32, on_start=lambda report, best: seen.append(report.outcome.start))
    assert seen == list(range(32))
    assert resumed.solver["auto"] == whole.solver["auto"] and resumed.solver["confidence"] == whole.solver["confidence"]
    assert resumed.objective["value"] == whole.objective["value"] and resumed.design == whole.design


def test_ctrl_c_between_two_batches_keeps_the_finished_batch(tmp_path, toy):
    """A signal as batch 32 begins (its NLP not yet built): the run stops Interrupted, keeping batch 16 whole --
    status interrupted, the design and starts of --starts 16 -- where it used to end with nothing kept."""
    loaded = _toy(tmp_path)
    fixed, _, _ = solve_spec(loaded, starts=16, workers=1)
    caught, _ = interrupted_auto_run(toy, loaded)
    kept, reports, _ = caught.partial
    assert kept.status == "interrupted" and len(reports) == 16 and caught.exit_code == 130
    assert kept.solver["auto"]["stopped_by"] == "interrupted" and kept.solver["auto"]["batches"] == [16, 32]
    assert kept.design == fixed.design and kept.objective["value"] == fixed.objective["value"]


def test_ctrl_c_inside_a_batch_keeps_the_better_of_it_and_the_last_finished_batch(tmp_path, toy):
    """A signal 3 starts into batch 32: those 3 starts' best ties batch 16's (the toy's one optimum), so the kept
    result is batch 16 whole (every one of its starts); the batches begun are both."""
    loaded = _toy(tmp_path)
    fixed, _, _ = solve_spec(loaded, starts=16, workers=1)
    caught, told = interrupted_auto_run(toy, loaded, after_told=16 + 3)
    kept, reports, _ = caught.partial
    assert len(told) == 16 + 3 and len(reports) == 16 and kept.solver["auto"]["batches"] == [16, 32]
    assert kept.design == fixed.design and kept.objective["value"] == fixed.objective["value"]


@pytest.mark.slow         # seconds: two commands
def test_resume_in_the_other_start_order_is_refused_before_any_folder_is_made(tmp_path):
    """An auto run's starts.jsonl whose last batch mark says "nested" (the kind's own order) while this kind numbers
    comb_finger's starts in the fixed order: --resume exits 2 naming both orders, and leaves no staging folder."""
    spec = _combing(tmp_path, "4")
    out = tmp_path / "out"
    first = agrisynth("solve", spec, "--starts", "auto", "--max-starts", "16", "--workers", "1", "--out", out)
    assert first.returncode == 0, first.stderr
    folder = out / "redesign_max_combing"
    log = folder / startlog.FILENAME
    log.write_text(log.read_text().replace('{"auto_batch":16}', '{"auto_batch":16,"nested":true}'))
    resumed = agrisynth("solve", spec, "--resume", folder, "--workers", "1")
    said = " ".join(resumed.stderr.split())
    assert resumed.returncode == 2 and "numbered its starts in the kind's own order" in said, resumed.stderr
    assert "in the fixed order" in said and "Traceback" not in resumed.stderr
    assert sorted(p.name for p in out.iterdir()) == ["redesign_max_combing"]


@pytest.mark.slow
def test_auto_on_a_library_crank_rocker_equals_the_fixed_run_of_its_count():
    """crank_rocker_max_transmission: the first batch of 16 has fewer than 16 converged starts, the second (32)
    meets the rule; the answer is --starts 32's to the bit (about 20 s)."""
    loaded = load_spec(LIBRARY / "picker" / "crank_rocker_max_transmission.toml")
    auto, _, _ = run_solve(kinds.solving_kind_for(loaded), loaded, workers=1, auto=AutoStarts())
    fixed, _, _ = solve_spec(loaded, starts=auto.solver["starts"], workers=1)
    assert auto.solver["auto"]["batches"] == [16, 32] and auto.solver["auto"]["stopped_by"] == "rule"
    assert auto.objective["value"] == fixed.objective["value"] and auto.design == fixed.design
    assert auto.solver["confidence"] == fixed.solver["confidence"]


def test_auto_on_rules_no_start_meets_stops_after_one_batch(tmp_path, toy):
    """The toy above y = 12 inside a disc of radius 10: no start meets every rule; auto stops after its first batch
    of 16 (not 1008 starts to max_starts) and the elastic diagnosis names the conflict as for fixed starts."""
    path = tmp_path / "toy.toml"
    path.write_text(TOY.format(starts=4).replace("y_min = -5.0", "y_min = 12.0"))
    result, _, _ = run_solve(toy, load_spec(path), workers=1, auto=AutoStarts())
    assert result.status == "infeasible" and set(result.elastic["conflicting"]) == {"inside_disc", "above_line"}
    assert result.solver["auto"]["stopped_by"] == "none_converged" and result.solver["starts"] == 16
    assert result.solver["confidence"]["starts_counted"] == 0 and result.solver["confidence"]["optima"] == []



@pytest.mark.slow         # about a minute: 48 starts of the torque-limited double crank
def test_auto_never_returns_a_worse_design_than_an_earlier_batch_found():
    """picker_double_crank_torque_limited, seed 12: the 16-start batch (the fixed --starts 16 run) reaches the best
    known optimum, 6.23814 mm; the 32-start batch, a hypercube of its own, misses it.  The run stopped there by the
    rule with the worse 6.23954 mm and "1 distinct optimum ... P ~ 0.97" -- its last batch's statement, ignorant of
    the better design it had solved.  Now the rule may not stop on a batch an earlier one beats, and the answer is
    that earlier batch's (auto.answer_batch), the same as --starts 16."""
    loaded = load_spec(LIBRARY / "picker" / "picker_double_crank_torque_limited.toml")
    fixed, _, _ = solve_spec(loaded, starts=16, seed=12, workers=1)
    kind = kinds.solving_kind_for(loaded)
    result, _, _ = run_solve(kind, loaded, None, 12, 1, auto=AutoStarts(max_starts=32))
    auto = result.solver["auto"]
    assert auto["batches"] == [16, 32] and auto["stopped_by"] == "max_starts" and auto["answer_batch"] == 16
    assert result.design == fixed.design and result.objective["value"] == pytest.approx(6.23814, abs=5e-6)
    assert result.solver["confidence"] == fixed.solver["confidence"]


@pytest.mark.slow         # seconds
def test_auto_goes_on_while_its_starts_meet_every_rule_short_of_full_tolerance(tmp_path):
    """steering_redesign_27 with max_iter = 11: every start of the first batch meets every rule but stops at the
    iteration limit, so none is counted by the statement; the run stopped there (none_converged, status feasible)
    as if the rules conflicted, where a fixed 32-start run is optimal.  Now none_converged needs a batch with no
    start meeting every rule."""
    text = (LIBRARY / "steering" / "steering_redesign_27.toml").read_text()
    assert "[solver]" in text
    (tmp_path / "spec.toml").write_text(text.replace("[solver]", "[solver]\nmax_iter = 11", 1))
    loaded = load_spec(tmp_path / "spec.toml")
    kind = kinds.solving_kind_for(loaded)
    result, reports, _ = run_solve(kind, loaded, None, 6, 1, auto=AutoStarts(max_starts=64))
    assert result.solver["auto"]["stopped_by"] != "none_converged" and result.solver["auto"]["batches"][-1] > 16
    assert result.status == "optimal"


def test_auto_begins_no_batch_projected_past_its_time_limit(tmp_path, toy):
    """A time limit of a millisecond: the first batch always runs whole; the second (32 starts, projected at twice
    the first's time) would end past it, so the run stops there by time_limit with the first batch's answer."""
    loaded = _toy(tmp_path)
    result, _, _ = run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20, time_limit_s=1e-3))
    fixed, _, _ = run_solve(toy, loaded, starts=16, workers=1)
    assert result.solver["auto"]["stopped_by"] == "time_limit" and result.solver["auto"]["batches"] == [16]
    assert result.solver["auto"]["time_limit_s"] == 1e-3 and result.objective["value"] == fixed.objective["value"]


def test_an_interrupt_of_a_resumed_auto_run_keeps_the_batch_the_interrupted_run_had_finished(tmp_path, toy):
    """Resumed in batch 32 with 3 of its starts and batch 16 finished: the resumed run logs batch 16 again (its
    mark, its starts) and a signal 2 starts later keeps the better of the batch in progress and batch 16 -- as the
    interrupted run would -- where it kept those 5 starts of batch 32 alone (batch 16 lost from the folder)."""
    import signal

    from synthesis.core import interrupt
    from synthesis.core.interrupt import Interrupted

    loaded = _toy(tmp_path)
    kept: list = []
    run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20), record=kept.append)
    first = {out.start: out for out in kept[:16]}
    second = {out.start: out for out in kept[16:16 + 3]}
    fixed, _, _ = solve_spec(loaded, starts=16, workers=1)
    logged: list = []
    told: list = []

    def on_start(report, best):
        told.append(report.outcome.start)
        if len(told) == 3 + 2:
            interrupt.simulate(signal.SIGINT)
    try:
        with pytest.raises(Interrupted) as caught:
            run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20), finished=second, resumed_batch=32,
                      previous=[(16, first)], on_start=on_start, record=lambda out: logged.append(out.start),
                      on_batch=lambda total, nested: logged.append(f"batch {total}"))
    finally:
        interrupt.uninstall()
    result, reports, _ = caught.value.partial
    assert logged[:18] == ["batch 16", *range(16), "batch 32"]     # the new starts.jsonl holds batch 16 again
    assert len(reports) == 16 and result.solver["auto"]["batches"] == [16, 32]
    assert result.design == fixed.design and result.objective["value"] == fixed.objective["value"]


@pytest.mark.parametrize("when", ["recounting", "building"])
def test_an_interrupt_of_a_resumed_auto_run_before_its_batch_is_counted_again_keeps_nothing(tmp_path, toy, when):
    """A signal while the resumed batch's 3 finished starts are counted again (at the 2nd), or as its NLP is built:
    the batch replayed before it must not be kept -- the new starts.jsonl lacks finished starts of batch 32, and
    the run being resumed would be replaced by one with fewer starts."""
    import signal

    from synthesis.core import interrupt
    from synthesis.core import solve as core
    from synthesis.core.interrupt import Interrupted

    loaded = _toy(tmp_path)
    kept: list = []
    run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20), record=kept.append)
    first = {out.start: out for out in kept[:16]}
    second = {out.start: out for out in kept[16:16 + 3]}
    told: list = []
    batches: list = []

    def on_start(report, best):
        told.append(report.outcome.start)
        if when == "recounting" and len(told) == 2:
            interrupt.simulate(signal.SIGINT)

    def on_batch(total, nested):
        batches.append(total)
        if when == "building" and total == 32:          # the replay done, batch 32 not yet built
            interrupt.simulate(signal.SIGINT)
            raise KeyboardInterrupt
    try:
        with pytest.raises(Interrupted) as caught:
            core.run_auto(toy, Setting(loaded.model, 0, toy.solving().prepare(loaded.model)),
                          AutoStarts(min_converged=20), workers=1, finished=second, resumed_batch=32,
                          previous=[(16, first)], on_start=on_start, on_batch=on_batch)
    finally:
        interrupt.uninstall()
    assert batches == [16, 32] and caught.value.partial is None


def test_the_batch_before_the_one_an_auto_run_was_solving_is_read_back(tmp_path, toy):
    loaded = _toy(tmp_path)
    kept: list = []
    run_solve(toy, loaded, workers=1, auto=AutoStarts(min_converged=20), record=kept.append)
    settings, print_ = startlog.fingerprint("toy", "toy", "0" * 64, 16, 0, {"min_converged": 20})
    log = startlog.StartLog(tmp_path / startlog.FILENAME, settings, print_)
    log.batch(16)
    for out in kept[:16]:
        log.append(out)
    log.batch(32)
    for out in kept[16:19]:
        log.append(out)
    log.close()
    [(total, previous)] = startlog.read_resumed(tmp_path, print_).previous
    assert total == 16 and sorted(previous) == list(range(16))
    assert all(previous[i].objective == kept[i].objective for i in range(16))
    assert sorted(startlog.read(tmp_path, print_)) == sorted(out.start for out in kept[16:19])
    assert startlog.read_resumed(tmp_path, print_).last_batch == (32, False)


def test_starts_auto_in_a_spec_is_read_in_any_case_as_the_option_is_and_another_word_is_named(tmp_path):
    from synthesis.errors import SpecError

    text = (LIBRARY / "planting_arm" / "redesign_from_example1.toml").read_text()
    assert "\nstarts = 16" in text
    for word, auto in (('"AUTO"', True), ('" Auto"', True)):
        path = tmp_path / "spec.toml"
        path.write_text(text.replace("\nstarts = 16", f"\nstarts = {word}"))
        assert load_spec(path).model.solver.starts_auto is auto
    path.write_text(text.replace("\nstarts = 16", '\nstarts = "all"'))
    with pytest.raises(SpecError, match=r'planting_fourbar\.solver: starts: expected a whole number 1\.\.10000 or '
                                        r'"auto", got "all"'):
        load_spec(path)


def test_an_interrupt_while_the_finished_batches_are_counted_again_keeps_nothing(tmp_path, toy):
    """A resumed auto run (batch 64 begun, none of its starts finished) counts batches 16 and 32 again; a signal as
    batch 32's count begins kept batch 16 alone and wrote it over the run resumed, which held both: now nothing is
    kept until every finished batch is counted again (the run resumed stays as it was)."""
    import signal

    from synthesis.core import interrupt
    from synthesis.core import solve as core
    from synthesis.core.interrupt import Interrupted

    loaded = _toy(tmp_path)
    auto = AutoStarts(min_converged=10**6, max_starts=128)          # never stopped by the rule
    kept: list = []
    run_solve(toy, loaded, workers=1, auto=auto, record=kept.append)
    b16 = {o.start: o for o in kept[:16]}
    b32 = {o.start: o for o in kept[16:48]}
    batches: list = []

    def on_batch(total, nested):
        batches.append(total)
        if total == 32:
            interrupt.simulate(signal.SIGINT)
            raise KeyboardInterrupt
    try:
        with pytest.raises(Interrupted) as caught:
            core.run_auto(toy, Setting(loaded.model, 0, toy.solving().prepare(loaded.model)), auto, workers=1,
                          finished={}, resumed_batch=64, previous=[(16, b16), (32, b32)], on_batch=on_batch)
    finally:
        interrupt.uninstall()
    assert batches == [16, 32] and caught.value.partial is None


def test_a_batch_solved_again_locally_tells_and_logs_its_carried_starts_once(tmp_path, toy, monkeypatch):
    """A later batch whose cluster cannot be reached is solved locally; its carried start 0 had been told and logged
    before the cluster was reached, and was told and logged again (57 of 56 starts, start 0 twice in starts.jsonl)."""
    from synthesis.core import cluster
    from synthesis.core.executor import ClusterUnreachable

    loaded = _toy(tmp_path)
    calls: list = []

    def fake_cluster(factory, starts, scheduler, on_done, indices=None, failure=None):
        calls.append(len(indices))
        if len(calls) >= 2:                         # the cluster is gone for the second batch
            raise ClusterUnreachable(f"--scheduler {scheduler}: cannot reach a dask scheduler there (refused)")
        solver = factory()
        outs = []
        for i, x0 in zip(indices, starts):
            out = solver.solve(i, x0)
            on_done(out)
            outs.append(out)
        return outs

    monkeypatch.setattr(cluster, "run_starts_on_cluster", fake_cluster)
    recorded, told, notes = [], [], []
    auto = AutoStarts(max_starts=32, first=8, min_converged=10**6)
    run_solve(toy, loaded, None, 0, 1, lambda rep, best: told.append(rep.outcome.start), "tcp://127.0.0.1:1",
              record=recorded.append, auto=auto, on_batch=lambda t, n: recorded.append(("batch", t)),
              on_note=notes.append)
    assert len(notes) == 1 and "could not be reached for the batch of 16 starts (cannot reach a dask" in notes[0]
    batches: dict = {}
    for item in recorded:
        if isinstance(item, tuple):
            batch = batches.setdefault(item[1], [])
        else:
            batch.append(item.start)
    assert {b: sorted(s) for b, s in batches.items()} == {b: list(range(b)) for b in (8, 16, 32)}
    assert len(told) == 8 + 16 + 32
