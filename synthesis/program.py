"""The ``agrisynth`` program's entry point.

The SIGINT / SIGTERM handlers (:mod:`synthesis.core.interrupt`, a few standard modules) are installed before
anything else: importing the command line (click, rich, and through the rules casadi and numpy) takes about 0.2 s,
and the commands import more before they would install them.  A signal in those moments ended the run silently
(SIGTERM: killed by the signal, no word) or in a KeyboardInterrupt traceback out of ``import casadi`` (Ctrl-C).  It
ends here as one during a run does: "interrupted", exit 130 (SIGINT) or 143 (SIGTERM), docs/ARCHITECTURE.md (exit
codes).  A signal the process was started ignoring stays ignored.  Only the moments before this function runs
(the interpreter's own start, tens of milliseconds) are left to the signal's default.

:func:`program` (the console script, ``python -m synthesis.program``) ends the process once the command has
returned without the interpreter's teardown: freeing a solve's expression graphs and modules one by one took 0.25 to
0.3 s after the last line was written (a 32-start planting solve, 3.7 s in all).  The exit handlers run and the
standard streams are flushed first, so nothing written is lost; with a thread or child process still running the
process ends the ordinary way.  :func:`main` raises ``SystemExit`` as before (a caller in process: the tests).
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import errno
import gc
import multiprocessing
import os
import sys
import threading
from typing import NoReturn


#: the cyclic garbage collector's thresholds for the console script: Python's (700, 10) for the young generations,
#: and a full collection after 100 collections of the middle one instead of 10 (:func:`program`)
GC_THRESHOLDS = (700, 10, 100)


def program() -> NoReturn:
    """The ``agrisynth`` console script: :func:`main`, then the end of the process (:func:`_end`).

    A command imports most of what it runs on first use (click, pydantic, casadi, scipy, matplotlib): hundreds of
    thousands of objects that live as long as the process.  With Python's thresholds the collector walked all of
    them in three full collections during those imports, 0.13 to 0.17 s of a 2 s ``check`` (its own callbacks'
    measure); a full collection once in 100 middle ones (:data:`GC_THRESHOLDS`) makes none there, and later ones
    still run, after ten times as many surviving allocations (a long bench or study keeps its cyclic garbage a
    little longer).  Measured, five runs each, interleaved: ``check`` of taiwan_example1 2.04 -> 1.87 s, a 32-start
    compiled planting solve 2.98 -> 2.78 s (medians); the interpreted solve unchanged (4.37 / 4.40 s).  The tests
    call :func:`main` and keep Python's thresholds."""
    gc.set_threshold(*GC_THRESHOLDS)
    try:
        main()
    except SystemExit as exc:
        _end(exc.code)
    _end(0)


def _end(code) -> NoReturn:
    """End the process with ``code`` (``SystemExit``'s: None is 0, a message is said and is 1) without the
    interpreter's teardown, unless something still runs that the teardown would wait for or whose output could be
    lost (a thread, a child process, a stream that cannot be flushed), a tool runs this program and acts once it
    returns (a profiler or coverage: ``python -m cProfile -m synthesis.program ...``), or the code is one Python
    itself maps (outside 0-255): then ``sys.exit`` ends it the ordinary way."""
    from synthesis.core import interrupt

    # the command's outcome is decided: a signal now changes nothing, on either way out (in the teardown or the wait
    # for a thread it would be a KeyboardInterrupt traceback; agrisynth's own threads are daemons, none is waited for)
    interrupt.ignore()
    if code is not None and not isinstance(code, int):
        sys.stderr.write(f"{code}\n")
        code = 1
    status = 0 if code is None else code
    others = [t for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    watched = sys.gettrace() is not None or sys.getprofile() is not None or "coverage" in sys.modules
    if others or multiprocessing.active_children() or watched or not 0 <= status <= 255:
        sys.exit(status)
    # what the interpreter runs first at exit (logging's flush, multiprocessing's finalizers, temporary folders'
    # clean-up); the teardown after them only frees memory the operating system takes back at once
    atexit._run_exitfuncs()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):       # a closed pipe: said and ended as Python would
        sys.exit(status)
    # and the C library's buffers, which os._exit leaves unwritten (native code's prints: CasADi, IPOPT)
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None).fflush(None)
    os._exit(status)


class _ReaderMayLeave:
    """A standard stream whose reader may leave (``| head``, a pager quit, a ``tee`` ended by the same Ctrl-C) or that
    was never there (a closed descriptor): from the first broken pipe or bad descriptor on, what is written goes to
    /dev/null, so the command goes on, keeps its files and exits with its own code.  (click turned a broken pipe into
    exit 1 and the run's folder was discarded: a finished solve lost, an interrupted one's "interrupted" line and
    exit 130 with it.)"""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except OSError as exc:
            if exc.errno not in (errno.EPIPE, errno.EBADF):
                raise
            self._to_null()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except OSError as exc:
            if exc.errno not in (errno.EPIPE, errno.EBADF):
                raise
            self._to_null()
            with contextlib.suppress(OSError, ValueError):
                self._stream.flush()        # what was waiting goes to /dev/null too

    def _to_null(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self._stream.fileno())
            os.close(null)

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def _standard_streams() -> None:
    """Standard descriptors the process was started without (``>&-``, a daemon's) are /dev/null, so no file the
    command opens takes their number (native code printing into it) and writing to them is no error (a traceback
    from the first isatty(), exit 1); standard output and error are then guarded against a reader that leaves."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            null = os.open(os.devnull, os.O_RDWR)
            if null != fd:
                os.dup2(null, fd)
                os.close(null)
    for fd, name, mode in ((0, "stdin", "r"), (1, "stdout", "w"), (2, "stderr", "w")):
        if getattr(sys, name) is None:       # Python had no stream for it: one on the descriptor just opened
            setattr(sys, name, open(fd, mode, closefd=False))
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if not isinstance(stream, _ReaderMayLeave):
            setattr(sys, name, _ReaderMayLeave(stream))


def main() -> None:
    from synthesis.core import interrupt

    _standard_streams()
    interrupt.install(keep_ignored=True)
    try:
        from synthesis.cli import main as run
    except (KeyboardInterrupt, ImportError, SystemError) as exc:
        # a signal inside a C extension's initialisation comes out as ImportError ("initialization failed") or
        # SystemError; without a signal those are real errors, and said as such
        if not isinstance(exc, KeyboardInterrupt) and interrupt.pending() is None:
            raise
        sys.stderr.write("interrupted\n")
        sys.exit(128 + interrupt.signal_of(exc))
    run()


if __name__ == "__main__":
    program()
