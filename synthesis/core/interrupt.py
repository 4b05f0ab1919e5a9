"""SIGINT / SIGTERM during a solve: stop at the next safe point, keep every finished start.

CasADi checks Python's signal handlers while IPOPT iterates; when a handler raises, CasADi swallows the
exception, prints ``KeyboardInterruptException`` and returns the start as ``NonIpopt_Exception_Thrown``
-- a solve that *looks* finished.  So the handler installed here first records the signal (``pending()``)
and only then raises ``KeyboardInterrupt`` (which stops IPOPT at once).  The multistart checks
``pending()`` after every in-process solve and discards a start that was interrupted; blocks that must
not be cut in half (appending a start to ``starts.jsonl``, moving a run folder into place) run under
:func:`deferred`, which only records the signal and raises when the block ends.

Exit codes: 130 for SIGINT (Ctrl-C), 143 for SIGTERM (128 + the signal number, the shell convention).
"""

from __future__ import annotations

import contextlib
import signal
import threading

_pending: int | None = None      # the first signal received since install()
_defer_depth = 0
_replaced: dict = {}             # signal -> the disposition install() replaced (restore() puts it back)


class Interrupted(Exception):
    """The run was stopped by a signal; ``partial`` holds whatever the caller could keep."""

    def __init__(self, signum: int, partial=None):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum
        self.partial = partial

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


def _handler(signum, frame) -> None:
    global _pending
    if _pending is None:
        _pending = signum
    if _defer_depth == 0:
        raise KeyboardInterrupt


def install(keep_ignored: bool = False) -> None:
    """Handle SIGINT and SIGTERM in this (main) process as described above (a no-op off the main thread).
    ``keep_ignored``: a signal the process was started ignoring stays ignored (the program's entry point, which
    installs the handlers before anything else, for every command: a studio started with ``&`` keeps ignoring
    SIGINT).  The dispositions replaced are kept for :func:`restore`."""
    global _pending
    if threading.current_thread() is not threading.main_thread():
        _pending = None
        return
    # a second install (a command's, after the entry point's) keeps a signal already noted: it arrived during the
    # command's own imports and must still stop the run
    if not any(signal.getsignal(sig) is _handler for sig in (signal.SIGINT, signal.SIGTERM)):
        _pending = None
    for sig in (signal.SIGINT, signal.SIGTERM):
        current = signal.getsignal(sig)
        if keep_ignored and current is signal.SIG_IGN:
            continue
        if current is not _handler:
            _replaced.setdefault(sig, current)
        signal.signal(sig, _handler)


def restore() -> None:
    """Give SIGINT and SIGTERM back the dispositions :func:`install` replaced (for a command whose signals act as the
    process was started with: the studio, which ends by SIGTERM)."""
    global _pending
    _pending = None
    if threading.current_thread() is threading.main_thread():
        for sig, disposition in _replaced.items():
            signal.signal(sig, disposition)
        _replaced.clear()


def uninstall() -> None:
    global _pending
    _pending = None
    _replaced.clear()
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def ignore() -> None:
    """From now on SIGINT and SIGTERM do nothing (main thread only): for a command whose answer is written and
    printed, the moments left before the process exits have nothing to stop."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)


def pending() -> int | None:
    """The signal received since :func:`install` (None: none)."""
    return _pending


def caused_by_signal(exc: BaseException) -> bool:
    """Whether ``exc`` is this module's KeyboardInterrupt: the exception itself, or the SystemError Python raises
    when the handler's KeyboardInterrupt fires inside a C callback ("DM.__array__ returned a result with an
    exception set", numpy reading a CasADi matrix), which names it as its cause."""
    if isinstance(exc, KeyboardInterrupt):
        return True
    if not isinstance(exc, SystemError) or _pending is None:
        return False
    seen = set()
    cause = exc.__cause__ or exc.__context__
    while cause is not None and id(cause) not in seen:      # nested callbacks: SystemError from SystemError ...
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False


def signal_of(exc: BaseException) -> int:
    """The signal behind a KeyboardInterrupt (SIGINT when no handler recorded one)."""
    return _pending or signal.SIGINT


def check() -> None:
    """Raise KeyboardInterrupt if a signal arrived (for loops with a safe point)."""
    if _pending is not None and _defer_depth == 0:
        raise KeyboardInterrupt


@contextlib.contextmanager
def deferred(reraise: bool = True):
    """Record a signal arriving inside the block and raise KeyboardInterrupt only when it ends
    (``reraise=False``: not even then -- for the blocks that keep an interrupted run's results)."""
    global _defer_depth
    _defer_depth += 1
    try:
        yield
    finally:
        _defer_depth -= 1
    if reraise:
        check()


def deferring() -> bool:
    """Whether a :func:`deferred` block is running (a signal then waits for its end instead of being raised)."""
    return _defer_depth > 0


def simulate(signum: int = signal.SIGINT) -> None:
    """Record ``signum`` as if it had arrived (tests)."""
    global _pending
    _pending = signum
