"""IPOPT's output: its log (printed to file descriptor 1 from C++, captured per solve so the run folder
keeps it) and what its return statuses mean for a result's status."""

from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager
from typing import Callable, Iterator

from synthesis.core.library_log import captured_warnings


@contextmanager
def captured_stdout() -> Iterator[Callable[[], str]]:
    """Send fd 1 (where IPOPT prints) to a temporary file; yields a callable returning the text.  CasADi's
    warnings (written to ``sys.stderr``) and Python warnings raised meanwhile are appended to it
    (:mod:`synthesis.core.library_log`): they belong in the run's log, not on the terminal."""
    sys.stdout.flush()
    saved = os.dup(1)
    text: list[str] = []
    said = None
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        try:
            with captured_warnings() as said:
                os.dup2(tmp.fileno(), 1)
                yield lambda: "".join(text)
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
            tmp.seek(0)
            text.append(tmp.read().decode(errors="replace"))
            if said is not None:
                text.append(said())


def reached_optimum(return_status: str) -> bool:
    """Did IPOPT stop at a point meeting its full tolerances?  CasADi's ``success`` also counts
    Solved_To_Acceptable_Level (looser tolerances), which a result may call feasible but not optimal."""
    return return_status == "Solve_Succeeded"
