"""``agrisynth solve`` for every kind: fixed-seed multistart, fine-grid re-check, one verdict, one Result.

The kind declares its pieces (:class:`synthesis.core.kind.Solving`); this module runs them the same
way for all: the NLP is built once here (and once in each worker), start 0 is the spec's design and
the others a scrambled Latin hypercube over the free variables' bounds, every start is re-checked
independently of the solver, the best is chosen in start order, and when no start satisfies every
rule an elastic re-solve says whether the rules conflict.  The diagnosis is stored in the result
before it is written, so ``result.json`` says what the exit-3 message says.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, replace
from typing import Any, Callable, cast

import numpy as np

from synthesis.core import interrupt
from synthesis.core.compiled_code import compile_seconds
from synthesis.core.confidence import OBJECTIVE_TOLERANCE, statement
from synthesis.core.executor import ClusterUnreachable, failed_start, latin_hypercube_starts, run_starts, workers_inherit_memory
from synthesis.core.interrupt import Interrupted
from synthesis.core.ipopt_log import reached_optimum
from synthesis.core.kind import Kind, Setting, Solving
from synthesis.core.pinned import fixed_fields, of_nlp, refuse_violated
from synthesis.core.verdict import (FINE, SLACK_TOL, TIE, ElasticDiagnosis, StartReport, best_in_start_order, better,
                                    diagnosis_of, failure_of, measured, report_of, status_note, status_of,
                                    unsatisfied_error)
from synthesis.errors import AgrisynthError, OutputError, SolverError, SpecError
from synthesis.result import Result
from synthesis.spec.design_info import at_bound, describe


@dataclass
class Run:
    """A finished multistart: every start's report (in start order) and the best one."""

    reports: list[StartReport]
    best: StartReport
    starts: int
    seed: int
    workers: int | None
    scheduler: str | None
    wall_s: float
    #: the NLP the driver built in this process (reused by a start from the elastic re-solve's design)
    nlp: Any = None
    #: of ``wall_s``, building that NLP in this process (the workers' own builds are in the rest)
    build_s: float = 0.0
    #: ``--starts auto``: why it stopped and its batches (result.json ``solver.auto``); None for fixed starts
    auto: dict | None = None


def _solving(kind: Kind) -> Solving:
    """The kind's solve side: this module runs only kinds that solve (``Kind.solves``; the CLI refuses the others
    before a run begins), so a kind without one is a caller's error."""
    solving = kind.solving()
    if solving is None:
        raise TypeError(f"kind {kind.name} does not solve")
    return solving


def _recheck(solving: Solving, setting: Setting, outcome):
    return solving.recheck(setting, outcome)


def free_variables(nlp) -> list[str]:
    """Names of the design variables whose bounds leave room to move."""
    return [n for n, (lo, hi) in zip(nlp.names, nlp.bounds) if hi > lo]


def _written_at(spec, name: str) -> str:
    """Where the spec file writes design variable ``name`` (``[links] l7``, ``[spline] control[0][0]``), else its
    name."""
    path = (describe(spec).get(name) or {}).get("path")
    if not path:
        return name
    table, _, key = path.partition(".")
    return f"[{table}] {key}" if key else path


def run_multistart(kind: Kind, setting: Setting, *, starts: int, workers: int, scheduler: str | None = None,
                   on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
                   record: Callable[[Any], None] | None = None, finished: dict[int, Any] | None = None,
                   rows_by_index: bool = False, carried: dict[int, StartReport] | None = None,
                   on_note: Callable[[str], None] = lambda text: None) -> Run:
    """The multistart of every kind.  ``record(outcome)`` sees each finished start first (the run's
    ``starts.jsonl``); ``finished``: starts already solved by an interrupted run (not solved again);
    ``rows_by_index``: each start's decision-variable row drawn for its index alone (:func:`rows_of_indices`,
    a kind's auto order) instead of a Latin hypercube of ``starts`` points; ``carried``: the reports of starts
    an earlier batch of a nested auto run finished (neither solved, recorded, re-checked nor told to ``on_start``
    again: they count as they were); ``on_note``: told in one line when a cluster stopped serving the run and its
    other starts were solved on local workers (:func:`~synthesis.core.executor.run_starts`).

    A SIGINT/SIGTERM (:mod:`synthesis.core.interrupt`) raises :class:`Interrupted` whose ``partial`` is
    the :class:`Run` of the starts finished so far (None when none has)."""
    solving = _solving(kind)
    # the wall time includes building the NLP, here and in each worker alike: it compares across worker counts
    t0 = time.perf_counter()
    nlp = solving.build(setting, False)           # built once here; also validates before any worker starts
    build_s = time.perf_counter() - t0
    if not free_variables(nlp):
        raise SpecError(f"{kind.name}: solve needs at least one free design variable (give one bounds, e.g. "
                        f"{_written_at(setting.spec, nlp.names[0])} = {{init = ..., bounds = [lo, hi]}}); every one "
                        f"is fixed, so use `agrisynth check`")
    refuse_violated(kind, setting.spec, nlp)     # a violated rule no design variable moves: exit 2 before any start
    x_starts = (rows_of_indices if rows_by_index else latin_hypercube_starts)(
        np.asarray(nlp.bounds, float), np.asarray(nlp.init, float), starts, setting.seed)
    maximise = solving.maximise(setting)
    recheck = functools.partial(_recheck, solving, setting)
    stop = solving.stop_when(setting)
    earlier = dict(carried or {})
    # an earlier batch's reports count as they were, all at once (one dict copy: no signal can fall in between)
    reports: dict[int, StartReport] = dict(earlier)
    best: list[StartReport] = [best_in_start_order([earlier[i] for i in sorted(earlier)], maximise)] if earlier else []

    def done(outcome) -> None:
        if outcome.start in earlier:     # counted above
            return
        with interrupt.deferred():       # a start is kept whole or not at all
            if record is not None:
                record(outcome)
            rep = report_of(outcome, recheck)
            reports[outcome.start] = rep
            if not best or better(rep, best[0], maximise):
                best[:] = [rep]
            on_start(rep, best[0])

    def failed(index: int, status: str, reason: str):
        """A start that raised or whose worker died: its starting point as its design (starts table)."""
        out = failed_start(index, status, reason)
        out.design = {n: float(v) for n, v in zip(nlp.names, x_starts[index])}
        return out

    # a worker forked from here starts with the NLP built above (building it is a tenth of a planting multistart);
    # a dask worker, or a spawned one, builds its own from the picklable recipe
    shared = scheduler is None and (workers <= 1 or workers_inherit_memory())
    factory = (lambda: nlp) if shared else functools.partial(solving.build, setting, False)
    try:
        outcomes = run_starts(factory, x_starts, workers, done, scheduler=scheduler,
                              finished={**(finished or {}), **{i: r.outcome for i, r in earlier.items()}},
                              stop_when=None if stop is None else (lambda out: stop(reports[out.start])),
                              failure=failed, on_note=on_note)
    except (KeyboardInterrupt, SystemError) as exc:
        if not interrupt.caused_by_signal(exc):
            raise
        wall = time.perf_counter() - t0
        kept = [reports[i] for i in sorted(reports)]
        best_kept = best_in_start_order(kept, maximise) if kept else None
        # stopped while a resumed run's finished starts were being counted again: keeping fewer than it had would
        # replace the interrupted run with less, so nothing is kept (the interrupted run stays as it was)
        recounted = all(i in reports for i in (finished or {}) if i < starts)
        partial = (Run(kept, best_kept, starts, setting.seed, None if scheduler else workers, scheduler, wall,
                       nlp, build_s)
                   if recounted and best_kept is not None and failure_of(best_kept.outcome) is None else None)
        raise Interrupted(interrupt.signal_of(exc), partial) from None
    wall = time.perf_counter() - t0
    ordered = [reports[o.start] for o in outcomes]       # the starts that count (an early stop: 0..k)
    winner = best_in_start_order(ordered, maximise)
    if failure_of(winner.outcome) is not None:           # ranked last: every start failed to run
        raise SolverError(f"{kind.name}: no start could be solved: {_failures(ordered)}")
    return Run(ordered, winner, starts, setting.seed, None if scheduler else workers, scheduler, wall, nlp, build_s)


#: the random stream of :func:`rows_of_indices` (apart from the streams a kind draws from the seed itself)
ROWS_STREAM = 0x6175746F


def rows_of_indices(bounds: np.ndarray, init: np.ndarray, n: int, seed: int) -> np.ndarray:
    """(n, d) start points: row 0 = init, row i >= 1 uniform in [lo, hi] (fixed dims = lo) from a generator seeded
    by (seed, i) alone, so row i is the same for any n (a kind's auto order: batches that grow by appending)."""
    lo, hi = bounds[:, 0], bounds[:, 1]
    rows = np.tile(init, (n, 1)).astype(float)
    for i in range(1, n):
        rows[i] = lo + np.random.default_rng([seed, ROWS_STREAM, i]).random(len(lo)) * (hi - lo)
    return rows


@dataclass(frozen=True)
class AutoStarts:
    """``--starts auto``: the multistart grows in batches until Boender and Rinnooy Kan's stopping rule holds
    (:mod:`synthesis.core.confidence`, fewer than half an optimum expected unseen) over at least ``min_converged``
    starts that converged with every rule held, or a budget is spent.

    Batch k is the whole fixed-starts run of ``first * 2**k`` starts (the last one ``max_starts``): a Latin hypercube
    of N points is not the first N of a larger one, so each batch draws its own, exactly those of ``--starts N``, and
    a run that stops after N starts is ``--starts N`` to the bit.  Only start 0 (the spec's design, the same in every
    batch) is carried from batch to batch; the starts solved in all are at most about twice the last batch's.  The
    decision is taken on whole batches, so the answer and N are the same for any worker count or a cluster -- except
    with ``time_limit_s``: a batch whose projected time (the last batch's, scaled by its size) would end past the
    limit is not begun, and the count then depends on the machine.

    A kind whose :attr:`~synthesis.core.kind.Solving.auto_order` holds for the spec numbers an auto run's starts in
    an order of its own (e.g. its screened starts first) in which start i is the same in every batch: its rows
    are drawn per index (:func:`rows_of_indices`), every finished start is carried to the next batch and only the new
    ones are solved (at most ``max_starts`` starts in all).  Such a run that stops after N starts is not
    ``--starts N`` (another order, other rows) but ``--starts auto --max-starts N`` to the bit, whatever the
    budget it was given: its first N starts do not depend on the batches after them."""

    max_starts: int = 512
    time_limit_s: float | None = None
    min_converged: int = 16
    first: int = 16

    def batches(self) -> list[int]:
        """The total starts of each batch: first, 2 first, 4 first, ..., max_starts."""
        totals = [min(self.first, self.max_starts)]
        while totals[-1] < self.max_starts:
            totals.append(min(2 * totals[-1], self.max_starts))
        return totals

    def settings(self) -> dict:
        """What decides an auto run's starts (its starts.jsonl fingerprint, result.json ``solver.auto``)."""
        return {"max_starts": self.max_starts, "time_limit_s": self.time_limit_s, "min_converged": self.min_converged,
                "first": self.first}


def run_auto(kind: Kind, setting: Setting, auto: AutoStarts, *, workers: int, scheduler: str | None = None,
             on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
             record: Callable[[Any], None] | None = None, finished: dict[int, Any] | None = None,
             on_batch: Callable[[int, bool], None] = lambda total, nested: None,
             resumed_batch: int | None = None, resumed_nested: bool | None = None,
             previous: list[tuple[int, dict[int, Any]]] | None = None,
             on_note: Callable[[str], None] = lambda text: None) -> Run:
    """The batches of :class:`AutoStarts`, each a :func:`run_multistart` of its total; the last one's Run, its
    ``wall_s`` the whole time and its ``auto`` why it stopped.  ``on_batch(total, nested)`` is told as a batch
    begins (the run's starts.jsonl marks it, nested when the kind orders the starts); ``resumed_batch``/``finished``:
    an interrupted auto run's batch and its finished starts (the earlier batches ended without stopping, so the run
    goes on from that one); ``resumed_nested``: whether that batch was marked nested (a run interrupted in the other
    order is refused: its starts are not this order's); ``previous``: the interrupted run's finished batches
    before that one, in order (each one's total and starts: :attr:`~synthesis.core.startlog.Resumed.previous`),
    counted again without solving and logged, so the resumed run knows them as the interrupted run did.

    The batches are not nested unless the kind orders the starts: each is a fixed run of its own, and the answer is
    the last batch's -- unless an earlier batch found a better design (:func:`~synthesis.core.verdict.better`, not a
    tie), whose batch is then the answer (``auto.answer_batch`` its total), and the rule may not stop the run on a
    batch whose best it beats: the batch's own statement would call a worse optimum the global one.

    Interrupted (SIGINT/SIGTERM) anywhere, inside a batch or between two: raises :class:`Interrupted` whose
    ``partial`` is the better of the batch in progress (its finished starts; a nested one's include the earlier
    batches') and the last batch that finished, or None when neither has a start to keep."""
    solving = _solving(kind)
    maximise = solving.maximise(setting)
    nested = solving.auto_order(setting)
    if resumed_batch is not None and resumed_nested is not None:
        refuse_other_order(kind, resumed_nested, nested)
    if nested:
        setting = replace(setting, auto_order=True)
    stop = solving.stop_when(setting)
    totals = auto.batches()
    first = totals.index(resumed_batch) if resumed_batch in totals else 0
    # a nested run's interrupted batch: every start it had finished (the log keeps the earlier batches' starts too)
    resumed = dict(finished or {}) if resumed_batch in totals else {}
    carried: dict[int, StartReport] = {}     # nested: the reports of the batches before, counted as they were
    t0 = time.perf_counter()
    last: Run | None = None
    replayed: Run | None = None               # the batch the interrupted run finished before this one, counted again
    # the batch in progress holds starts the interrupted run finished that are not yet counted (and logged) again: a
    # signal before they are keeps nothing, so the run resumed is never replaced by one with fewer starts
    pending = set(i for i in resumed if i < totals[first])
    in_batch = False                          # inside a batch's run_multistart (not the replay)
    k = first
    lost: list[str] = []                      # what a cluster that stopped serving the run said
    best: Run | None = None                   # not nested: the finished batch with the best answer (the later on a tie)

    def finished_batch(run: Run) -> None:
        nonlocal best
        if best is None or not better(best.best, run.best, maximise, by_index=False):
            best = run

    def noted(text: str) -> None:
        lost.append(text)
        on_note(text)

    def counting(report: StartReport, best: StartReport) -> None:
        """``on_start``, and the resumed batch's starts crossed off as they are counted (and logged) again."""
        pending.discard(report.outcome.start)
        on_start(report, best)

    def interrupted() -> dict:
        """The kept result's ``solver.auto``: stopped by the signal, the batches begun."""
        return {"stopped_by": "interrupted", "batches": totals[:k + 1], **auto.settings(),
                **({"order": "kind"} if nested else {})}
    # the interrupted run's finished batches being counted again: a signal before they all are keeps nothing (a kept
    # result of fewer batches would replace the run resumed, which had them all)
    replaying = False
    on_cluster = False                        # a batch has run on the cluster (a later one that cannot reach it: lost)
    try:
        if previous and not nested and first > 0 and [t for t, _ in previous] == totals[:first]:
            replaying = True
            for total, starts_of in previous:
                on_batch(total, nested)
                replayed = run_multistart(kind, setting, starts=total, workers=workers,
                                          scheduler=None if lost else scheduler, record=record, finished=starts_of,
                                          on_note=noted)
                finished_batch(replayed)
            replaying = False
        for k in range(first, len(totals)):
            on_batch(totals[k], nested)
            began, compiled_before = time.perf_counter(), compile_seconds()
            in_batch = True
            # the starts the batch counts again (its resumed ones) are told and logged before the cluster is reached:
            # a batch solved again locally does not tell or log them twice
            told: set[int] = set()

            def first_told(report: StartReport, best: StartReport) -> None:
                told.add(report.outcome.start)
                counting(report, best)

            def first_logged(out) -> None:
                told.add(out.start)
                if record is not None:
                    record(out)
            try:
                run = run_multistart(kind, setting, starts=totals[k], workers=workers,
                                     scheduler=None if lost else scheduler, on_start=first_told,
                                     record=first_logged if record is not None else None, finished=resumed,
                                     rows_by_index=nested, carried=carried, on_note=noted)
            except ClusterUnreachable as exc:
                if not on_cluster or lost:      # the first batch: the address is the user's to fix (exit 2)
                    raise
                # the cluster served the batches before and cannot be reached now: lost between two batches
                why = str(exc).split(": ", 1)[-1]          # without its own "--scheduler ADDR: "
                noted(f"--scheduler {scheduler}: the cluster could not be reached for the batch of {totals[k]} "
                      f"starts ({why}); it and the later batches are solved here on {max(workers, 1)} local "
                      f"worker{'s' if workers > 1 else ''} (the same starts: the same answer)")
                run = run_multistart(kind, setting, starts=totals[k], workers=workers, scheduler=None,
                                     on_start=lambda report, best: None if report.outcome.start in told
                                     else counting(report, best),
                                     record=None if record is None else (lambda out: None if out.start in told
                                                                         else record(out)),
                                     finished=resumed, rows_by_index=nested, carried=carried, on_note=noted)
            on_cluster = scheduler is not None and not lost
            in_batch = False
            pending.clear()
            last = run
            # a first compile of the NLP's functions (solve --compiled) is no cost of the next batch's starts
            took = time.perf_counter() - began - (compile_seconds() - compiled_before)
            # the starts this batch solved, and the next one would: all of them, or (nested) the new ones only
            solved_now = totals[k] - len(carried) - len(resumed)
            # an earlier batch's better design: this batch's statement is not about the global optimum
            earlier = best if best is not None and better(best.best, run.best, maximise, by_index=False) else None
            stopped_by = _auto_stop(run, auto, totals, k, nested, maximise, stop, earlier is not None,
                                    best is not None and best.best.satisfied)
            if (stopped_by is None and auto.time_limit_s is not None
                    and time.perf_counter() - t0 + took * (totals[k + 1] - totals[k] if nested else totals[k + 1])
                    / max(solved_now, 1) > auto.time_limit_s):
                stopped_by = "time_limit"
            if stopped_by is not None:
                answer = earlier or run
                return replace(answer, wall_s=time.perf_counter() - t0,
                               auto={"stopped_by": stopped_by, "batches": totals[:k + 1], **auto.settings(),
                                     **({"order": "kind"} if nested else {}),
                                     **({"answer_batch": answer.starts} if earlier is not None else {})})
            if not nested:
                finished_batch(run)
            if nested:      # the next batch appends to this one: every start is kept (a failed one too: each
                carried = {r.outcome.start: r for r in run.reports}      # start is solved once, whatever the budget)
                resumed = {}
            else:
                zero = run.reports[0].outcome
                resumed = {0: zero} if zero.start == 0 and failure_of(zero) is None else {}
    except Interrupted as exc:
        # a batch's partial holds its recounted starts (None before they are all counted again); the replay's is
        # never kept on its own
        partial = exc.partial if in_batch else None
        if pending or replaying:
            raise Interrupted(exc.signum, None) from None
        raise Interrupted(exc.signum, _kept_so_far(partial, (last if nested else best) or replayed, maximise, t0,
                                                   interrupted(), nested)) from None
    except (Exception, KeyboardInterrupt) as exc:
        # between two batches, or building the next one's NLP: KeyboardInterrupt, or what a signal inside a CasADi
        # call comes out as (SystemError, NotImplementedError ...); any other error is the run's own
        if not isinstance(exc, KeyboardInterrupt) and interrupt.pending() is None:
            raise
        kept = None if pending or replaying else _kept_so_far(None, (last if nested else best) or replayed, maximise,
                                                              t0, interrupted(), nested)
        raise Interrupted(interrupt.signal_of(exc), kept) from None
    raise AssertionError("unreachable: the last batch stops by max_starts")


def takes_auto_order(kind: Kind, spec, seed: int) -> bool:
    """Whether ``--starts auto`` on ``spec`` numbers its starts in the kind's own order (nested batches)."""
    solving = _solving(kind)
    return bool(solving.auto_order(Setting(spec, seed, solving.prepare(spec))))


def refuse_other_order(kind: Kind, resumed_nested: bool, nested: bool) -> None:
    """OutputError (exit 2) when an interrupted auto run being resumed numbered its starts in the other order (this
    version of the kind orders them otherwise): its finished starts are not this run's."""
    if resumed_nested != nested:
        order = {True: "the kind's own order", False: "the fixed order"}
        raise OutputError(f"{kind.name}: the interrupted run numbered its starts in {order[resumed_nested]}, this "
                          f"version of agrisynth numbers them in {order[nested]}: its finished starts are not this "
                          f"run's; solve again without --resume")


def _auto_stop(run: Run, auto: AutoStarts, totals: list[int], k: int, nested: bool, maximise: bool,
               stop: Callable[[StartReport], bool] | None, beaten: bool = False,
               earlier_feasible: bool = False) -> str | None:
    """Why an auto run stops after batch ``k`` (not for its time limit, which the caller projects), or None.
    ``beaten``: an earlier batch found a better design than this batch's best (the rule then may not stop the run);
    ``earlier_feasible``: an earlier batch had a design meeting every rule."""
    stated = confidence_statement(run.reports, run.nlp, maximise, run.best)
    assert stated is not None, "run_multistart builds the NLP in this process, so the statement has it"
    if len(run.reports) < totals[k] or (stop is not None and any(stop(r) for r in run.reports)):
        return "stop_at_objective"         # the kind's own early stop ended the batch (at its last start, too)
    # an answer better than every counted optimum (a start that met every rule short of IPOPT's full tolerance) shows
    # the counted best is not the global optimum, whatever the rule estimates of it
    beyond = (not stated["answer_counted"] and run.best.satisfied
              and answer_beyond(run.best, [o["objective"] for o in stated["optima"]], maximise))
    if (stated["stopping_rule_met"] and stated["starts_counted"] >= auto.min_converged
            and not (nested and k == 0) and not beyond and not beaten):
        # a kind's own first batch is its picks (fourbar_path: the best screened shapes), correlated by
        # construction; the rule assumes starts drawn over the box, so it may stop a nested run only once a
        # later batch has brought such starts in
        return "rule"
    if not run.best.satisfied and not earlier_feasible and totals[k] >= auto.min_converged:
        # not one start met every rule: more starts of the same box rarely do (an infeasible spec ran 1008
        # starts to max_starts for nothing); the elastic diagnosis says why.  (Starts that met every rule short of
        # IPOPT's full tolerance are not counted by the statement, but more starts may well converge: the run goes on)
        return "none_converged"
    if k == len(totals) - 1:
        return "max_starts"
    return None


def _kept_so_far(partial: Run | None, last: Run | None, maximise: bool, t0: float, auto: dict,
                 nested: bool) -> Run | None:
    """What an interrupted auto run keeps: a nested run, the batch in progress (it holds every earlier start too)
    or else the last finished batch; otherwise whichever of the two has the better best (the finished batch on a
    tie: it has every one of its starts).  Its wall is the whole run's and ``auto`` (stopped by "interrupted", the
    batches begun) its result's ``solver.auto``; None when neither has a start to keep."""
    kept = [r for r in (last, partial) if r is not None]
    if not kept:
        return None
    if nested or len(kept) == 1:
        chosen = kept[-1]
    else:     # the batch in progress only if its best beats the finished batch's for more than its start index
        chosen = kept[1] if better(kept[1].best, kept[0].best, maximise, by_index=False) else kept[0]
    return replace(chosen, wall_s=time.perf_counter() - t0, auto=auto)


def _failures(reports: list[StartReport], shown: int = 3) -> str:
    """'start 0 Worker_Crashed: its worker ...; start 1 ...' for the first few, and how many more."""
    text = "; ".join(f"start {r.outcome.start} {r.outcome.return_status} ({r.why})" for r in reports[:shown])
    return text + (f"; and {len(reports) - shown} more" if len(reports) > shown else "")


#: elastic re-solves from different points (the relaxation has local minima too): at most this many points ...
ELASTIC_ATTEMPTS = 4
#: ... and no more once this many have converged (the smallest of them is kept)
ELASTIC_CONVERGED = 2


def elastic_points(solving: Solving, run: Run, nlp) -> list[np.ndarray]:
    """Where the elastic re-solve starts, in order: the best start's design, the other starts' designs least
    violated first and the given design last; or for a kind that relaxes from the given design, that one first
    (deterministic), each point once (starts that ended on one design are one point).  A relaxation started on a
    degenerate design can stop on an invalid number (a crank-rocker whose swing it shrank to nothing); from
    another point the same problem converges."""
    given = np.asarray(nlp.init, float)
    valid = [r for r in run.reports if r.why is None and failure_of(r.outcome) is None
             and math.isfinite(r.worst_violation)]
    ranked = sorted(valid, key=lambda r: (r.worst_violation, r.outcome.start))
    best = [nlp.x_of(run.best.outcome.design)] if any(r is run.best for r in valid) else []
    others = [nlp.x_of(r.outcome.design) for r in ranked if r is not run.best]
    candidates = [*best, *others, given] if solving.elastic_from == "best" else [given, *best, *others]
    points: list[np.ndarray] = []
    for x in candidates:
        if len(points) >= ELASTIC_ATTEMPTS:
            break
        if not any(np.allclose(x, p, rtol=1e-6, atol=1e-9) for p in points):
            points.append(x)
    return points


def relaxation(diagnosis: ElasticDiagnosis) -> float:
    """The elastic objective: the slacks in their rules' scales, summed."""
    return sum(s / diagnosis.scales[name] for name, s in diagnosis.slacks.items())


def elastic_diagnosis(kind: Kind, setting: Setting, run: Run) -> ElasticDiagnosis:
    """Re-solve with one slack per rule (minimise their sum) from the points of :func:`elastic_points` until
    ELASTIC_CONVERGED of them converge; the smallest of those relaxations is kept (each is a local minimum: a
    crank-rocker's transmission rule missed by 24.6 deg from one point, by 9.86 from another, the least any design
    misses it)."""
    solving = _solving(kind)
    nlp = solving.build(setting, True)
    first = kept = None
    converged = 0
    for x0 in elastic_points(solving, run, nlp):
        if interrupt.pending() is not None:
            break
        try:
            outcome = nlp.solve(0, x0)
        except (AgrisynthError, ValueError, ArithmeticError, RuntimeError) as exc:
            # a diagnosis that could not run proves nothing: the run is "failed", and says why
            first = first or (None, ElasticDiagnosis(f"not run: {exc}", False, {}, {}, {}))
            continue
        diagnosis = diagnosis_of(nlp.compiled, outcome.raw)
        first = first or (outcome, diagnosis)
        if diagnosis.converged:
            converged += 1
            if kept is None or relaxation(diagnosis) < relaxation(kept[1]):
                kept = (outcome, diagnosis)
            # no rule needs slack: the rules can be met together, nothing smaller to find
            if converged >= ELASTIC_CONVERGED or not diagnosis.relaxed:
                break
    # none converged: the first attempt's diagnosis is reported (what the kind's own choice of point gave)
    outcome, diagnosis = kept or first or (None, ElasticDiagnosis("not run: interrupted", False, {}, {}, {}))
    if outcome is None:
        return diagnosis
    design = {k: float(v) for k, v in (getattr(outcome, "design", None) or {}).items()
              if isinstance(v, (int, float)) and not isinstance(v, bool)}
    return replace(diagnosis, design=design or None,
                   between_samples=missed_between_samples(solving, setting, outcome, diagnosis.relaxed),
                   alone=alone_slacks(nlp.compiled, outcome.raw, diagnosis.relaxed, diagnosis.slacks),
                   at_bounds=at_bounds(nlp.design_names, nlp.bounds, design)
                   if diagnosis.relaxed else [],
                   fixed=fixed_fields(kind, of_nlp(kind, setting.spec, nlp), diagnosis.relaxed)
                   if diagnosis.relaxed else {})


def missed_between_samples(solving: Solving, setting: Setting, outcome, relaxed: list[str]) -> dict[str, dict]:
    """The rules the elastic design misses on the check's finer grid (the kind's re-check) that the relaxation does
    not give up on: rule -> {"miss", "unit"} in the check's own terms.  Held (ELASTIC_BACKOFF inside) at the NLP's
    samples, a sampled rule on its limit may miss between them (rotary_planetary's largest depth, 0.02 mm at 72
    samples a turn), and the diagnosis says so rather than a `check elastic.toml` failing a rule it said holds.  A
    rule is named by its base name (an envelope's ``rule@mu=0.6`` in the NLP is ``rule`` and ``rule@envelope`` in
    the check), so a rule given up on at any operating point is none of these.  Empty where the design cannot be
    re-checked."""
    if not relaxed:
        return {}
    try:
        records = [r.record() for r in solving.recheck(setting, outcome).rules]
    except (AgrisynthError, ValueError, ArithmeticError):
        return {}
    given_up = {name.split("@", 1)[0] for name in relaxed}
    return {r.name: {"miss": float(-r.margin), "unit": r.unit} for r in records
            if not r.satisfied and r.name.split("@", 1)[0] not in given_up and isinstance(r.margin, (int, float))
            and math.isfinite(r.margin)}


def at_bounds(names, bounds, design: dict) -> list[dict]:
    """The free design variables of ``design`` at a bound: ``{"name", "side" ("lower"/"upper"), "bound"}`` in the
    spec's units, in the variables' order; judged as the report's design table judges them (design_info.at_bound)."""
    out = []
    for name, (lo, hi) in zip(names, np.asarray(bounds, float)):
        side = at_bound(design.get(name), {"free": bool(hi > lo), "bounds": (lo, hi)})
        if side:
            out.append({"name": name, "side": side, "bound": float(lo if side == "lower" else hi)})
    return out


#: "every other rule relaxed": their elastic slacks held at this many of their scales, far beyond any margin
RELAXED_AWAY = 1e6


def alone_slacks(compiled, raw, relaxed: list[str], slacks: dict[str, float]) -> dict[str, float | None]:
    """Each rule the elastic re-solve gives up on, re-solved alone: from the elastic design, every other rule's
    slack held at RELAXED_AWAY scales (the rule is out of the problem) and only its own minimised.  The slack it
    still needs, in the rule's unit: positive, near that design the variable bounds or the mechanism (and the rules
    kept hard in the elastic form) hold the rule back, not the other rules; below its elastic slack, the other
    rules hold it back too.  None: nothing is known -- the re-solve did not converge, or it wandered off to a worse
    local minimum than the elastic design, which is a point of this relaxation.  A local statement, from the
    elastic design, like the diagnosis: another region of the bounds may meet the rule."""
    if not relaxed:
        return {}
    n = compiled.t.n_x
    names = [r.name for r in compiled.rules]
    scale_of = {r.name: r.scale for r in compiled.rules}
    free = [k for k, hard in enumerate(compiled.t.hard) if not hard]      # slack k is extra variable k
    out: dict[str, float | None] = {}
    for name in relaxed:
        if interrupt.pending() is not None:
            break
        own = names.index(name)
        lo, hi = compiled.t.lbw[n:].copy(), compiled.t.ubw[n:].copy()
        extra0 = np.array(raw.x[n:], float)
        for k in free:
            if k != own:
                lo[k] = hi[k] = extra0[k] = RELAXED_AWAY
        try:
            alone = compiled.solve(0, raw.x[:n], extra0, p=raw.p, extra_bounds=(lo, hi))
        except (AgrisynthError, ValueError, ArithmeticError, RuntimeError):
            out[name] = None
            continue
        value = compiled.slack_values(alone.x)[name] if alone.success else None
        worse = value is not None and value > slacks[name] + SLACK_TOL * scale_of[name]
        out[name] = None if value is None or worse else min(value, slacks[name])
    return out


#: ``details.start_from`` of the start solved from the elastic re-solve's design
FROM_ELASTIC = "elastic re-solve"


def start_from_elastic(kind: Kind, setting: Setting, run: Run, elastic: ElasticDiagnosis) -> Run:
    """When no start satisfies every rule but the elastic re-solve converged needing no slack, its design meets
    the rules at the solver's samples: a point the starts missed, not a conflict.  One more start (index
    ``run.starts``, ``details.start_from = "elastic re-solve"``) solves the spec's own NLP from it and is re-checked
    like any start.  The run keeps it only when it satisfies every rule (then it is the best: no other start does),
    and says so in ``solver.status_note``; otherwise, and for an NLP that builds its own starts
    (``builds_its_own_starts``: it may ignore the design given), the run is returned unchanged.  A start stopped by
    a signal is discarded (``interrupt.pending()``), as the multistart discards one."""
    if not elastic.converged or elastic.relaxed or not elastic.design:
        return run
    solving = _solving(kind)
    nlp = run.nlp if run.nlp is not None else solving.build(setting, False)
    if nlp.builds_its_own_starts:
        return run
    try:
        x0 = nlp.x_of(elastic.design)
        outcome = nlp.solve(run.starts, np.asarray(x0, float))
    except (AgrisynthError, ValueError, ArithmeticError, RuntimeError, KeyError):
        return run                # no start could be made from it: the run's verdict stands
    if interrupt.pending() is not None:
        return run
    outcome.details = {**(outcome.details or {}), "start_from": FROM_ELASTIC}
    report = report_of(outcome, functools.partial(_recheck, solving, setting))
    if not report.satisfied:
        return run
    return replace(run, reports=run.reports + [report], best=report)


def reaching_best(reports: list[StartReport], best: StartReport, maximise: bool) -> dict:
    """result.json ``solver`` entries: how many starts reach the best objective (every rule satisfied,
    objective tied with the best's by the verdict's tie rule) and how many starts, in start order, it
    took to reach it the first time -- a multistart's hit rate (bench, tests).  None / 0 when no start
    satisfies every rule."""
    if not best.satisfied:
        return {"starts_needed": None, "starts_reaching_best": 0}
    sign = -1.0 if maximise else 1.0
    fb = sign * best.outcome.objective
    hits = [r.outcome.start for r in reports
            if r.satisfied and sign * r.outcome.objective <= fb + TIE * max(1.0, abs(fb))]
    return {"starts_needed": min(hits) + 1, "starts_reaching_best": len(hits)}


def confidence_statement(reports: list[StartReport], nlp, maximise: bool,
                         answer: StartReport | None = None) -> dict | None:
    """result.json ``solver.confidence`` (:mod:`synthesis.core.confidence`): the starts that converged with every
    rule held (the starts an ``optimal`` verdict counts; the start from the elastic re-solve is no drawn start and is
    left out) grouped into distinct optima in the unit box of the NLP's free variables.  ``answer``: the run's best
    start; ``answer_counted`` says whether it is among the counted starts, and where it is not (it satisfies every
    rule but ended short of IPOPT's full tolerance, or came from the elastic re-solve) a note says the figures are
    the counted starts', not the answer's.  None without the NLP (a run interrupted before it was built)."""
    if nlp is None:
        return None
    bounds = np.asarray(nlp.bounds, float)
    free = bounds[:, 1] > bounds[:, 0]
    lo, width = bounds[free, 0], bounds[free, 1] - bounds[free, 0]
    counted = [r for r in reports if r.satisfied and r.outcome.success and reached_optimum(r.outcome.return_status)
               and (r.outcome.details or {}).get("start_from") != FROM_ELASTIC]
    notes = _not_uniform(nlp)
    try:
        units = np.reshape([(nlp.x_of(r.outcome.design)[free] - lo) / width for r in counted],
                           (len(counted), int(free.sum())))
    except (KeyError, ValueError, TypeError):     # a design without the NLP's variables: optima by value alone
        units = np.zeros((len(counted), 1))
        notes.append("the starts' designs could not be mapped to the box: distinct_designs not counted")
    counted_starts = {r.outcome.start for r in counted}
    outside = answer is not None and answer.outcome.start not in counted_starts
    if outside and answer is not None and answer.satisfied:     # (one that misses a rule: no start is counted)
        how = ("comes from the elastic re-solve, no drawn start"
               if (answer.outcome.details or {}).get("start_from") == FROM_ELASTIC
               else f"ended {answer.outcome.return_status}, short of IPOPT's full tolerance")
        above = answer_beyond(answer, [r.outcome.objective for r in counted], maximise)
        notes.append(f"the answer (start {answer.outcome.start}) is not counted: it {how}; these figures are the "
                     f"counted starts'{', every one of them worse than the answer' if above else ''}")
    return {**statement([r.outcome.objective for r in counted], units, [r.outcome.start for r in counted],
                        maximise=maximise, assumptions_not_met=notes), "answer_counted": not outside}


def answer_beyond(answer: StartReport, counted: list[float], maximise: bool) -> bool:
    """Whether the answer is better than every counted optimum by more than the statement's grouping tolerance
    (relative :data:`~synthesis.core.confidence.OBJECTIVE_TOLERANCE`): a start at the same optimum that stopped a
    hair lower (IPOPT's acceptable level) is not a better one."""
    if not counted:
        return False
    sign = -1.0 if maximise else 1.0
    best = min(sign * f for f in counted)
    mine = sign * answer.outcome.objective
    return mine < best - OBJECTIVE_TOLERANCE * max(1.0, abs(best))


def _not_uniform(nlp) -> list[str]:
    """Where a kind's starts break the estimate's model of uniform starts in the box of its decision variables."""
    notes = []       # a Latin hypercube's points are each uniform in the box (stratified, so not independent)
    if nlp.builds_its_own_starts:
        notes.append("the kind builds its own starts (screened), not uniform in the box")
    if nlp.configuration is not None:
        notes.append("each start first solves a reduced form of the problem")
    if list(nlp.design_names) != list(nlp.names):
        notes.append("the decision variables are not the design's own (the design map is not the identity)")
    if nlp.maps_its_starts:
        notes.append("the kind maps each start before solving it (its design may leave the uniform draw, e.g. "
                     "pulled into the region where the mechanism assembles)")
    return notes


def starts_table(reports: list[StartReport]) -> list[dict]:
    """result.json ``starts``: one row per start, the same shape for every kind."""
    return [{"start": r.outcome.start, "return_status": r.outcome.return_status, "success": r.outcome.success,
             "iterations": r.outcome.iterations, "wall_s": r.outcome.wall_s,
             "objective": measured(r.outcome.objective), "satisfied_on_fine_grid": r.satisfied,
             "worst_violation": measured(r.worst_violation), "why": r.why,
             "design": {k: measured(v) if isinstance(v, float) else v for k, v in r.outcome.design.items()},
             "details": r.outcome.details} for r in reports]


def ipopt_log(reports: list[StartReport]) -> str:
    return "\n".join(f"===== start {r.outcome.start}: {r.outcome.return_status}, {r.outcome.iterations} iterations\n"
                     f"{r.outcome.log}" for r in reports)


def run_solve(kind: Kind, loaded, starts: int | None = None, seed: int | None = None, workers: int = 1,
              on_start: Callable[[StartReport, StartReport], None] = lambda report, best: None,
              scheduler: str | None = None, record: Callable[[Any], None] | None = None,
              finished: dict[int, Any] | None = None, auto: AutoStarts | None = None,
              on_batch: Callable[[int, bool], None] = lambda total, nested: None,
              resumed_batch: int | None = None,
              resumed_nested: bool | None = None,
              previous: list[tuple[int, dict[int, Any]]] | None = None,
              on_note: Callable[[str], None] = lambda text: None) -> tuple[Result, list[StartReport], str]:
    """Multistart solve of a loaded spec of ``kind``; returns (result, every start's report, IPOPT log).

    ``starts``/``seed`` default to the spec's ``[solver]``; ``scheduler``: a dask.distributed address
    to run the starts on instead of ``workers`` local processes; ``record``/``finished``: see
    :func:`run_multistart`; ``auto`` (then ``starts`` is not used), ``on_batch``, ``resumed_batch``/``_nested``, ``previous``: see
    :func:`run_auto`.  Interrupted (SIGINT/SIGTERM): raises :class:`Interrupted` whose ``partial`` is
    (result with status ``interrupted`` -- the best of the finished starts --, reports, log), or None when
    no start had finished."""
    spec = loaded.model
    solving = _solving(kind)
    starts = spec.solver.starts if starts is None else starts
    seed = spec.solver.seed if seed is None else seed
    setting = Setting(spec, seed, solving.prepare(spec))
    try:
        if auto is None:
            run = run_multistart(kind, setting, starts=starts, workers=workers, scheduler=scheduler,
                                 on_start=on_start, record=record, finished=finished, on_note=on_note)
        else:
            run = run_auto(kind, setting, auto, workers=workers, scheduler=scheduler, on_start=on_start,
                           record=record, finished=finished, on_batch=on_batch, resumed_batch=resumed_batch,
                           resumed_nested=resumed_nested, previous=previous, on_note=on_note)
    except Interrupted as exc:
        if exc.partial is None:
            raise
        with interrupt.deferred(reraise=False):
            kept = _result(kind, loaded, setting, exc.partial, "interrupted", None)
        raise Interrupted(exc.signum, (kept, exc.partial.reports, ipopt_log(exc.partial.reports))) from None
    best = run.best
    elastic = None
    try:
        elastic = None if best.satisfied else elastic_diagnosis(kind, setting, run)
        if elastic is not None and interrupt.pending() is None:
            run = start_from_elastic(kind, setting, run, elastic)
            best = run.best
    except (KeyboardInterrupt, SystemError) as exc:    # a signal outside IPOPT (in Python code): recorded, handled
        if interrupt.pending() is None or not interrupt.caused_by_signal(exc):     # as the one below
            raise
    if interrupt.pending() is not None:       # stopped inside the elastic re-solve: every start is kept
        with interrupt.deferred(reraise=False):
            kept = _result(kind, loaded, setting, run, "interrupted", None)
        raise Interrupted(cast(int, interrupt.pending()), (kept, run.reports, ipopt_log(run.reports)))
    try:
        result = _result(kind, loaded, setting, run, status_of(best, elastic), elastic)
        # the exit-3 message, kept with the run for its report (_result always fills ``solver``)
        if result.status in ("infeasible", "failed") and result.solver is not None:
            result.solver["diagnosis"] = str(exit_error(kind, result, run.reports))
        # the answer is complete: a signal from here on is only noted (interrupt.pending), for the caller to say
        with interrupt.deferred(reraise=False):
            return result, run.reports, ipopt_log(run.reports)
    except (KeyboardInterrupt, SystemError) as exc:     # stopped while the kind finished the answer (a robust
        if not interrupt.caused_by_signal(exc):         # solve's Monte-Carlo check): every start is kept, as above
            raise
        with interrupt.deferred(reraise=False):
            kept = _result(kind, loaded, setting, run, "interrupted", None)
        raise Interrupted(interrupt.signal_of(exc), (kept, run.reports, ipopt_log(run.reports))) from None


def _result(kind: Kind, loaded, setting: Setting, run: Run, status: str, elastic: ElasticDiagnosis | None) -> Result:
    spec = loaded.model
    solving = _solving(kind)
    best = run.best
    try:
        finished = solving.finish(setting, best)
    except Exception:
        # a signal raised inside a CasADi call comes out as another exception (NotImplementedError): it is the
        # interruption, and the run keeps its finished starts as for any other (a robust finish checks for
        # signals between its samples itself, so the finish is not deferred as a whole)
        if interrupt.pending() is not None and not interrupt.deferring():
            raise KeyboardInterrupt from None
        raise
    extra_failed = [] if finished.rules is None or not best.satisfied else [
        r["name"] for r in finished.rules if not r["satisfied"]]
    if extra_failed and status in ("optimal", "feasible"):
        # the kind's table adds rules the per-start re-check does not hold (e.g. a tolerance-robust solve's
        # worst cases): a design that misses one was promised nothing -- the run failed, and says which
        status = "failed"
    note = (f"every rule holds on the fine grid at the best start, but not {', '.join(extra_failed)}: the design "
            f"does not keep its promise" if extra_failed and status == "failed" else None)
    return Result(
        kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status=status, design=finished.design,
        rules=[r.to_json() for r in best.records] if finished.rules is None else finished.rules,
        objective={**finished.objective, "value": measured(finished.objective.get("value"))},
        trajectory=finished.trajectory,
        solver={"name": "ipopt", "return_status": best.outcome.return_status,
                "iterations": best.outcome.iterations, "wall_s": run.wall_s, "starts": run.starts,
                "starts_run": len(run.reports), "stopped_early": status != "interrupted" and len(run.reports) < run.starts,
                "seed": run.seed, "best_start": best.outcome.start, "workers": run.workers,
                "scheduler": run.scheduler, "fine_grid_factor": FINE,
                "status_note": _sentences(note or _note(status, best, run), finished.note),
                **reaching_best(run.reports, best, solving.maximise(setting)), **finished.solver_settings,
                "confidence": confidence_statement(run.reports, run.nlp, solving.maximise(setting), best),
                # the run layer's: {"folder", "compile_s"} when the NLP's functions were compiled (solve --compiled)
                "compiled": None,
                **({} if run.auto is None else {"auto": run.auto})},
        starts=starts_table(run.reports),
        elastic=None if elastic is None else elastic.to_json(),
        baseline_design=(spec.design_values() if finished.baseline_design is None else finished.baseline_design),
        fine_grid_worst_violation=measured(best.worst_violation),
        extra=finished.facts,
    )


def _sentences(*notes: str | None) -> str | None:
    """The notes given in one text, each closed by a full stop when there are several; one note as it is; None
    when there is none."""
    said = [n for n in notes if n]
    if len(said) < 2:
        return said[0] if said else None
    return " ".join(n if n.endswith(".") else n + "." for n in said)


def _note(status: str, best: StartReport, run: Run) -> str | None:
    from_elastic = (best.outcome.details or {}).get("start_from") == FROM_ELASTIC
    if status != "interrupted" and best.satisfied and from_elastic:
        return " ".join(filter(None, [
            f"no start of {run.starts} satisfied every rule; the elastic re-solve needed no slack, and the design "
            f"is start {best.outcome.start}, one more start solved from the elastic re-solve's design",
            status_note(best)]))
    if status == "interrupted":
        done = min(len(run.reports), run.starts)
        extra = " and the start from the elastic re-solve" if len(run.reports) > run.starts else ""
        return (f"interrupted after {done} of {run.starts} starts{extra}: the best of those "
                f"(`agrisynth solve SPEC --resume RUN_DIR` finishes the run)")
    return status_note(best)


def exit_error(kind: Kind, result: Result, reports: list[StartReport]) -> SolverError:
    """The exit-3 error of a run with status infeasible or failed, from what the result says."""
    solving = _solving(kind)
    elastic = None if result.elastic is None else ElasticDiagnosis.from_json(result.elastic)
    note = (result.solver or {}).get("status_note")
    if result.status == "failed" and elastic is None and note and "does not keep its promise" in note:
        error = SolverError(f"{note}. {solving.relax_hint}")
    else:
        best_start = (result.solver or {}).get("best_start")
        error = unsatisfied_error(result.status, [r["name"] for r in result.violated()], reports, elastic,
                                  samples_hint=solving.samples_hint, relax_hint=solving.relax_hint,
                                  best=next((r for r in reports if r.outcome.start == best_start), None))
    said_more = solving.explain_failure(result) if solving.explain_failure is not None else None
    return SolverError(f"{error} {said_more}") if said_more else error


def baseline_rules(kind: Kind, loaded) -> list[dict] | None:
    """The rule table of the spec's given design, for the side-by-side table (None: it cannot be evaluated)."""
    solving = _solving(kind)
    spec = loaded.model
    setting = Setting(spec, spec.solver.seed, solving.prepare(spec))
    try:
        return solving.baseline_rules(setting)
    except (ValueError, ArithmeticError):
        return None


__all__ = ["Run", "AutoStarts", "rows_of_indices", "run_auto", "takes_auto_order", "refuse_other_order", "run_solve", "exit_error", "baseline_rules", "run_multistart", "elastic_diagnosis",
           "starts_table", "reaching_best", "ipopt_log"]
