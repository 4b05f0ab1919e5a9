"""Library warnings (scipy's ``UserWarning``s, CasADi's ``WARNING(...)`` lines) kept out of the terminal and
put into the run's log instead.

CasADi writes its warnings to Python's ``sys.stderr`` object (not to file descriptor 2), scipy and numpy
raise Python warnings; :func:`captured_warnings` swaps the one and records the other while a library call
runs, and yields a callable returning what was said, one line each, ready to append to a log.  Nothing is
lost: a run writes the text into its log (``ipopt.log`` of a solve, ``warnings.log`` of a check).
"""

from __future__ import annotations

import io
import sys
import warnings
from contextlib import contextmanager
from typing import Callable, Iterator


def _format(w: warnings.WarningMessage) -> str:
    return f"warning: {w.category.__name__}: {w.message} ({w.filename}:{w.lineno})"


@contextmanager
def captured_warnings() -> Iterator[Callable[[], str]]:
    """Record Python warnings and text written to ``sys.stderr`` inside the block; yields ``text()``."""
    buffer = io.StringIO()
    saved = sys.stderr
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        sys.stderr = buffer
        text: list[str] = []
        try:
            yield lambda: "".join(text)
        finally:
            sys.stderr = saved
            lines = [line for line in buffer.getvalue().splitlines() if line.strip()]
            lines += [_format(w) for w in caught]
            text.append("".join(f"{line}\n" for line in lines))
