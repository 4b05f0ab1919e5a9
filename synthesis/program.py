"""The ``agrisynth`` program's entry point.

Importing the command line (click, rich, and through the rules casadi and numpy) takes about 0.2 s, before
:func:`synthesis.cli.main` can handle a signal: a Ctrl-C then ended in a KeyboardInterrupt traceback out of
``import casadi``.  It ends here as one during a run does: "interrupted", exit 130 (docs/ARCHITECTURE.md, "Exit codes").
"""

from __future__ import annotations

import sys


def main() -> None:
    try:
        from synthesis.cli import main as run
    except KeyboardInterrupt:
        sys.stderr.write("interrupted\n")
        sys.exit(130)
    run()


if __name__ == "__main__":
    main()
