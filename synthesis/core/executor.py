"""Fixed-seed starts through a ``concurrent.futures`` process pool or a dask cluster, for every kind.

A problem provides a picklable *factory* that builds its solver once; each worker process calls it
once (in the pool initializer) and reuses the built solver for every start it is given.  Start 0
is always the spec's own design; the others are a scrambled Latin hypercube over the free
variables' bounds, so the same seed gives the same starts on any machine.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import multiprocessing
import os
import signal
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable

import numpy as np

from synthesis.core import interrupt
from synthesis.core.outcome import StartOutcome
from synthesis.errors import AgrisynthError

_worker_solver: Any = None   # the solver built by this worker process's initializer
_worker_began: Any = None    # this worker's end of the pool's "start i began" queue

#: a start that raised: ``return_status`` is this prefix and the exception's type
START_RAISED = "Start_Raised"
#: a start whose worker process died (killed by the OS, out of memory, a crash in native code)
WORKER_CRASHED = "Worker_Crashed"


def failed_start(index: int, status: str, reason: str):
    """The outcome of a start that could not be solved (the default ``failure`` of :func:`run_starts`):
    not converged, objective inf, no design, and ``details["failure"]`` the reason (the verdict never
    re-checks it and ranks it below every start that ran)."""
    return StartOutcome(index, {}, math.inf, status, False, 0, 0.0, f"{status}: {reason}\n",
                        details={"failure": reason})


def _raised(exc: BaseException) -> tuple[str, str]:
    text = " ".join(str(exc).split())
    text = text if len(text) <= 300 else text[:297] + "..."
    return f"{START_RAISED}: {type(exc).__name__}", f"the start raised {type(exc).__name__}: {text or '(no message)'}"


def unit_latin_hypercube(d: int, n: int, seed: int) -> np.ndarray:
    """(n, d) points of a scrambled Latin hypercube in (0, 1]: each column one point in each of its n strata, at a
    uniform place within it.  The draws are scipy's ``qmc.LatinHypercube(d=d, seed=np.random.default_rng(seed))
    .random(n)``, to the bit (its generator is a child spawned from default_rng's seed sequence, the jitter drawn
    before the strata are shuffled column by column), without importing scipy.stats: 0.3 to 0.6 s of a solve's
    start-up."""
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed).spawn(1)[0]))
    jitter = rng.uniform(size=(n, d))
    strata = np.tile(np.arange(1, n + 1), (d, 1))
    for column in strata:
        rng.shuffle(column)
    return (strata.T - jitter) / n


def latin_hypercube_starts(bounds: np.ndarray, init: np.ndarray, n: int, seed: int) -> np.ndarray:
    """(n, d) start points: row 0 = init, rows 1.. a Latin hypercube in [lo, hi] (fixed dims = lo)."""
    lo, hi = bounds[:, 0], bounds[:, 1]
    starts = np.tile(init, (n, 1)).astype(float)
    if n > 1:
        starts[1:] = lo + unit_latin_hypercube(len(lo), n - 1, seed) * (hi - lo)
    return starts


def _init_worker(factory: Callable[[], Any], main_pid: int, began: Any = None) -> None:
    """A pool worker: leaves SIGINT/SIGTERM to the main process (which stops the run and ends the workers),
    dies with the main process (even a SIGKILL of it) and builds the solver once.  ``began``: a queue on
    which the worker says which start it begins (so a worker that dies names the start it was solving)."""
    global _worker_solver, _worker_began
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _die_with(main_pid)
    _worker_began = began
    _worker_solver = factory()


def _die_with(main_pid: int) -> None:
    """End this process when ``main_pid`` ends: PR_SET_PDEATHSIG where Linux has it, and a watchdog thread."""
    parent = os.getppid()
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)     # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError, TypeError):
        pass

    def alive(pid: int) -> bool:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
        return True

    def watch() -> None:
        while os.getppid() == parent and alive(main_pid):
            time.sleep(1.0)
        os._exit(1)

    if os.getppid() != parent or not alive(main_pid):
        os._exit(1)
    threading.Thread(target=watch, daemon=True, name="agrisynth-watchdog").start()


def _solve_in_worker(index: int, x0: np.ndarray):
    if _worker_began is not None:
        _worker_began.put(index)        # a SimpleQueue: written before the solve starts, not by a thread
    return _worker_solver.solve(index, x0)


def _drain(queue: Any, into: set[int]) -> None:
    with contextlib.suppress(OSError, EOFError, ValueError):
        while not queue.empty():
            into.add(queue.get())


def _exit_text(code: int | None) -> str:
    if code is None:
        return "its worker process died"
    if code < 0:
        with contextlib.suppress(ValueError):
            return f"its worker process was killed by {signal.Signals(-code).name}"
        return f"its worker process was killed by signal {-code}"
    return f"its worker process ended with exit code {code}"


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def _end_workers(pool: ProcessPoolExecutor) -> None:
    """Kill the pool's worker processes (an interrupted run: their starts are not waited for)."""
    kill = getattr(pool, "kill_workers", None)          # Python >= 3.14
    if kill is not None:
        kill()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            proc.kill()


def _pool_context():
    """The process pools' start method: fork where the platform has it, so a worker begins with this process's
    memory (its imports and the solver already built here), else the platform's default."""
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else None)


def workers_inherit_memory() -> bool:
    """True when a pool worker starts as a copy of this process (fork): a solver built here needs no rebuilding
    there, and its factory need not be picklable."""
    return _pool_context().get_start_method() == "fork"


def run_starts(factory: Callable[[], Any], starts: np.ndarray, workers: int,
               on_done: Callable[[Any], None] = lambda outcome: None,
               stop_when: Callable[[Any], bool] | None = None, scheduler: str | None = None,
               finished: dict[int, Any] | None = None,
               failure: Callable[[int, str, str], Any] = failed_start,
               on_note: Callable[[str], None] = lambda text: None) -> list:
    """Solve every start; returns the outcomes in start order. ``on_done`` sees each as it finishes.

    ``stop_when(outcome)`` ends the multistart early: when the start with the smallest index k for
    which it holds has finished, together with every start before it, the remaining starts are
    cancelled and the outcomes of starts 0..k are returned (in order; outcomes of later starts that
    happened to finish are dropped).  The result is therefore the same for any number of workers.

    ``finished`` (start index -> outcome): starts already solved (a resumed run); they are passed to
    ``on_done`` first, in start order, and not solved again, so the answer is the uninterrupted one.

    ``scheduler`` (a dask.distributed address) sends the starts to that cluster instead of a local
    process pool of ``workers``; there every start runs, and ``stop_when`` only trims the outcomes
    the same way, so the answer does not depend on where it ran.  When the cluster stops serving the run
    (the connection lost, no worker left), the starts it did not finish are solved on ``workers`` local
    workers and ``on_note`` is told so in one line.

    A start that raises, or whose worker process dies (killed by the OS, a crash in native code), is that
    start's failure and the run goes on: ``failure(index, return_status, reason)`` makes its outcome
    (return_status ``Start_Raised: <Error>`` or ``Worker_Crashed``).  After a worker dies the starts that
    were running are solved again one by one in a fresh worker, so the start that kills its worker is the
    one named, whatever the number of workers.

    Interrupts (:mod:`synthesis.core.interrupt`): KeyboardInterrupt propagates after the pending starts
    are cancelled and the pool's workers killed; a start that was running in this process when the
    signal came is discarded (IPOPT returns it as if finished).  Outcomes already passed to ``on_done``
    are the caller's to keep.
    """
    run = _Multistart(factory, starts, on_done, stop_when, failure, on_note)
    run.replay(finished or {})
    todo = [i for i in range(run.stop_at + 1) if i not in run.outcomes]
    if scheduler is not None:
        return run.on_cluster(todo, scheduler, workers)
    if todo and workers <= 1:      # in this process: no pool start-up cost, the solver built once
        run.in_process(todo)
    elif todo:
        run.in_pools(todo, workers)
    return run.counted()


class ClusterUnreachable(AgrisynthError):
    """A dask scheduler that cannot be reached, or has no worker to give the run (exit 2 before a run has used it:
    the address is the user's to fix; an auto run's later batch solves locally instead: core.solve.run_auto)."""


class _Multistart:
    """One call of :func:`run_starts`: the outcomes kept so far, the last start that counts (``stop_at``, lowered by
    an early stop) and how a finished start is kept."""

    def __init__(self, factory: Callable[[], Any], starts: np.ndarray, on_done: Callable[[Any], None],
                 stop_when: Callable[[Any], bool] | None, failure: Callable[[int, str, str], Any],
                 on_note: Callable[[str], None] = lambda text: None):
        self.factory, self.starts, self.on_done, self.stop_when, self.failure = (factory, starts, on_done, stop_when,
                                                                                 failure)
        self.on_note = on_note
        self.outcomes: dict[int, Any] = {}
        self.stop_at = len(starts) - 1                  # the last start index that counts

    def counted(self) -> list:
        return [self.outcomes[i] for i in range(self.stop_at + 1)]

    def settled(self) -> bool:
        return all(i in self.outcomes for i in range(self.stop_at + 1))

    def replay(self, finished: dict[int, Any]) -> None:
        """A resumed run's finished starts, in start order, as if they had just finished."""
        for i in sorted(finished):
            if i > self.stop_at:
                break
            out = finished[i]
            self.outcomes[i] = out
            self.on_done(out)
            if self.stop_when is not None and self.stop_when(out):
                self.stop_at = i
                break

    def accept(self, out) -> None:
        if out.start > self.stop_at or out.start in self.outcomes:
            return
        self.outcomes[out.start] = out
        self.on_done(out)
        if self.stop_when is not None and out.start < self.stop_at and self.stop_when(out):
            self.stop_at = out.start

    def on_cluster(self, todo: list[int], scheduler: str, workers: int) -> list:
        """Every start on the cluster; an early stop only trims the outcomes (the answer does not depend on where
        it ran).  A cluster that stops serving the run (:class:`~synthesis.core.cluster.SchedulerLost`) keeps the
        starts it finished; the rest are solved here on ``workers`` local workers, said by ``on_note``."""
        try:
            from synthesis.core.cluster import SchedulerLost, run_starts_on_cluster   # dask.distributed: an extra
        except ImportError:
            raise AgrisynthError("--scheduler needs dask.distributed: pip install 'agrisynth[cluster]'") from None
        try:
            solved = (run_starts_on_cluster(self.factory, self.starts[todo], scheduler, self.on_done, indices=todo,
                                            failure=self.failure) if todo else [])
            self.outcomes.update({out.start: out for out in solved})
        except SchedulerLost as lost:
            self.outcomes.update(lost.done)                   # each already handed to on_done
            for i in sorted(lost.done):                       # an early stop among them: fewer left to solve
                if self.stop_when is not None and i < self.stop_at and self.stop_when(lost.done[i]):
                    self.stop_at = i
            rest = self.remaining(todo)
            self.on_note(f"--scheduler {scheduler}: {lost.why} after {len(lost.done)} of {len(todo)} starts; the "
                         f"other {len(rest)} are solved here on {max(workers, 1)} local "
                         f"worker{'s' if workers > 1 else ''} (the same starts: the same answer)")
            if rest and workers <= 1:
                self.in_process(rest)
            elif rest:
                self.in_pools(rest, workers)
        everything = self.counted()
        first = next((i for i, out in enumerate(everything) if self.stop_when is not None and self.stop_when(out)),
                     None)
        return everything if first is None else everything[:first + 1]

    def in_process(self, todo: list[int]) -> None:
        solver = self.factory()
        interrupt.check()
        for i in todo:
            if i > self.stop_at:
                break
            try:
                out = solver.solve(i, self.starts[i])
            except Exception as exc:          # this start's failure; the run goes on
                if interrupt.pending() is not None:
                    raise KeyboardInterrupt from None
                out = self.failure(i, *_raised(exc))
            if interrupt.pending() is not None:      # IPOPT was stopped inside this start: not a finished one
                raise KeyboardInterrupt
            self.accept(out)

    def remaining(self, todo: list[int]) -> list[int]:
        return [i for i in todo if i <= self.stop_at and i not in self.outcomes]

    def in_pools(self, todo: list[int], workers: int) -> None:
        """The starts in process pools of ``workers``; after a worker dies, the starts that were running in it are
        solved again each alone in a pool of one, so the start that brings its worker down is the one named."""
        idle_breaks = 0
        while self.remaining(todo):
            suspects, broken = _PoolRound(self, self.remaining(todo), workers).run()
            if broken is None:
                break
            if not suspects:        # a worker died outside any start (building the solver?): try once more
                idle_breaks += 1
                if idle_breaks >= 2:
                    for i in self.remaining(todo):
                        self.accept(self.failure(i, WORKER_CRASHED, f"{broken} before solving it (every worker "
                                                                    f"process dies before solving any start: "
                                                                    f"building the solver?)"))
                continue
            idle_breaks = 0
            for i in suspects:
                if i > self.stop_at or i in self.outcomes:
                    continue
                _, alone = _PoolRound(self, [i], 1).run()
                if i not in self.outcomes:
                    self.accept(self.failure(i, WORKER_CRASHED, f"{alone or broken} while solving this start"))


class _PoolRound:
    """Some starts of a :class:`_Multistart` solved in one process pool.

    While this thread is inside concurrent.futures a signal is only recorded, and raised at the loop's safe point:
    raised there, it can leave a future's lock held (wait() takes every waited future's lock one by one), and the
    pool's manager thread, cancelling that future, then blocks forever and shutdown() with it (a SIGTERM hung a run
    this way)."""

    def __init__(self, run: _Multistart, indices: list[int], n_workers: int):
        self.multistart, self.indices = run, indices
        ctx = _pool_context()
        self.began_q = ctx.SimpleQueue()
        self.pool = ProcessPoolExecutor(max_workers=min(n_workers, len(indices)), mp_context=ctx,
                                        initializer=_init_worker, initargs=(run.factory, os.getpid(), self.began_q))
        self.began: set[int] = set()
        self.futures: dict = {}
        self.procs: list = []
        self.broken: str | None = None

    def run(self) -> tuple[list[int], str | None]:
        """Returns the starts that began but did not finish and, when a worker died (the pool is then broken), what
        happened to it (None: every start finished)."""
        try:
            self.collect()
        except BaseException as exc:
            self.abort(exc)
            raise
        self.close()
        run = self.multistart
        return sorted(i for i in self.began if i not in run.outcomes and i <= run.stop_at), self.broken

    def accept_finished(self) -> None:
        """Keep every start whose future finished without raising and is not yet kept."""
        for fut in sorted(self.futures, key=self.futures.__getitem__):
            if fut.done() and not fut.cancelled() and fut.exception() is None:
                self.multistart.accept(fut.result())

    def collect(self) -> None:
        """Submit the starts and keep each as it finishes, until every start that counts is kept or a worker dies."""
        run = self.multistart
        with interrupt.deferred(reraise=False):
            self.futures = {self.pool.submit(_solve_in_worker, i, run.starts[i]): i for i in self.indices}
        self.procs = list((getattr(self.pool, "_processes", None) or {}).values())
        by_start = {i: fut for fut, i in self.futures.items()}
        waiting = set(self.futures)
        cancelled_after = len(run.starts)
        while waiting and not run.settled():
            with interrupt.deferred(reraise=False):
                done, waiting = wait(waiting, timeout=0.5, return_when=FIRST_COMPLETED)
                _drain(self.began_q, self.began)
                for fut in sorted(done, key=self.futures.__getitem__):
                    self.keep(fut)
                if run.stop_at + 1 < cancelled_after:       # an early stop: the later starts are not needed
                    for later in range(run.stop_at + 1, cancelled_after):
                        if later in by_start:
                            by_start[later].cancel()
                    cancelled_after = run.stop_at + 1
            interrupt.check()       # the loop's safe point: the starts that finished are kept
            if self.broken is not None:
                codes = [p.exitcode for p in self.procs if p.exitcode not in (None, 0, -signal.SIGTERM)]
                self.broken = _exit_text(codes[0]) if len(codes) == 1 else self.broken
                break

    def keep(self, fut) -> None:
        """A finished future's start: its outcome, or its failure when it raised; a dead worker breaks the pool."""
        if fut.cancelled():      # a start after the early stop, cancelled before it ran
            return
        try:
            out = fut.result()
        except BrokenProcessPool:
            self.broken = "its worker process died"
            return
        except Exception as exc:        # raised inside the start: its failure, the run goes on
            out = self.multistart.failure(self.futures[fut], *_raised(exc))
        self.multistart.accept(out)

    def abort(self, exc: BaseException) -> None:
        """A signal or an error: the starts that finished since the last look are kept (after a signal), the others
        cancelled and the workers ended."""
        with interrupt.deferred(reraise=False):      # a second signal does not cut the clean-up short
            if interrupt.caused_by_signal(exc):
                with contextlib.suppress(Exception):    # (never at the cost of ending the workers below)
                    self.accept_finished()
            for fut in self.futures:
                fut.cancel()
            _end_workers(self.pool)
            self.pool.shutdown(wait=True, cancel_futures=True)

    def close(self) -> None:
        with interrupt.deferred():
            # after an early stop the starts still running are not needed: they are waited for (as shutdown
            # would) only until a signal comes, then their workers are ended
            running = [fut for fut in self.futures if not fut.done()] if self.broken is None else []
            while running and interrupt.pending() is None:
                running = list(wait(running, timeout=0.5)[1])
            if self.broken is not None or running:
                _end_workers(self.pool)
            self.pool.shutdown(wait=True, cancel_futures=True)
            _drain(self.began_q, self.began)
            if self.broken is not None:
                self.accept_finished()           # starts that finished as the pool broke
