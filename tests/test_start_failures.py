"""A start that raises, or whose worker process dies, is that start's failure and the run goes on.

The executor records it as an outcome (return_status ``Start_Raised: <Error>`` / ``Worker_Crashed`` and the
reason), the verdict ranks it below every start that ran, and a run whose every start failed is exit 3.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass

import numpy as np
import pytest

from synthesis import kinds
from synthesis.core.executor import run_starts
from synthesis.core.verdict import failure_of


@dataclass
class Outcome:
    start: int
    good: bool = False


class FragileSolver:
    """Start 1 kills its worker process (as the OS does when memory runs out), start 3 raises."""

    def solve(self, index: int, x0) -> Outcome:
        if index == 1:
            time.sleep(0.1)
            os._exit(7)
        if index == 3:
            raise ZeroDivisionError("float division by zero in the kinematics")
        time.sleep(0.02)
        return Outcome(index)


def make_fragile() -> FragileSolver:
    return FragileSolver()


def test_a_start_that_raises_is_its_failure_in_process():
    seen: list[int] = []
    out = run_starts(RaisingOnly, np.zeros((5, 1)), 1, lambda o: seen.append(o.start))   # no os._exit here
    assert [o.start for o in out] == [0, 1, 2, 3, 4] and sorted(seen) == [0, 1, 2, 3, 4]
    assert out[3].return_status == "Start_Raised: ZeroDivisionError"
    assert failure_of(out[3]) == "the start raised ZeroDivisionError: float division by zero in the kinematics"
    assert all(isinstance(o, Outcome) for i, o in enumerate(out) if i != 3)


class RaisingOnly(FragileSolver):
    def solve(self, index: int, x0) -> Outcome:
        if index == 3:
            raise ZeroDivisionError("float division by zero in the kinematics")
        return Outcome(index)


def test_a_worker_that_dies_and_a_start_that_raises_do_not_end_the_run():
    """Two workers: start 1's worker exits (os._exit) -- the pool breaks -- and start 3 raises; every other
    start is solved, the dead worker's start is named (not its innocent neighbour), the order is kept."""
    seen: list[int] = []
    t0 = time.perf_counter()
    out = run_starts(make_fragile, np.zeros((8, 1)), 2, lambda o: seen.append(o.start))
    assert time.perf_counter() - t0 < 20
    assert [o.start for o in out] == list(range(8)) and sorted(seen) == list(range(8))
    assert out[1].return_status == "Worker_Crashed"
    # the exit code is named when the pool has reaped the process by the time it notices the break; under
    # load it may notice first (then "died")
    assert failure_of(out[1]) in ("its worker process ended with exit code 7 while solving this start",
                                  "its worker process died while solving this start")
    assert out[3].return_status == "Start_Raised: ZeroDivisionError"
    assert all(isinstance(o, Outcome) for i, o in enumerate(out) if i not in (1, 3))


@pytest.fixture
def toy():
    import toy_kind

    kinds.register(toy_kind.KIND)
    yield toy_kind.KIND
    kinds.unregister("toy_disc")


TOY = """kind = "toy_disc"
name = "toy"
x = { init = 0.0, bounds = [-20.0, 20.0] }
y = { init = 1.0, bounds = [-20.0, 20.0] }
radius = 10.0
y_min = -5.0
target = [30.0, 40.0]
[solver]
starts = 3
"""


def test_a_solve_keeps_going_past_a_raising_start_and_writes_it(tmp_path, toy):
    from synthesis.core.ipopt import answered_by, solved_with_method
    from synthesis.core.solve import run_solve
    from synthesis.errors import SolverError
    from synthesis.result import result_text
    from synthesis.spec import load_spec

    path = tmp_path / "toy.toml"
    path.write_text(TOY)
    loaded = load_spec(path)

    def runner(compiled, start, w0, p):
        if start == 0:
            raise RuntimeError("NLP evaluation failed\nin a way IPOPT could not handle")
        with answered_by([compiled], None):        # IPOPT itself for the other starts
            return compiled.solve(start, w0[:compiled.n_x])

    result, reports, _ = run_solve(solved_with_method(toy, runner=runner), loaded, workers=1)
    assert result.status == "optimal" and result.solver["best_start"] != 0
    row = json.loads(result_text(result))["starts"][0]
    assert row["return_status"] == "Start_Raised: RuntimeError" and row["objective"] is None
    assert row["why"] == "the start raised RuntimeError: NLP evaluation failed in a way IPOPT could not handle"
    assert row["design"] == {"x": 0.0, "y": 1.0}           # where it started

    def always(compiled, start, w0, p):
        raise MemoryError("cannot allocate")

    with pytest.raises(SolverError) as err:
        run_solve(solved_with_method(toy, runner=always), loaded, workers=1)
    assert err.value.exit_code == 3
    assert str(err.value) == ("toy_disc: no start could be solved: start 0 Start_Raised: MemoryError (the start "
                              "raised MemoryError: cannot allocate); start 1 Start_Raised: MemoryError (the start "
                              "raised MemoryError: cannot allocate); start 2 Start_Raised: MemoryError (the start "
                              "raised MemoryError: cannot allocate)")
