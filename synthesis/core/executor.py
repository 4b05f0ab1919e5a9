"""Fixed-seed starts through a ``concurrent.futures`` process pool or a dask cluster, for every kind.

A problem provides a picklable *factory* that builds its solver once; each worker process calls it
once (in the pool initializer) and reuses the built solver for every start it is given.  Start 0
is always the spec's own design; the others are a scrambled Latin hypercube over the free
variables' bounds, so the same seed gives the same starts on any machine.
"""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, Callable

import numpy as np
from scipy.stats import qmc

from synthesis.errors import AgrisynthError

_worker_solver: Any = None   # the solver built by this worker process's initializer


def latin_hypercube_starts(bounds: np.ndarray, init: np.ndarray, n: int, seed: int) -> np.ndarray:
    """(n, d) start points: row 0 = init, rows 1.. a Latin hypercube in [lo, hi] (fixed dims = lo)."""
    lo, hi = bounds[:, 0], bounds[:, 1]
    starts = np.tile(init, (n, 1)).astype(float)
    if n > 1:
        unit = qmc.LatinHypercube(d=len(lo), seed=np.random.default_rng(seed)).random(n - 1)
        starts[1:] = lo + unit * (hi - lo)
    return starts


def _init_worker(factory: Callable[[], Any]) -> None:
    global _worker_solver
    _worker_solver = factory()


def _solve_in_worker(index: int, x0: np.ndarray):
    return _worker_solver.solve(index, x0)


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def run_starts(factory: Callable[[], Any], starts: np.ndarray, workers: int,
               on_done: Callable[[Any], None] = lambda outcome: None,
               stop_when: Callable[[Any], bool] | None = None, scheduler: str | None = None) -> list:
    """Solve every start; returns the outcomes in start order. ``on_done`` sees each as it finishes.

    ``stop_when(outcome)`` ends the multistart early: when the start with the smallest index k for
    which it holds has finished, together with every start before it, the remaining starts are
    cancelled and the outcomes of starts 0..k are returned (in order; outcomes of later starts that
    happened to finish are dropped).  The result is therefore the same for any number of workers.

    ``scheduler`` (a dask.distributed address) sends the starts to that cluster instead of a local
    process pool of ``workers``; there every start runs, and ``stop_when`` only trims the outcomes
    the same way, so the answer does not depend on where it ran.

    KeyboardInterrupt propagates after cancelling pending starts; outcomes already passed to
    ``on_done`` are the caller's to keep.
    """
    if scheduler is not None:
        try:
            from synthesis.core.cluster import run_starts_on_cluster
        except ImportError:
            raise AgrisynthError("--scheduler needs dask.distributed: pip install 'agrisynth[cluster]'") from None
        everything = run_starts_on_cluster(factory, starts, scheduler, on_done)
        first = next((i for i, out in enumerate(everything) if stop_when is not None and stop_when(out)), None)
        return everything if first is None else everything[:first + 1]
    outcomes: dict[int, Any] = {}
    stop_at = len(starts) - 1                  # the last start index that counts

    def settled() -> bool:
        return all(i in outcomes for i in range(stop_at + 1))

    if workers <= 1:      # in this process: no pool start-up cost, the solver built once
        solver = factory()
        for i, x0 in enumerate(starts):
            out = solver.solve(i, x0)
            outcomes[i] = out
            on_done(out)
            if stop_when is not None and stop_when(out):
                stop_at = i
                break
        return [outcomes[i] for i in range(stop_at + 1)]
    with ProcessPoolExecutor(max_workers=workers, initializer=_init_worker, initargs=(factory,)) as pool:
        futures = [pool.submit(_solve_in_worker, i, x0) for i, x0 in enumerate(starts)]
        try:
            for fut in as_completed(futures):
                if fut.cancelled():      # a start after the early stop, cancelled before it ran
                    continue
                out = fut.result()
                outcomes[out.start] = out
                on_done(out)
                if stop_when is not None and out.start < stop_at and stop_when(out):
                    stop_at = out.start
                    for later in futures[stop_at + 1:]:
                        later.cancel()
                if settled():
                    break
        except BaseException:
            for fut in futures:
                fut.cancel()
            raise
        for fut in futures[stop_at + 1:]:
            fut.cancel()
    return [outcomes[i] for i in range(stop_at + 1)]
