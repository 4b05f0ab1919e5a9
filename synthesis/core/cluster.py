"""Multistart starts on a dask.distributed cluster: the ``--scheduler`` path of :mod:`synthesis.core.executor`.

Imported only when a scheduler is given, so that local runs never import dask.
"""

from __future__ import annotations

import contextlib
import threading
import uuid
from typing import Any, Callable

import numpy as np
from distributed import Client, WorkerPlugin, get_worker
from distributed import as_completed as dask_completed

from synthesis.errors import AgrisynthError

CONNECT_TIMEOUT_S = 10       # how long to wait for the scheduler before giving up


class _SolverPlugin(WorkerPlugin):
    """Builds the problem's solver once on each dask worker (``worker.plugins[name].solver``).

    A worker may run several tasks at once in threads; one CasADi/IPOPT solver object is not
    thread-safe and the IPOPT log capture redirects the process's stdout, so the worker's solves
    take turns (start workers with ``--nthreads 1`` to give each core its own process).
    """

    def __init__(self, factory: Callable[[], Any], name: str):
        self.factory, self.name, self.solver = factory, name, None
        self.lock: threading.Lock | None = None

    def setup(self, worker) -> None:
        self.solver = self.factory()
        self.lock = threading.Lock()

    def solve(self, index: int, x0: np.ndarray):
        with self.lock:
            return self.solver.solve(index, x0)


def _solve_on_dask_worker(plugin_name: str, index: int, x0: np.ndarray):
    return get_worker().plugins[plugin_name].solve(index, x0)


def _worker_failed(scheduler: str, exc: Exception) -> AgrisynthError:
    return AgrisynthError(f"--scheduler {scheduler}: a dask worker failed: {type(exc).__name__}: {exc} "
                          f"(do the workers run the same agrisynth and its dependencies?)")


def run_starts_on_cluster(factory: Callable[[], Any], starts: np.ndarray, scheduler: str,
                          on_done: Callable[[Any], None] = lambda outcome: None,
                          indices: list[int] | None = None,
                          failure: Callable[[int, str, str], Any] | None = None) -> list:
    """``run_starts`` on a dask.distributed cluster: each worker builds the solver once (a plugin).

    ``scheduler`` is the scheduler's address (``tcp://host:8786``).  The workers need agrisynth
    installed.  Outcomes come back in start order, so the result does not depend on the cluster.
    ``indices``: the start index of each row of ``starts`` (default 0, 1, ...; a resumed run's unfinished ones).
    ``failure(index, return_status, reason)``: the outcome of a start that raised or whose worker died
    (:func:`synthesis.core.executor.run_starts`); None: such a start ends the run (AgrisynthError).
    """
    indices = list(range(len(starts))) if indices is None else list(indices)
    outcomes: dict[int, Any] = {}
    try:
        client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
    except (OSError, ValueError, TimeoutError) as exc:
        raise AgrisynthError(f"--scheduler {scheduler}: cannot reach a dask scheduler there ({exc})") from None
    with client:
        name = f"agrisynth-solver-{uuid.uuid4().hex}"
        try:
            client.register_plugin(_SolverPlugin(factory, name), name=name)
        except Exception as exc:     # the worker could not build the solver: its environment, not our input
            raise _worker_failed(scheduler, exc) from None
        try:
            futures = [client.submit(_solve_on_dask_worker, name, i, x0, pure=False) for i, x0 in zip(indices, starts)]
            index_of = {fut.key: i for fut, i in zip(futures, indices)}
            try:
                for fut in dask_completed(futures):
                    try:
                        out = fut.result()
                    except Exception as exc:
                        if failure is None:
                            raise _worker_failed(scheduler, exc) from None
                        from synthesis.core.executor import WORKER_CRASHED, _raised

                        if type(exc).__name__ == "KilledWorker":
                            out = failure(index_of[fut.key], WORKER_CRASHED, f"the dask worker died: {exc}")
                        else:
                            out = failure(index_of[fut.key], *_raised(exc))
                    outcomes[out.start] = out
                    on_done(out)
            except BaseException:
                client.cancel(futures)
                raise
        finally:
            with contextlib.suppress(Exception):     # never hide the error that got us here
                client.unregister_worker_plugin(name)
    return [outcomes[i] for i in indices]
