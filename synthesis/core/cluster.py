"""Multistart starts on a dask.distributed cluster: the ``--scheduler`` path of :mod:`synthesis.core.executor`.

Imported only when a scheduler is given, so that local runs never import dask.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time
import uuid
from typing import Any, Callable, cast

import msgpack
import numpy as np
from distributed import Client, WorkerPlugin, get_worker
from distributed import wait as dask_wait

from synthesis.core import interrupt
from synthesis.core.executor import WORKER_CRASHED, ClusterUnreachable, _raised
from synthesis.errors import AgrisynthError

CONNECT_TIMEOUT_S = 10       # how long to wait for the scheduler before giving up
#: how long a scheduler without workers is waited for one to join: its starts would wait for ever, and the run with
#: them, without a word
WORKER_WAIT_S = 60.0
#: how often a run waiting for its starts looks whether the cluster still serves it (connected, a worker joined)
HEALTH_CHECK_S = 5.0
LOST = "the connection to the scheduler was lost"
#: a client's states once dask has given up its connection (it reconnects for a while first: "connecting")
GAVE_UP = ("closing", "closed", "failed")


class SchedulerLost(Exception):
    """The cluster stopped serving a run before every start had finished: ``why`` says how (one clause), ``done`` holds
    the outcomes it did finish (start index -> outcome, each already handed to ``on_done``).  Not a failure of the
    starts still pending: :mod:`synthesis.core.executor` solves them on local workers."""

    def __init__(self, why: str, done: dict[int, Any]):
        super().__init__(why)
        self.why, self.done = why, done


class _SolverPlugin(WorkerPlugin):
    """Builds the problem's solver once on each dask worker (``worker.plugins[name].solver``).

    A worker may run several tasks at once in threads; one CasADi/IPOPT solver object is not
    thread-safe and the IPOPT log capture redirects the process's stdout, so the worker's solves
    take turns (start workers with ``--nthreads 1`` to give each core its own process).
    """

    def __init__(self, factory: Callable[[], Any], name: str):
        self.factory, self.name = factory, name
        self.solver: Any = None           # the factory's solver, built on the worker (setup)
        self.lock: threading.Lock | None = None

    def setup(self, worker) -> None:
        self.solver = self.factory()
        self.lock = threading.Lock()

    def solve(self, index: int, x0: np.ndarray):
        if self.lock is None:
            raise RuntimeError(f"{self.name}: a solver plug-in solves only on a dask worker that set it up")
        with self.lock:
            return self.solver.solve(index, x0)


def _solve_on_dask_worker(plugin_name: str, index: int, x0: np.ndarray):
    plugin = cast(_SolverPlugin, get_worker().plugins[plugin_name])      # the one this module registered
    return plugin.solve(index, x0)


def _worker_failed(scheduler: str, exc: Exception) -> AgrisynthError:
    return AgrisynthError(f"--scheduler {scheduler}: a dask worker failed: {type(exc).__name__}: {exc} "
                          f"(do the workers run the same agrisynth and its dependencies?)")


#: a dask handshake message is a few hundred bytes; a first frame announcing more is not dask talking
MAX_HANDSHAKE_BYTES = 1 << 20


def probe_scheduler(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Check within ``timeout`` seconds that a dask scheduler answers at ``address`` (tcp://host:port).

    A dask server speaks first: right after accepting a connection it sends its handshake, a frame whose
    first 8 bytes are its length (little-endian).  So: connect, read 8 bytes, check the length.  A peer
    that answers otherwise (an HTTP server, an SSH daemon) or says nothing within the timeout is refused
    here (AgrisynthError, exit 2) rather than left to dask, which would wait for ever or try to allocate
    what the peer's bytes announce.  Only plain TCP is spoken (tls:// and ucx:// are refused; an inproc://
    scheduler lives in this process and needs no probe)."""
    scheme, sep, rest = address.partition("://")
    if scheme == "inproc":          # a scheduler in this very process (tests): nothing to probe
        return
    if not sep or scheme != "tcp":
        raise ClusterUnreachable(f"--scheduler {address[:80]}: only tcp://host:port addresses are supported")
    host, _, port_text = rest.rpartition(":")
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    try:
        port = int(port_text)
    except ValueError:
        raise ClusterUnreachable(f"--scheduler {address[:80]}: no port number (give tcp://host:port)") from None
    deadline = time.monotonic() + timeout
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except socket.timeout:
        raise ClusterUnreachable(f"--scheduler {address}: no answer within {timeout:g} s (nothing accepts "
                             f"connections there, or a firewall drops them)") from None
    except OSError as exc:
        raise ClusterUnreachable(f"--scheduler {address}: cannot reach a dask scheduler there "
                             f"({exc.strerror or exc})") from None
    def receive(count: int) -> bytes:
        """Up to ``count`` bytes (fewer: the peer closed), all by the deadline (socket.timeout otherwise)."""
        got = bytearray()
        while len(got) < count:
            left = deadline - time.monotonic()
            if left <= 0:
                raise socket.timeout
            sock.settimeout(left)
            chunk = sock.recv(min(count - len(got), 65536))
            if not chunk:
                break
            got += chunk
        return bytes(got)

    with sock:
        try:
            head = receive(8)
        except socket.timeout:
            raise ClusterUnreachable(f"--scheduler {address}: the peer accepted the connection but sent nothing "
                                 f"within {timeout:g} s; a dask scheduler greets at once, so this is not one") from None
        except OSError as exc:
            raise ClusterUnreachable(f"--scheduler {address}: the connection failed ({exc.strerror or exc})") from None
        if len(head) < 8:
            raise ClusterUnreachable(f"--scheduler {address}: the peer closed the connection without a dask handshake; "
                                 f"not a dask scheduler")
        (length,) = struct.unpack("<Q", head)
        if not 8 <= length <= MAX_HANDSHAKE_BYTES:
            what = " (it speaks HTTP: a web server or the dashboard port?)" if head.startswith(b"HTTP") else ""
            raise ClusterUnreachable(f"--scheduler {address}: the peer does not speak the dask protocol{what}; "
                                 f"it began with {head!r}")
        # the length alone proves little (8 bytes may read as a plausible one): read the whole first message by the
        # same deadline and check that it is dask's handshake -- dask reads it with no deadline and unpacks whatever
        # arrives (a peer silent after the length hung agrisynth for good; garbage after it was a struct.error)
        try:
            body = receive(length)
        except socket.timeout:
            raise ClusterUnreachable(f"--scheduler {address}: the peer announced a {length}-byte message and did not "
                                 f"send it within {timeout:g} s; a dask scheduler sends its handshake at once, so "
                                 f"this is not one") from None
        except OSError as exc:
            raise ClusterUnreachable(f"--scheduler {address}: the connection failed ({exc.strerror or exc})") from None
    if len(body) < length:
        raise ClusterUnreachable(f"--scheduler {address}: the peer closed the connection within its first message; "
                             f"not a dask scheduler")
    problem = handshake_problem(body)
    if problem:
        raise ClusterUnreachable(f"--scheduler {address}: the peer does not speak the dask protocol ({problem})")


def handshake_problem(message: bytes) -> str | None:
    """What keeps ``message`` (a first message's bytes after its length) from being a dask scheduler's handshake, or
    None: a count of frames, their lengths (8 bytes each, little-endian) and the frames, the first of them a msgpack
    map naming the peer's ``python`` and ``compression`` (distributed.comm.core's handshake_info).  Read here with
    struct and msgpack alone: dask's own reader would unpickle what it is sent."""
    if len(message) < 8:
        return "its first message is too short to hold a frame count"
    (count,) = struct.unpack_from("<Q", message)
    if not 1 <= count <= 64 or len(message) < 8 * (1 + count):
        return f"its first message announces {count} frames"
    lengths = struct.unpack_from(f"<{count}Q", message, 8)
    if 8 * (1 + count) + sum(lengths) != len(message):
        return "its first message's frames do not add up to its length"
    start = 8 * (1 + count)
    try:
        info = msgpack.unpackb(message[start:start + lengths[0]], raw=False, strict_map_key=False)
    except Exception as exc:            # noqa: BLE001 - any failure to unpack says the same: not dask's handshake
        return f"its first frame is not msgpack: {type(exc).__name__}"
    if not isinstance(info, dict) or "python" not in info or "compression" not in info:
        return "its first message is not a dask handshake"
    return None


def _connected_client(scheduler: str, timeout: float = CONNECT_TIMEOUT_S):
    """``Client(scheduler)`` within ``timeout`` seconds (twice it for the whole: the connection, dask's handshake and
    the first exchange), or AgrisynthError (exit 2).  dask reads the scheduler's handshake with no deadline: a peer
    that answered the probe and then stays silent would hold ``Client()`` for ever, so it is made in a daemon thread
    that is left behind (the run ends with the error) when it does not return in time."""
    made: dict[str, Any] = {}

    def connect() -> None:
        try:
            made["client"] = Client(scheduler, timeout=f"{timeout:g}s")
        except BaseException as exc:       # noqa: BLE001 - carried to the caller, who says it in one line
            made["error"] = exc

    thread = threading.Thread(target=connect, name="agrisynth-dask-connect", daemon=True)
    thread.start()
    thread.join(2 * timeout)
    if thread.is_alive():
        raise ClusterUnreachable(f"--scheduler {scheduler}: no dask handshake within {2 * timeout:g} s (the peer "
                             f"accepted the connection and then stopped answering); not a usable dask scheduler")
    if "error" in made:
        exc = made["error"]
        if not isinstance(exc, Exception):
            raise exc
        said = f": {str(exc)[:160]}" if str(exc) else ""
        raise ClusterUnreachable(f"--scheduler {scheduler}: cannot reach a dask scheduler there "
                             f"({type(exc).__name__}{said})") from None
    return made["client"]


def _wait_for_a_worker(client, scheduler: str, timeout: float = WORKER_WAIT_S) -> None:
    """Return once the scheduler has a worker; AgrisynthError (exit 2) when none joins within ``timeout`` seconds.
    A signal ends the wait (the scheduler's list is looked at every half second, a safe point each time)."""
    deadline = time.monotonic() + timeout
    while not client.scheduler_info().get("workers"):
        if time.monotonic() >= deadline:
            raise ClusterUnreachable(f"--scheduler {scheduler}: no dask worker joined the scheduler within {timeout:g} s "
                                 f"(start one: `dask worker {scheduler}`)")
        interrupt.check()
        time.sleep(0.5)


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
    probe_scheduler(scheduler)
    client = _connected_client(scheduler)
    with client:
        _wait_for_a_worker(client, scheduler)
        name = f"agrisynth-solver-{uuid.uuid4().hex}"
        try:
            client.register_plugin(_SolverPlugin(factory, name), name=name)
        except Exception as exc:     # the worker could not build the solver: its environment, not our input
            raise _worker_failed(scheduler, exc) from None
        try:
            futures = [client.submit(_solve_on_dask_worker, name, i, x0, pure=False) for i, x0 in zip(indices, starts)]
            index_of = {fut.key: i for fut, i in zip(futures, indices)}
            try:
                _collect(client, futures, index_of, scheduler, outcomes, on_done, failure)
            except BaseException:
                with contextlib.suppress(Exception):        # a lost scheduler cannot be told
                    client.cancel(futures)
                raise
        finally:
            with contextlib.suppress(Exception):     # never hide the error that got us here
                client.unregister_worker_plugin(name)
    return [outcomes[i] for i in indices]


def _collect(client, futures: list, index_of: dict, scheduler: str, outcomes: dict[int, Any],
             on_done: Callable[[Any], None], failure: Callable[[int, str, str], Any] | None) -> None:
    """Each start's outcome into ``outcomes`` (and ``on_done``) as it finishes.  Every :data:`HEALTH_CHECK_S` seconds
    without one, the cluster is looked at: a client that lost its scheduler (dask gives up reconnecting after its
    own timeout and cancels every pending start with the reason ``scheduler-connection-lost``), or a scheduler left
    without workers for :data:`WORKER_WAIT_S` seconds, raises :class:`SchedulerLost` -- never a failure of the
    starts still pending, which would turn a cluster's trouble into a run of fewer starts (each recorded as
    finished, so no ``--resume`` would solve them)."""
    pending = list(futures)
    alone_since: float | None = None
    while pending:
        try:
            finished, not_done = dask_wait(pending, timeout=HEALTH_CHECK_S, return_when="FIRST_COMPLETED")
        except TimeoutError:
            finished, not_done = set(), set(pending)
        except Exception as exc:       # noqa: BLE001 - a client that can no longer wait: its connection is gone
            why = (LOST if client.status in GAVE_UP or "Cancelled" in type(exc).__name__
                   else f"the client could no longer wait on it ({type(exc).__name__})")
            raise SchedulerLost(why, outcomes) from None
        pending = [f for f in pending if f in not_done]
        for fut in sorted(finished, key=lambda f: index_of[f.key]):
            try:
                out = fut.result()
            except Exception as exc:
                if _connection_lost(client, exc):
                    raise SchedulerLost(LOST, outcomes) from None
                if failure is None:
                    raise _worker_failed(scheduler, exc) from None
                if type(exc).__name__ == "KilledWorker":
                    out = failure(index_of[fut.key], WORKER_CRASHED, f"the dask worker died: {exc}")
                else:
                    out = failure(index_of[fut.key], *_raised(exc))
            outcomes[out.start] = out
            on_done(out)
        if finished or not pending:
            alone_since = None
            continue
        if client.status in GAVE_UP:            # "connecting": dask is still trying to reconnect
            raise SchedulerLost(LOST, outcomes)
        try:
            workers = client.scheduler_info().get("workers")
        except Exception:         # noqa: BLE001 - the scheduler does not answer its client
            raise SchedulerLost("the scheduler stopped answering", outcomes) from None
        if workers:
            alone_since = None
        elif alone_since is None:
            alone_since = time.monotonic()
        elif time.monotonic() - alone_since >= WORKER_WAIT_S:
            raise SchedulerLost(f"no dask worker was left on the scheduler for {WORKER_WAIT_S:g} s", outcomes)


def _connection_lost(client, exc: Exception) -> bool:
    """Whether a start's error is its client's lost connection rather than the start's own failure."""
    return (getattr(exc, "reason", None) == "scheduler-connection-lost"
            or (type(exc).__name__ in ("FutureCancelledError", "CancelledError") and client.status in GAVE_UP))
