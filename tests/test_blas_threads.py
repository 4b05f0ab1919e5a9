"""An answer does not depend on the machine's cores: IPOPT's linear algebra (MUMPS on CasADi's OpenBLAS) summed in
another order with more BLAS threads, so rotary_planetary's key-pose redesign (seed 7) ended start 2 at another
design, 0.01 mm away, on a 2-core machine than on a dask worker (whose nanny runs one thread).  synthesis.core.ipopt
asks for one thread while the IPOPT plugin loads, whatever the environment says (and leaves the environment as it
was)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from conftest import LIBRARY, ROOT


@pytest.mark.slow         # two short solves
@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="OpenBLAS runs one thread on one core whatever it is asked")
def test_a_solve_is_the_same_whatever_blas_threads_the_environment_asks_for(tmp_path):
    spec = LIBRARY / "rotary_planetary" / "key_pose_redesign.toml"
    starts = []          # one thread and four: the same answer to the bit
    for threads in ("1", "4"):
        env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
        env["OPENBLAS_NUM_THREADS"] = env["OMP_NUM_THREADS"] = threads
        out = tmp_path / threads
        env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
        # a process of its own: the environment is read when the IPOPT plugin loads, once per process
        run = subprocess.run([sys.executable, "-m", "synthesis.program", "solve", str(spec), "--starts", "4", "--seed",
                              "7", "--workers", "1", "--out", str(out)], cwd=tmp_path, env=env, capture_output=True,
                             text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        data = json.loads((out / "key_pose_redesign" / "result.json").read_text())
        starts.append([(s["objective"], s["design"]) for s in data["starts"]])
    assert starts[0] == starts[1]


def test_the_blas_pin_leaves_the_environment_as_it_was(monkeypatch):
    """The pin is asked for while nlpsol runs, not left in the process's environment for whatever else it runs."""
    import casadi as ca

    from synthesis.core.ipopt import BLAS_THREADS, _nlpsol

    x = ca.SX.sym("x")
    for before in (None, "3"):
        if before is None:
            monkeypatch.delenv(BLAS_THREADS, raising=False)
        else:
            monkeypatch.setenv(BLAS_THREADS, before)
        _nlpsol("pin", "ipopt", {"x": x, "f": x**2}, {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
        assert os.environ.get(BLAS_THREADS) == before
