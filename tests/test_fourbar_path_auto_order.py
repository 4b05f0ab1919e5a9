"""``--starts auto`` in a kind's own start order (synthesis/core/solve.py AutoStarts, Solving.auto_order) and
fourbar_path's auto order (synthesis/kinds/fourbar_path/starts.py auto_role): batches that grow by appending, the
same answer for any worker count, a resumed run's answer the uninterrupted one."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from conftest import LIBRARY
from solving import interrupted_auto_run
from synthesis import kinds
from synthesis.core.solve import AutoStarts, rows_of_indices, run_solve
from synthesis.kinds import solving_kind_for
from synthesis.kinds.fourbar_path.inexact import inexact_spec
from synthesis.kinds.fourbar_path.starts import AUTO_SCREENED, StartMaker, auto_role, takes_auto_order
from synthesis.spec import load_spec

TOY = """kind = "toy_disc"
name = "toy"
x = { init = 0.0, bounds = [-20.0, 20.0] }
y = { init = 1.0, bounds = [-20.0, 20.0] }
radius = 10.0
y_min = -5.0
target = [30.0, 40.0]
[solver]
starts = 20
"""


@pytest.fixture
def nested_toy():
    """The toy kind (one optimum) with an auto order of its own: its starts are the core's rows by index."""
    import toy_kind

    kinds.register(toy_kind.KIND)
    yield toy_kind.KIND.solving_with(dataclasses.replace(toy_kind.KIND.solving(), auto_order=lambda setting: True))
    kinds.unregister("toy_disc")


def _toy(tmp_path):
    path = tmp_path / "toy.toml"
    path.write_text(TOY)
    return load_spec(path)


# ---------------------------------------------------------------------------- the core: nested batches

def test_rows_by_index_do_not_depend_on_the_run_size():
    """Row i is drawn for (seed, i) alone: the first 5 rows of 40 are the 5 rows of 5; row 0 is the given design;
    every row is within the bounds and a fixed variable stays at its bound; another seed draws other rows."""
    bounds = np.array([[-2.0, 3.0], [1.0, 1.0], [0.0, 10.0]])
    init = np.array([0.5, 1.0, 4.0])
    forty, five = rows_of_indices(bounds, init, 40, 7), rows_of_indices(bounds, init, 5, 7)
    assert np.array_equal(forty[:5], five) and np.array_equal(forty[0], init)
    assert np.all(forty[1:, 1] == 1.0)
    assert np.all(forty >= bounds[:, 0]) and np.all(forty <= bounds[:, 1])
    assert len({tuple(r) for r in forty}) == 40
    assert not np.array_equal(rows_of_indices(bounds, init, 5, 8)[1:], five[1:])
    # 39 uniform draws per variable: their mean is within 4 standard errors of the box's middle
    for j in (0, 2):
        lo, hi = bounds[j]
        assert abs(forty[1:, j].mean() - 0.5 * (lo + hi)) < 4 * (hi - lo) / np.sqrt(12 * 39)


def test_a_nested_auto_run_solves_each_start_once_and_gives_the_same_answer_on_one_and_two_workers(tmp_path,
                                                                                                   nested_toy):
    """The toy's batches 16 and 32 (min_converged 20): 32 starts solved in all (the first batch's 16 carried, not
    solved again: the second batch replays the very same outcomes), against 48 for the fixed order; one and two
    workers give the same answer, count and statement; result.json says the order was the kind's."""
    loaded = _toy(tmp_path)
    runs = {}
    for workers in (1, 2):
        kept = []
        result, reports, _ = run_solve(nested_toy, loaded, workers=workers, auto=AutoStarts(min_converged=20),
                                       record=kept.append)
        runs[workers] = result
        assert result.solver["auto"]["batches"] == [16, 32] and result.solver["auto"]["order"] == "kind"
        assert len({id(out) for out in kept}) == 32 and [r.outcome.start for r in reports] == list(range(32))
    one, two = runs[1], runs[2]
    assert one.solver["auto"] == two.solver["auto"] and one.solver["starts"] == two.solver["starts"] == 32
    assert one.objective["value"] == two.objective["value"] and one.design == two.design
    assert one.solver["confidence"] == two.solver["confidence"]
    assert [s["design"] for s in one.starts] == [s["design"] for s in two.starts]


def test_a_nested_auto_run_resumed_inside_its_second_batch_gives_the_uninterrupted_answer(tmp_path, nested_toy):
    """A nested run's starts.jsonl, cut 7 starts into batch 32 (header, mark 16, starts 0-15, mark 32, 7 starts):
    startlog keeps all 23 (start i is the same in every batch) and names the batch, nested; resumed from them, the
    run solves the other 9 only and gives the uninterrupted answer."""
    from synthesis.core import startlog

    loaded = _toy(tmp_path)
    auto = AutoStarts(min_converged=20)
    settings, print_ = startlog.fingerprint("toy_disc", loaded.name, loaded.sha256, auto.max_starts, 0,
                                            auto.settings())
    log = startlog.StartLog(tmp_path / startlog.FILENAME, settings, print_)
    whole, _, _ = run_solve(nested_toy, loaded, workers=1, auto=auto, record=log.append, on_batch=log.batch)
    log.close()
    lines = (tmp_path / startlog.FILENAME).read_text().splitlines()
    assert len(lines) == 1 + 1 + 16 + 1 + 16          # each start written once, after its own batch's mark
    (tmp_path / startlog.FILENAME).write_text("\n".join(lines[:1 + 1 + 16 + 1 + 7]) + "\n")
    cut = startlog.read(tmp_path, print_)
    assert sorted(cut) == list(range(23)) and startlog.read_resumed(tmp_path, print_).last_batch == (32, True)
    solved = []
    resumed, _, _ = run_solve(nested_toy, loaded, workers=1, auto=auto, finished=cut, resumed_batch=32,
                              resumed_nested=True, record=solved.append)
    fresh = {id(out) for out in cut.values()}      # the resumed ones are recorded again (the new run's log)
    assert sorted(out.start for out in solved if id(out) not in fresh) == list(range(23, 32))
    assert resumed.solver["auto"] == whole.solver["auto"] and resumed.solver["confidence"] == whole.solver["confidence"]
    assert resumed.objective["value"] == whole.objective["value"] and resumed.design == whole.design


def test_a_nested_run_tells_and_rechecks_each_start_once(tmp_path, nested_toy, monkeypatch):
    """Batches 16 and 32: the progress hears of each of the 32 starts once, and the fine-grid re-check runs once
    per start (the second batch counts the first one's reports as they were)."""
    from synthesis.core import solve as core

    loaded = _toy(tmp_path)
    rechecked: list[int] = []
    real = core._recheck
    monkeypatch.setattr(core, "_recheck", lambda solving, setting, out: rechecked.append(out.start) or
                        real(solving, setting, out))
    told: list[int] = []
    result, _, _ = run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(min_converged=20),
                             on_start=lambda report, best: told.append(report.outcome.start))
    assert result.solver["auto"]["batches"] == [16, 32]
    assert sorted(told) == list(range(32)) and sorted(rechecked) == list(range(32))


def test_a_run_interrupted_in_the_other_order_is_not_resumed(tmp_path, nested_toy):
    """An auto run's batch mark says whether its starts were in the kind's order: resuming one in the other order
    (the code's order changed since) is refused, naming both, not silently mixed."""
    from synthesis.errors import OutputError

    loaded = _toy(tmp_path)
    with pytest.raises(OutputError, match="numbered its starts in the fixed order, this version of agrisynth "
                                          "numbers them in the kind's own order"):
        run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(), finished={}, resumed_batch=32,
                  resumed_nested=False)


def test_ctrl_c_between_two_nested_batches_keeps_every_finished_start(tmp_path, nested_toy):
    """A signal as batch 32 begins (before any of its starts): the run stops Interrupted with the first batch's 16
    reports and their best, status interrupted."""
    loaded = _toy(tmp_path)
    first, _, _ = run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(max_starts=16))
    caught, _ = interrupted_auto_run(nested_toy, loaded)
    kept, reports, _ = caught.partial
    assert kept.status == "interrupted" and [r.outcome.start for r in reports] == list(range(16))
    assert kept.solver["auto"] == {**AutoStarts(min_converged=20).settings(), "stopped_by": "interrupted",
                                   "batches": [16, 32], "order": "kind"}
    assert kept.design == first.design and kept.objective["value"] == first.objective["value"]


def test_ctrl_c_inside_a_nested_batch_keeps_the_earlier_batches_and_its_own_finished_starts(tmp_path, nested_toy):
    """A signal 3 starts into nested batch 32: the kept result holds starts 0-18 (the first batch's 16, told once,
    and the 3 new ones), not only the last finished batch's 16."""
    caught, told = interrupted_auto_run(nested_toy, _toy(tmp_path), after_told=16 + 3)
    kept, reports, _ = caught.partial
    assert sorted(told) == list(range(19)) and [r.outcome.start for r in reports] == list(range(19))
    assert kept.solver["starts"] == 32 and kept.solver["auto"]["stopped_by"] == "interrupted"


# ---------------------------------------------------------------------------- fourbar_path's auto order

def test_the_auto_order_is_the_given_design_then_the_screened_shapes_then_blocks_of_four():
    """auto_role maps the auto order one to one onto the fixed order's indices: 0 itself; 1..15 the screened
    shapes of rank 1..15 (fixed 3, 7, ..., 59); then each block of four one screened shape (next rank), one pool
    start (next rank) and two hypercube starts (the next two, so their crank directions alternate cw, ccw as the
    fixed order's 2, 4, ...).  The first 512 are 512 distinct fixed indices."""
    roles = [auto_role(i) for i in range(512)]
    assert len(set(roles)) == 512 and roles[0] == 0
    assert roles[1:AUTO_SCREENED + 1] == [4 * r - 1 for r in range(1, AUTO_SCREENED + 1)]
    rest = roles[AUTO_SCREENED + 1:]
    screened = [j for j in rest if j % 4 == 3]
    pool = [j for j in rest if j % 4 == 1]
    hypercube = [j for j in rest if j % 2 == 0]
    assert screened == [4 * r - 1 for r in range(AUTO_SCREENED + 1, AUTO_SCREENED + 1 + len(screened))]
    assert pool == [4 * q + 1 for q in range(len(pool))] and hypercube == [2 * (h + 1) for h in range(len(hypercube))]
    assert len(screened) == len(pool) == len(hypercube) // 2 == (512 - AUTO_SCREENED - 1) // 4
    for block in range(len(rest) // 4):
        screened_one, hyper_one, pool_one, hyper_two = rest[4 * block:4 * block + 4]
        assert (screened_one % 4, pool_one % 4, hyper_one % 2, hyper_two % 2) == (3, 1, 0, 0)
        assert hyper_two == hyper_one + 2


def test_only_the_screened_sets_take_the_auto_order():
    """The inexact set (free timing, 12-25 targets) takes it; the library's picking arc (10 targets: no screen)
    keeps the fixed order, and a StartMaker asked for the auto order there builds the fixed order's starts."""
    assert takes_auto_order(inexact_spec("egg16").model)
    arc = load_spec(LIBRARY / "fourbar_path" / "picking_arc.toml").model
    assert not takes_auto_order(arc) and not StartMaker(arc, 0, auto_order=True).auto_order


@pytest.mark.slow
def test_an_auto_order_start_is_the_fixed_orders_start_of_its_role():
    """Start i of the auto order is fixed start auto_role(i) (the screened and pool starts, which ignore the row, to
    the bit; a hypercube start from the same row also to the bit, its continuation flag set)."""
    spec = inexact_spec("s_curve12").model
    fixed, auto = StartMaker(spec, 0), StartMaker(spec, 0, auto_order=True)
    rng = np.random.default_rng(3)
    lo, hi = fixed.bounds[:, 0], fixed.bounds[:, 1]
    for i in (1, 2, 15, 16, 17, 18, 19):
        x = lo + rng.random(len(lo)) * (hi - lo)
        a, f = auto(i, x), fixed(auto_role(i), x)
        assert np.array_equal(a.design, f.design) and np.array_equal(a.theta, f.theta) and a.sign == f.sign
        assert a.timing_first == f.timing_first == (auto_role(i) % 2 == 0)


@pytest.mark.slow         # about 10 s: two auto runs of 32 starts of an inexact problem
def test_an_inexact_auto_run_is_the_same_on_one_and_two_workers_and_its_prefix_is_the_smaller_budgets_run():
    """egg16, seed 0, max_starts 32: one and two workers give the same answer and starts; the run with max_starts
    16 is the first batch of it to the bit (the auto order's start i does not depend on the budget)."""
    loaded = inexact_spec("egg16", {"seed": 0})
    kind = solving_kind_for(loaded)
    one, _, _ = run_solve(kind, loaded, workers=1, auto=AutoStarts(max_starts=32))
    two, _, _ = run_solve(kind, loaded, workers=2, auto=AutoStarts(max_starts=32))
    assert one.solver["auto"]["order"] == "kind" and one.solver["starts"] == two.solver["starts"]
    assert one.objective["value"] == two.objective["value"] and one.design == two.design
    assert [s["objective"] for s in one.starts] == [s["objective"] for s in two.starts]
    small, _, _ = run_solve(kind, loaded, workers=1, auto=AutoStarts(max_starts=16))
    assert [s["objective"] for s in small.starts] == [s["objective"] for s in one.starts[:16]]
    assert [s["design"] for s in small.starts] == [s["design"] for s in one.starts[:16]]


@pytest.mark.parametrize("nested", [True, False])
def test_the_time_limit_projects_the_next_batch_by_the_starts_it_would_solve(tmp_path, nested_toy, monkeypatch,
                                                                            nested):
    """A clock that moves 1 s per start solved (a replayed start costs nothing), a 40 s limit.  After the first
    batch (16 s) a nested run's next batch solves 16 new starts: projected to end at 32 s, it is begun (the toy
    then stops by the rule at 32); the fixed order's next batch solves all 32: projected at 48 s, not begun."""
    import types

    import synthesis.core.solve as core_solve

    clock, seen = [0.0], set()

    def tick(report, best):
        if report.outcome.start not in seen or not nested:
            clock[0] += 1.0
        seen.add(report.outcome.start)

    monkeypatch.setattr(core_solve, "time", types.SimpleNamespace(perf_counter=lambda: clock[0]))
    kind = nested_toy if nested else nested_toy.base
    result, _, _ = run_solve(kind, _toy(tmp_path), workers=1, on_start=tick,
                             auto=AutoStarts(min_converged=20, time_limit_s=40.0))
    assert result.solver["auto"]["batches"] == ([16, 32] if nested else [16])
    assert result.solver["auto"]["stopped_by"] == ("rule" if nested else "time_limit")


def test_a_nested_run_is_not_stopped_by_the_rule_on_its_first_batch(tmp_path, nested_toy):
    """A kind's own first batch is its picks (fourbar_path: the best screened shapes), not starts drawn over the box
    as the stopping rule assumes: the toy's one optimum meets the rule at 16 starts, yet a nested run goes on to the
    next batch and stops there; the same toy in the core's order stops at 16."""
    loaded = _toy(tmp_path)
    batches: list[int] = []
    nested, _, _ = run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(),
                             on_batch=lambda total, is_nested: batches.append(total))
    assert batches == [16, 32]
    assert nested.solver["auto"]["stopped_by"] == "rule" and nested.solver["auto"]["order"] == "kind"
    import toy_kind
    plain, _, _ = run_solve(toy_kind.KIND, loaded, workers=1, auto=AutoStarts())
    assert plain.solver["auto"]["batches"] == [16] and plain.solver["auto"]["stopped_by"] == "rule"


def test_a_nested_batch_mark_keeps_the_earlier_batches_starts_on_resume(tmp_path, nested_toy):
    """Cut just after a nested batch's mark, before its carried starts were written again, starts.jsonl still holds
    them before the mark: startlog.read keeps them (start i is the same in every batch), where a mark of the core's
    order (its batches' starts another run's) drops them."""
    from synthesis.core import startlog

    loaded = _toy(tmp_path)
    kept: list = []
    run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(min_converged=20), record=kept.append)
    first_batch = kept[:16]
    assert sorted(out.start for out in first_batch) == list(range(16))
    for nested, expected in ((True, list(range(16))), (False, [])):
        folder = tmp_path / f"nested_{nested}"
        folder.mkdir()
        settings, print_ = startlog.fingerprint("toy_disc", loaded.name, loaded.sha256, 512, 0, AutoStarts().settings())
        log = startlog.StartLog(folder / startlog.FILENAME, settings, print_)
        log.batch(16, nested)
        for out in first_batch:
            log.append(out)
        log.batch(32, nested)                  # cut here: none of the carried starts written again yet
        log.close()
        assert sorted(startlog.read(folder, print_)) == expected


# ---------------------------------------------------------------------------- the core's auto batches, edge cases

def test_a_failed_start_of_a_nested_batch_is_carried_not_solved_again(tmp_path, nested_toy, monkeypatch):
    """Start 3 raises in batch 16: it stays that start's failure in batch 32 (recorded and told once, 32 records
    in all), so each start is solved once whatever the budget."""
    from synthesis.core import solve as core

    loaded = _toy(tmp_path)
    real = core.run_starts

    class Raising:
        def __init__(self, inner):
            self.inner = inner

        def solve(self, i, x):
            if i == 3:
                raise RuntimeError("boom in start 3")
            return self.inner.solve(i, x)

        def __getattr__(self, name):
            return getattr(self.inner, name)

    monkeypatch.setattr(core, "run_starts", lambda factory, *a, **k: real(lambda: Raising(factory()), *a, **k))
    recorded: list = []
    told: list[int] = []
    result, reports, _ = run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(min_converged=20),
                                   record=recorded.append,
                                   on_start=lambda report, best: told.append(report.outcome.start))
    assert result.solver["auto"]["batches"] == [16, 32]
    assert sorted(out.start for out in recorded) == list(range(32)) and sorted(told) == list(range(32))
    assert reports[3].outcome.return_status.startswith("Start_Raised")


def test_a_signal_while_a_resumed_run_counts_its_finished_starts_keeps_nothing_new(tmp_path, nested_toy):
    """Resumed from 23 finished starts, a signal after the 5th is counted again: the run stops at once and keeps
    nothing (partial None), so the interrupted run it resumed is not replaced by one with 5 starts (the CLI then
    names that run's folder, still holding its 23)."""
    import signal

    from synthesis.core import interrupt
    from synthesis.core.interrupt import Interrupted

    loaded = _toy(tmp_path)
    recorded: list = []
    run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(max_starts=32, min_converged=100), record=recorded.append)
    finished = {out.start: out for out in recorded[:23]}
    told: list[int] = []

    def on_start(report, best):
        told.append(report.outcome.start)
        if len(told) == 5:
            interrupt.simulate(signal.SIGINT)
    try:
        with pytest.raises(Interrupted) as caught:
            run_solve(nested_toy, loaded, workers=1, auto=AutoStarts(max_starts=32, min_converged=100),
                      finished=finished, resumed_batch=32, resumed_nested=True, on_start=on_start)
    finally:
        interrupt.uninstall()
    assert caught.value.partial is None and len(told) == 5


@pytest.mark.parametrize("nested", [False, True])
def test_the_kinds_early_stop_at_a_batchs_last_start_ends_the_auto_run(tmp_path, nested):
    """The kind's early stop met by start 15, the first batch's last: the run stops there (stop_at_objective)
    with 16 starts solved, not a second batch."""
    import toy_kind

    kinds.register(toy_kind.KIND)
    try:
        solving = dataclasses.replace(toy_kind.KIND.solving(),
                                      stop_when=lambda setting: (lambda report: report.outcome.start == 15),
                                      **({"auto_order": lambda setting: True} if nested else {}))
        kind = toy_kind.KIND.solving_with(solving)
        solved: list = []
        result, reports, _ = run_solve(kind, _toy(tmp_path), workers=1, auto=AutoStarts(min_converged=100),
                                       record=solved.append)
    finally:
        kinds.unregister("toy_disc")
    assert result.solver["auto"]["stopped_by"] == "stop_at_objective" and result.solver["auto"]["batches"] == [16]
    assert len(solved) == 16 and len(reports) == 16


def test_an_interrupted_batch_tying_the_finished_one_keeps_the_finished_batch_whole():
    """Core: the batch in progress reached the finished batch's optimum at a lower start index (1 against 5): a
    tie, so the finished batch's 16 starts are kept, not the 3 of the batch in progress; a strictly better
    partial best is kept."""
    from types import SimpleNamespace

    from synthesis.core.solve import Run, _kept_so_far
    from synthesis.core.verdict import StartReport

    def report(start, objective):
        return StartReport(SimpleNamespace(start=start, objective=objective, success=True,
                                           return_status="Solve_Succeeded"), True, 0.0)

    finished = [report(i, 2.0) for i in range(16)]
    finished[5] = report(5, 1.0)
    last = Run(finished, finished[5], 16, 0, 1, None, 1.0)
    for best_in_progress, kept_starts in ((1.0, 16), (0.5, 3)):
        progress = [report(0, 2.0), report(1, best_in_progress), report(2, 2.0)]
        partial = Run(progress, progress[1], 32, 0, 1, None, 0.5)
        kept = _kept_so_far(partial, last, False, 0.0, {}, nested=False)
        assert kept is not None and len(kept.reports) == kept_starts
