"""Multistart on a dask.distributed cluster (--scheduler): same starts, same answer as local workers."""

from __future__ import annotations

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


def test_cluster_run_gives_the_local_result(cluster):
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    local, _, _ = run_solve(loaded, starts=3, seed=5, workers=1)
    remote, reports, _ = run_solve(loaded, starts=3, seed=5, workers=1, scheduler=cluster.scheduler_address)
    assert [r.outcome.start for r in reports] == [0, 1, 2]
    assert remote.design == local.design
    assert remote.solver["scheduler"] == cluster.scheduler_address and remote.solver["best_start"] == local.solver["best_start"]


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
    # a scheme other than tcp:// is refused before anything starts (issue 22: tls/ucx gave a TypeError)
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
