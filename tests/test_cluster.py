"""Multistart on a dask.distributed cluster (--scheduler): same starts, same answer as local workers."""

from __future__ import annotations

import contextlib
import subprocess
import sys

import pytest

from conftest import PLANTING
from solving import run_solve
from synthesis.spec import load_spec

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def cluster():
    # one worker: in-process (thread) workers would share one CasADi solver object between threads
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as c:
        yield c


@pytest.mark.slow
def test_cluster_run_gives_the_local_result(cluster):
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    local, _, _ = run_solve(loaded, starts=3, seed=5, workers=1)
    remote, reports, _ = run_solve(loaded, starts=3, seed=5, workers=1, scheduler=cluster.scheduler_address)
    assert [r.outcome.start for r in reports] == [0, 1, 2]
    assert remote.design == local.design
    assert remote.solver["scheduler"] == cluster.scheduler_address and remote.solver["best_start"] == local.solver["best_start"]


@pytest.mark.slow
def test_fourbar_path_on_the_cluster_gives_the_local_result(cluster):
    loaded = load_spec(PLANTING.parent / "fourbar_path" / "picking_arc.toml")
    local, _, _ = run_solve(loaded, starts=3, seed=1, workers=1)
    remote, _, _ = run_solve(loaded, starts=3, seed=1, workers=1, scheduler=cluster.scheduler_address)
    assert remote.design == local.design and remote.objective == local.objective


@pytest.mark.parametrize("spec", ["guide_tube/cai2020_delta2.toml", "clamp_cam/opening_cam_redesign.toml",
                                  "picker/cai2020_crank_rocker_synthesis.toml"])
def test_rule_kinds_on_the_cluster_give_the_local_result(cluster, spec):
    loaded = load_spec(PLANTING.parent / spec)
    run_solve_of_kind = run_solve
    local, _, _ = run_solve_of_kind(loaded, starts=2, seed=0, workers=1)
    remote, _, _ = run_solve_of_kind(loaded, starts=2, seed=0, workers=1, scheduler=cluster.scheduler_address)
    assert remote.design == local.design and remote.status == local.status
    assert remote.solver["scheduler"] == cluster.scheduler_address


def test_unreachable_scheduler_is_bad_input(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "synthesis.cli", "solve", str(PLANTING / "redesign_from_example1.toml"),
                           "--out", str(tmp_path), "--scheduler", "nonsense://nowhere"], capture_output=True, text=True)
    assert proc.returncode == 2
    # a scheme other than tcp:// is refused before anything starts (tls/ucx gave a TypeError)
    assert "'nonsense://nowhere' is not a scheduler address: give tcp://host:port" in proc.stderr
    assert "Traceback" not in proc.stderr


class _BrokenFactory:
    """A solver factory that fails on the worker, as a missing dependency there would."""

    def __call__(self):
        raise ModuleNotFoundError("No module named 'casadi' (on the worker)")


def test_a_failing_worker_is_reported_not_a_traceback(cluster):
    import numpy as np

    from synthesis.errors import AgrisynthError
    from synthesis.core.executor import run_starts

    with pytest.raises(AgrisynthError, match="a dask worker failed: .*No module named 'casadi'"):
        run_starts(_BrokenFactory(), np.zeros((2, 1)), 1, scheduler=cluster.scheduler_address)


class _Peer:
    """A local TCP server on a free port: ``greeting`` bytes sent on accept (None: it stays silent), then
    the connection is held open, or closed with ``hang_up``."""

    def __init__(self, greeting: bytes | None, hang_up: bool = False):
        import socket
        import threading

        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(4)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.greeting, self.hang_up, self.held = greeting, hang_up, []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            if self.greeting is not None:
                conn.sendall(self.greeting)
            if self.hang_up:
                conn.close()
            else:
                self.held.append(conn)          # kept open: a silent peer never closes

    def close(self) -> None:
        for c in self.held:
            c.close()
        self.sock.close()


HTTP = b"HTTP/1.1 400 Bad Request\r\nContent-Type: text/plain\r\nContent-Length: 11\r\n\r\nBad Request"


@pytest.mark.parametrize("greeting, hang_up, complaint", [
    (HTTP, False, "does not speak the dask protocol (it speaks HTTP"),
    (None, False, "sent nothing within 0.5 s"),
    (b"SSH-2", True, "closed the connection without a dask handshake"),
])
def test_a_peer_that_is_no_dask_scheduler_is_refused_within_the_timeout(greeting, hang_up, complaint):
    """A peer answering HTTP made dask allocate 3 EiB; a silent one hung for minutes."""
    import time

    from synthesis.core.cluster import probe_scheduler
    from synthesis.errors import AgrisynthError

    peer = _Peer(greeting, hang_up)
    t0 = time.perf_counter()
    try:
        with pytest.raises(AgrisynthError) as err:
            probe_scheduler(peer.address, timeout=0.5)
    finally:
        peer.close()
    assert time.perf_counter() - t0 < 2.0
    assert err.value.exit_code == 2 and complaint in str(err.value) and "\n" not in str(err.value)


def test_other_schemes_are_refused_and_a_real_scheduler_passes_the_probe():
    from synthesis.core.cluster import probe_scheduler
    from synthesis.errors import AgrisynthError

    for address in ("tls://127.0.0.1:8786", "ucx://127.0.0.1:8786"):
        with pytest.raises(AgrisynthError, match="only tcp://host:port addresses are supported"):
            probe_scheduler(address, timeout=0.5)
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0", protocol="tcp") as c:
        probe_scheduler(c.scheduler_address, timeout=5)


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_solve_with_an_http_peer_as_scheduler_exits_2_in_one_line(tmp_path):
    from synthesis.core import interrupt
    from test_run_folders import cli_in_process

    peer = _Peer(HTTP)
    try:
        code, err = cli_in_process("solve", str(PLANTING / "redesign_from_example1.toml"), "--out", str(tmp_path),
                                   "--scheduler", peer.address)
    finally:
        peer.close()
        interrupt.uninstall()
    assert code == 2, err
    assert "does not speak the dask protocol" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []          # refused before any output folder was made


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_scheduler_without_workers_is_said_in_one_line_not_waited_on_for_ever(monkeypatch):
    """A scheduler no worker had joined held `solve --scheduler` silently until a signal ended it."""
    from synthesis.core import cluster as cluster_module
    from synthesis.errors import AgrisynthError

    monkeypatch.setattr(cluster_module._wait_for_a_worker, "__defaults__", (1.0,))
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0", protocol="tcp") as c:
        with pytest.raises(AgrisynthError) as raised:
            run_solve(loaded, starts=2, seed=0, workers=1, scheduler=c.scheduler_address)
    assert str(raised.value) == (f"--scheduler {c.scheduler_address}: no dask worker joined the scheduler within 1 s "
                                 f"(start one: `dask worker {c.scheduler_address}`)")


@contextlib.contextmanager
def _cluster_processes():
    """A dask scheduler and one worker, each in a process of its own, the scheduler on a free port: (its address, the
    scheduler's process, the worker's), both killed on leaving (a test kills one of them mid-run)."""
    import socket
    import time

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", str(port), "--no-dashboard"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        time.sleep(2)
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                                   "--no-nanny", "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        yield address, scheduler, worker
    finally:
        for proc in (worker, scheduler):
            if proc is not None:
                proc.kill()
                proc.wait()


@pytest.mark.slow         # about 20 s: dask gives up reconnecting after its own 10 s
@pytest.mark.parametrize("lose, said", [
    ("scheduler", "the connection to the scheduler was lost"),
    ("worker", "no dask worker was left on the scheduler for 1 s"),
])
def test_a_cluster_lost_mid_run_leaves_its_pending_starts_to_local_workers(monkeypatch, lose, said):
    """A scheduler that died mid-run turned every start still pending into a failed start (``Start_Raised:
    FutureCancelledError``), each recorded as finished: a 60-start run answered from the 9 solved before, said
    `optimal`, and no --resume would have solved the rest; a cluster whose last worker died held the run for good.
    Now the finished starts are kept, the others solved here, and the answer is the local run's."""
    from synthesis import kinds
    from synthesis.core import cluster as cluster_module
    from synthesis.core.solve import run_solve as core_run_solve

    monkeypatch.setattr(cluster_module, "HEALTH_CHECK_S", 0.5)
    monkeypatch.setattr(cluster_module, "WORKER_WAIT_S", 1.0)
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    kind = kinds.solving_kind_for(loaded)
    finished, notes = [], []
    with _cluster_processes() as (address, scheduler, worker):
        def on_start(report, best) -> None:
            finished.append(report.outcome.start)
            if len(finished) == 2:
                (scheduler if lose == "scheduler" else worker).kill()

        remote, reports, _ = core_run_solve(kind, loaded, 24, 3, 1, on_start, address, on_note=notes.append)
    local, local_reports, _ = run_solve(loaded, starts=24, seed=3, workers=1)
    assert len(notes) == 1 and notes[0].startswith(f"--scheduler {address}: {said} after "), notes
    assert notes[0].endswith("are solved here on 1 local worker (the same starts: the same answer)")
    assert sorted(finished) == list(range(24))          # every start told once
    assert [r.outcome.return_status for r in reports] == [r.outcome.return_status for r in local_reports]
    assert not any(r.outcome.return_status.startswith("Start_Raised") for r in reports)
    assert remote.design == local.design and remote.solver["best_start"] == local.solver["best_start"]


@pytest.mark.slow         # about 25 s
def test_an_auto_run_whose_cluster_is_lost_solves_its_later_batches_locally(monkeypatch):
    """--starts auto on a cluster lost in its first batch: that batch's pending starts and every later batch run on
    the local workers (a later batch would otherwise probe the lost scheduler and end the run with exit 2, its
    finished batches lost); the answer and the batches are the local auto run's."""
    from synthesis import kinds
    from synthesis.core import cluster as cluster_module
    from synthesis.core.solve import AutoStarts, run_solve as core_run_solve

    monkeypatch.setattr(cluster_module, "HEALTH_CHECK_S", 0.5)
    auto = AutoStarts(max_starts=32, first=8, min_converged=16)      # the first batch cannot stop the run
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    kind = kinds.solving_kind_for(loaded)
    finished, notes = [], []
    with _cluster_processes() as (address, scheduler, _):
        def on_start(report, best) -> None:
            finished.append(report.outcome.start)
            if len(finished) == 2:
                scheduler.kill()

        remote, _, _ = core_run_solve(kind, loaded, None, 3, 1, on_start, address, auto=auto, on_note=notes.append)
    local, _, _ = core_run_solve(kind, loaded, None, 3, 1, auto=auto)
    assert len(notes) == 1 and "the connection to the scheduler was lost after " in notes[0]
    assert remote.solver["auto"] == local.solver["auto"] and remote.design == local.design
    assert len(remote.solver["auto"]["batches"]) >= 2


@pytest.mark.slow         # about 20 s
def test_an_auto_run_whose_cluster_is_gone_between_two_batches_solves_the_rest_locally():
    """The scheduler killed as batch 2 begins: its connection refused, the run ended with exit 2 and no result, the
    finished batch lost; now that batch and the later ones run locally, the answer the local auto run's."""
    from synthesis import kinds
    from synthesis.core.solve import AutoStarts, run_solve as core_run_solve

    auto = AutoStarts(max_starts=32, first=8, min_converged=16)      # the first batch cannot stop the run
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    kind = kinds.solving_kind_for(loaded)
    notes: list = []
    with _cluster_processes() as (address, scheduler, _):
        def on_batch(total: int, nested: bool) -> None:
            if total == 16:
                scheduler.kill()
                scheduler.wait()

        remote, _, _ = core_run_solve(kind, loaded, None, 3, 1, scheduler=address, auto=auto, on_batch=on_batch,
                                      on_note=notes.append)
    local, _, _ = core_run_solve(kind, loaded, None, 3, 1, auto=auto)
    assert len(notes) == 1 and notes[0].startswith(f"--scheduler {address}: the cluster could not be reached for "
                                                   f"the batch of 16 starts (")
    assert remote.solver["auto"] == local.solver["auto"] and remote.design == local.design
