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
import multiprocessing
import os
import sys
import threading
from typing import NoReturn


def program() -> NoReturn:
    """The ``agrisynth`` console script: :func:`main`, then the end of the process (:func:`_end`)."""
    try:
        main()
    except SystemExit as exc:
        _end(exc.code)
    _end(0)


def _end(code) -> NoReturn:
    """End the process with ``code`` (``SystemExit``'s: None is 0, a message is said and is 1) without the
    interpreter's teardown, unless something still runs that the teardown would wait for or whose output could be
    lost (a thread, a child process, a stream that cannot be flushed): then ``sys.exit`` ends it the ordinary way."""
    from synthesis.core import interrupt

    interrupt.ignore()      # the command's outcome is decided: a signal now changes nothing (as in the teardown)
    if code is not None and not isinstance(code, int):
        sys.stderr.write(f"{code}\n")
        code = 1
    status = 0 if code is None else code
    others = [t for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    if others or multiprocessing.active_children():
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
    os._exit(status & 0xFF)


def main() -> None:
    from synthesis.core import interrupt

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
