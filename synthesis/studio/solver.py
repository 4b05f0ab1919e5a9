"""Solve from here: the solve run on the page's values, in a worker process, one at a time, cancellable.

The values are written as a spec (the spec file with each free variable's start value set to them, so
they are start 0) into the studio's folder, and the worker (:mod:`.worker`) runs :func:`synthesis.runs.solve` on
it there, as ``agrisynth solve`` does: the same multistart, the same run folder (result.json, report, solved.toml,
ipopt.log).  Progress is the run's events, sent by the worker as JSON lines on its standard output (nothing
printed is parsed); cancelling sends SIGTERM, which the run answers by keeping the finished starts (exit 143); a worker
still alive GRACE seconds later is killed (SIGKILL).  The worker runs in its own process group, so the
studio, not the terminal, decides when it stops (Ctrl-C, SIGTERM or SIGHUP to the studio cancel it the
same way, unless the studio was started with that signal ignored, as nohup does SIGHUP) and the kill reaches
anything it started.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from synthesis.library import IMPORT_ROOT
from synthesis.result import load_result
from synthesis.studio.session import finite

#: exit codes of `agrisynth solve` (docs/ARCHITECTURE.md, "Exit codes") in words
EXITS = {0: "every rule satisfied", 1: "solved, some rule violated", 2: "bad input", 3: "infeasible or failed",
         130: "interrupted", 143: "cancelled (the finished starts are kept)"}
#: last lines of the solve's output kept for the page
TAIL = 12
#: the most starts a solve from the page runs: its starts box's cap, and an auto solve's budget
PAGE_MAX_STARTS = 256
#: seconds a cancelled worker has to write its finished starts before it is killed
GRACE = 10.0


def worker_env() -> dict[str, str]:
    """The environment of the worker: this one, with the folder this studio's ``synthesis`` was imported from
    first on PYTHONPATH, so the worker imports the same one whatever its working directory (the studio's folder)
    and however the studio found it (a relative PYTHONPATH, say)."""
    given = os.environ.get("PYTHONPATH", "")
    return dict(os.environ, PYTHONPATH=os.pathsep.join([str(IMPORT_ROOT)] + ([given] if given else [])))


@dataclass
class SolveJob:
    """One solve run in its own process (:mod:`.worker`)."""

    run_name: str
    spec_file: Path
    out: Path
    starts: int | str                   # a count, or "auto" (the run says its batches' totals as they begin)
    process: subprocess.Popen | None = None
    done: int = 0
    total: int = 0
    lines: list[str] = field(default_factory=list)
    error: str | None = None            # the run's own word on why it failed (bad input, infeasible)
    stderr: list[str] = field(default_factory=list)     # the last lines the worker wrote to its standard error
    exit_code: int | None = None
    cancelled: bool = False
    killed: bool = False
    grace: float = GRACE
    _reader: threading.Thread | None = None

    def start(self) -> None:
        cmd = [sys.executable, "-m", "synthesis.studio.worker", str(self.spec_file), str(self.out), str(self.starts)]
        self.total = self.starts if isinstance(self.starts, int) else 0
        # its own session (so its own process group): a Ctrl-C in the studio's terminal reaches the studio only,
        # which then cancels the worker, and the group can be killed as a whole
        self.process = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                        env=worker_env(), cwd=self.out, start_new_session=True)
        errors = threading.Thread(target=self._read_errors, daemon=True)
        errors.start()
        self._reader = threading.Thread(target=self._read, args=(errors,), daemon=True)
        self._reader.start()

    def _read(self, errors: threading.Thread) -> None:
        """The worker's events (one JSON object a line), until it ends; then its exit code."""
        assert self.process is not None and self.process.stdout is not None
        for text in self.process.stdout:
            try:
                event = json.loads(text)
            except ValueError:       # the channel is the worker's alone; a torn last line (a kill) is no event
                continue
            self.done, self.total = event.get("done", self.done), event.get("total", self.total)
            self.error = event.get("error", self.error)
            if event.get("line"):
                self.lines = (self.lines + [event["line"]])[-TAIL:]
        errors.join()
        self.exit_code = self.process.wait()

    def _read_errors(self) -> None:
        assert self.process is not None and self.process.stderr is not None
        for line in self.process.stderr:
            if line.strip():
                self.stderr = (self.stderr + [line.rstrip()])[-TAIL:]

    @property
    def running(self) -> bool:
        return self.exit_code is None

    def _signal_group(self, sig: int) -> None:
        assert self.process is not None
        try:
            os.killpg(self.process.pid, sig)
        except ProcessLookupError:         # already gone
            pass

    def cancel(self, grace: float = GRACE) -> None:
        """Ask the worker to stop (SIGTERM: it keeps its finished starts) and return at once; the worker's
        process group is killed if it is still alive ``grace`` seconds later."""
        if self.process is None or not self.running or self.cancelled:
            return
        self.cancelled, self.grace = True, grace
        self._signal_group(signal.SIGTERM)
        threading.Thread(target=self._kill_after, daemon=True).start()

    def _kill_after(self) -> None:
        self.wait(self.grace)
        if self.running:
            self.killed = True
            self._signal_group(signal.SIGKILL)

    def wait(self, timeout: float | None = None) -> None:
        if self._reader is not None:
            self._reader.join(timeout)

    def result(self) -> dict[str, Any] | None:
        """The run's result.json, once written (a cancelled run keeps its finished starts' best)."""
        path = self.out / self.run_name / "result.json"
        if self.running or not path.is_file():
            return None
        return load_result(path).to_json()

    def _exit_words(self, result: dict[str, Any] | None) -> str:
        """How the worker ended, in words the page shows as they are: the exit code in its documented meaning only
        when the run wrote its result (a crash exits 1 too)."""
        if self.exit_code is None:
            return ""
        if result is not None:
            return f"exit {self.exit_code}: {EXITS.get(self.exit_code, 'not an exit code of agrisynth solve')}"
        if self.killed:
            return f"killed after {self.grace:g} s of not stopping (nothing kept)"
        if self.cancelled and self.exit_code in (143, -signal.SIGTERM):    # -15: ended before solve set its handler
            return "cancelled before any start finished (nothing kept)"
        last = self.error or (self.stderr or self.lines or ["no output"])[-1]
        return f"failed (exit {self.exit_code}): {last[:200]}"

    def status(self) -> dict[str, Any]:
        if self.running:
            state = "cancelling" if self.cancelled else "running"
        else:
            state = "cancelled" if self.cancelled else "finished"
        result = self.result()
        if state == "finished" and result is None:
            state = "failed"
        out: dict[str, Any] = {"state": state, "run": self.run_name, "done": self.done, "total": self.total,
                               "lines": self.lines, "exit_code": self.exit_code, "exit": self._exit_words(result)}
        if result is not None:
            out.update(status=result["status"], design=result["design"], objective=result.get("objective"),
                       folder=self.run_name)
        return finite(out)
