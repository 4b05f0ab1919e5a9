"""The ``agrisynth`` program's entry point.

The SIGINT / SIGTERM handlers (:mod:`synthesis.core.interrupt`, a few standard modules) are installed before
anything else: importing the command line (click, rich, and through the rules casadi and numpy) takes about 0.2 s,
and the commands import more before they would install them.  A signal in those moments ended the run silently
(SIGTERM: killed by the signal, no word) or in a KeyboardInterrupt traceback out of ``import casadi`` (Ctrl-C).  It
ends here as one during a run does: "interrupted", exit 130 (SIGINT) or 143 (SIGTERM), docs/ARCHITECTURE.md (exit
codes).  A signal the process was started ignoring stays ignored.  Only the moments before this function runs
(the interpreter's own start, tens of milliseconds) are left to the signal's default.
"""

from __future__ import annotations

import sys


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
    main()
