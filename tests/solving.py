"""Test helpers over the kind contract: solve a loaded spec, re-check a design as the solve does."""

from __future__ import annotations

import functools
from types import SimpleNamespace

from synthesis import kinds
from synthesis.core.kind import Setting
from synthesis.kinds import solve_spec as run_solve


@functools.lru_cache(maxsize=None)
def solved_library_spec(relative: str):
    """``solve_spec(load_spec(problems/RELATIVE), workers=1)`` -- the spec's own starts and seed -- solved once per test
    process for the tests that read the same library solve (give them one ``xdist_group``, :func:`same_solve`, so
    that they share this process).  The answer is shared: read it, never change it."""
    from conftest import LIBRARY
    from synthesis.spec import load_spec

    return run_solve(load_spec(LIBRARY / relative), workers=1)


def same_solve(relative: str):
    """The mark that keeps the tests reading :func:`solved_library_spec` (``relative``) in one test process."""
    import pytest

    return pytest.mark.xdist_group(f"library-solve:{relative}")


def recheck_rules(spec, design: dict) -> list:
    """The rules (floats) of ``design`` as the multistart's fine-grid re-check evaluates them."""
    solving = kinds.get(spec.kind).solving()
    setting = Setting(spec, spec.solver.seed, solving.prepare(spec))
    return solving.recheck(setting, SimpleNamespace(design=design, details={})).rules


def diagnose_infeasible(loaded, result, reports):
    """The exit-3 error the CLI raises for this result."""
    from synthesis.core.solve import exit_error

    return exit_error(kinds.get(loaded.kind), result, reports)


def baseline_rules(loaded):
    from synthesis.core import solve

    return solve.baseline_rules(kinds.get(loaded.kind), loaded)


# --- through the CLI, as a user runs it -------------------------------------------------------------------

def needs_own_process(args) -> bool:
    """Whether ``agrisynth ARGS`` must run in a process of its own: a solve or bench on a pool of workers (it
    would fork this test process and its threads), on a cluster, or the studio (a server)."""
    args = [str(a) for a in args]
    if not args or args[0] == "studio" or "--scheduler" in args:
        return True
    if args[0] in ("solve", "bench"):
        given = [value for flag, value in zip(args, args[1:]) if flag == "--workers"]
        if given:
            return given[-1] != "1"                     # click keeps the last one given
        return not ({"-h", "--help"} & set(args))       # the default is one worker per core
    return False


class _TimedOut(BaseException):
    """Raised by the alarm of an in-process :func:`agrisynth` run (a BaseException: the CLI catches no such thing)."""


#: the warning filters of an interpreter started without -W or PYTHONWARNINGS (what a user's run shows)
_FRESH_WARNING_FILTERS = (("default", DeprecationWarning, "__main__"), ("ignore", DeprecationWarning, ""),
                          ("ignore", PendingDeprecationWarning, ""), ("ignore", ImportWarning, ""),
                          ("ignore", ResourceWarning, ""))


def agrisynth(*args, cwd=None, timeout: float = 300):
    """The agrisynth command line as ``python -m synthesis.cli ARGS`` run in ``cwd`` (default: this one) gives it: a
    ``subprocess.CompletedProcess`` with the exit code, and stdout and stderr as text -- what Python and native
    code (IPOPT) write to the two file descriptors, the Python warnings a fresh interpreter would print, an uncaught
    exception as its traceback and exit code 1; ``subprocess.TimeoutExpired`` after ``timeout`` seconds.

    It runs in this process (a new interpreter's imports cost a test 1-3 s of CPU; the suite starts hundreds),
    with the working directory, ``sys.argv``, the standard streams, the signal handlers and the interrupt state
    restored after it, except where :func:`needs_own_process`.  What an interpreter prints while importing is
    not seen here: the tests that a run imports only what it needs, and those of signals and exit codes of the
    process itself, start their own process."""
    import contextlib
    import io
    import os
    import signal
    import subprocess
    import sys
    import tempfile
    import traceback
    import warnings

    args = [str(a) for a in args]
    if needs_own_process(args):
        return subprocess.run([sys.executable, "-m", "synthesis.cli", *args], cwd=cwd, capture_output=True, text=True,
                              timeout=timeout)
    from synthesis.cli import main
    from synthesis.core import interrupt

    timer = {"armed": False, "fired": False}

    def alarm(signum, frame):
        if timer["armed"]:
            timer["fired"] = True
            # inside IPOPT CasADi swallows the exception: the noted signal stops the solve at its next safe point
            # (the timer repeats each second until the run is over)
            interrupt.simulate(signal.SIGALRM)
            raise _TimedOut

    here = os.getcwd()
    os.chdir(here if cwd is None else cwd)          # a folder that is not there raises here, in the test
    saved_streams = (sys.stdout, sys.stderr, sys.argv)
    saved_handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGALRM)}
    sys.stdout.flush()
    sys.stderr.flush()
    saved_fds: list[int] = []
    texts = ["", ""]
    code = 0
    try:
        saved_fds = [os.dup(1), os.dup(2)]
        with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
            os.dup2(out.fileno(), 1)
            os.dup2(err.fileno(), 2)
            stdout = io.TextIOWrapper(io.FileIO(1, "w", closefd=False), encoding="utf-8", write_through=True)
            stderr = io.TextIOWrapper(io.FileIO(2, "w", closefd=False), encoding="utf-8", write_through=True)
            sys.stdout, sys.stderr, sys.argv = stdout, stderr, ["agrisynth", *args]
            try:
                signal.signal(signal.SIGALRM, alarm)
                timer["armed"] = True
                signal.setitimer(signal.ITIMER_REAL, timeout, 1.0)
                with warnings.catch_warnings(record=True) as said:    # pytest records them: say them as Python does
                    warnings.resetwarnings()
                    for action, category, module in reversed(_FRESH_WARNING_FILTERS):
                        warnings.filterwarnings(action, category=category, module=module)
                    try:
                        main()
                    finally:
                        timer["armed"] = False
                        signal.setitimer(signal.ITIMER_REAL, 0)
                        for w in said:
                            stderr.write(warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line))
            except SystemExit as exc:
                if exc.code is None or isinstance(exc.code, int):
                    code = exc.code or 0
                else:                                   # sys.exit("message"): printed, exit code 1
                    print(exc.code, file=stderr)
                    code = 1
            except _TimedOut:
                pass
            except BaseException:                       # what the interpreter does with an uncaught exception
                traceback.print_exc(file=stderr)
                code = 1
            for stream in (sys.stdout, sys.stderr, stdout, stderr):
                with contextlib.suppress(Exception):
                    stream.flush()
            for k, f in enumerate((out, err)):
                f.seek(0)
                texts[k] = f.read().decode("utf-8", errors="replace")
    finally:
        timer["armed"] = False
        signal.setitimer(signal.ITIMER_REAL, 0)
        for fd, saved in zip((1, 2), saved_fds):
            os.dup2(saved, fd)
            os.close(saved)
        sys.stdout, sys.stderr, sys.argv = saved_streams
        os.chdir(here)
        interrupt.uninstall()                   # a signal noted by the run is the run's, not the next test's
        for sig, handler in saved_handlers.items():
            signal.signal(sig, handler)
    if timer["fired"]:
        raise subprocess.TimeoutExpired(["agrisynth", *args], timeout, *texts)
    return subprocess.CompletedProcess(["agrisynth", *args], code, *texts)


def spec_with(tmp_path, source, replacements: list[tuple[str, str]], name: str = "spec.toml"):
    """A copy of the spec file ``source`` with each (old, new) replaced once (old must be there)."""
    text = source.read_text()
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / name
    path.write_text(text)
    return path


def strict_json(path) -> dict:
    """result.json parsed with NaN and Infinity refused (the contract: never a non-finite number)."""
    import json

    def refuse(constant):
        raise AssertionError(f"{path}: {constant} in result.json")
    return json.loads(path.read_text(), parse_constant=refuse)


def modules_after_runs(tmp_path, runs: list[list[str]]) -> list[str]:
    """The modules one process has imported after the CLI commands ``runs`` (each a list of arguments),
    for the tests that a run builds only what its scene needs."""
    import json
    import subprocess
    import sys

    out = tmp_path / "modules.json"
    script = ("import json, sys\n"
              "from synthesis.cli import cli\n"
              f"for args in {runs!r}:\n"
              "    try:\n"
              "        cli.main(args, standalone_mode=False)\n"
              "    except SystemExit:\n"
              "        pass\n"
              f"open({str(out)!r}, 'w').write(json.dumps(sorted(sys.modules)))\n")
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(out.read_text())


def interrupted_auto_run(kind, loaded, *, after_told: int | None = None):
    """``--starts auto`` (min_converged 20: the toy goes on to batch 32) stopped by a SIGINT in its second batch: as
    the batch begins (``after_told`` None, the handler raising as it would) or once ``after_told`` starts of the run
    have been told to the progress.  Returns (the :class:`Interrupted` raised, the starts told in order)."""
    import signal

    import pytest

    from synthesis.core import interrupt
    from synthesis.core.interrupt import Interrupted
    from synthesis.core.solve import AutoStarts, run_solve as run_core

    batches: list[int] = []
    told: list[int] = []

    def on_batch(total, nested):
        batches.append(total)
        if total == 32 and after_told is None:
            interrupt.simulate(signal.SIGINT)
            raise KeyboardInterrupt

    def on_start(report, best):
        told.append(report.outcome.start)
        if batches == [16, 32] and len(told) == after_told:
            interrupt.simulate(signal.SIGINT)
    try:
        with pytest.raises(Interrupted) as caught:
            run_core(kind, loaded, workers=1, auto=AutoStarts(min_converged=20), on_start=on_start,
                     on_batch=on_batch)
    finally:
        interrupt.uninstall()
    return caught.value, told
