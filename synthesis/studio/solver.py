"""Solve from here: ``agrisynth solve`` on the page's values, in a worker process, one at a time, cancellable.

The values are written as a spec (the spec file with each free variable's start value set to them, so
they are start 0) into the studio's folder, and ``agrisynth solve`` runs on it there, exactly as a
user would run it: the same multistart, the same run folder (result.json, report, solved.toml, ipopt.log).
Progress is read from the lines ``solve`` prints for each finished start when its output is piped;
cancelling sends SIGTERM, which ``solve`` answers by keeping the finished starts (exit 143).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from synthesis.studio.session import finite

#: "start 3 finished (2/16): ..." -- one line per finished start (synthesis.cli._start_line)
_PROGRESS = re.compile(r"^start (\d+) finished \((\d+)/(\d+)\)")
#: exit codes of `agrisynth solve` (DESIGN.md) in words
EXITS = {0: "every rule satisfied", 1: "solved, some rule violated", 2: "bad input", 3: "infeasible or failed",
         130: "interrupted", 143: "cancelled (the finished starts are kept)", -15: "cancelled before any start finished"}
#: last lines of the solve's output kept for the page
TAIL = 12


@dataclass
class SolveJob:
    """One `agrisynth solve` run in its own process."""

    run_name: str
    spec_file: Path
    out: Path
    starts: int
    process: subprocess.Popen | None = None
    done: int = 0
    total: int = 0
    lines: list[str] = field(default_factory=list)
    exit_code: int | None = None
    cancelled: bool = False
    _reader: threading.Thread | None = None

    def start(self) -> None:
        cmd = [sys.executable, "-m", "synthesis.cli", "solve", str(self.spec_file), "--out", str(self.out),
               "--starts", str(self.starts), "--workers", "1"]
        self.total = self.starts
        self.process = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                        env=dict(os.environ, COLUMNS="120"), cwd=self.out)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process is not None and self.process.stdout is not None
        for line in self.process.stdout:
            line = line.rstrip()
            match = _PROGRESS.match(line)
            if match:
                self.done, self.total = int(match.group(2)), int(match.group(3))
            if line.strip():
                self.lines = (self.lines + [line])[-TAIL:]
        self.exit_code = self.process.wait()

    @property
    def running(self) -> bool:
        return self.exit_code is None

    def cancel(self) -> None:
        if self.process is not None and self.running:
            self.cancelled = True
            self.process.terminate()

    def wait(self, timeout: float | None = None) -> None:
        if self._reader is not None:
            self._reader.join(timeout)

    def result(self) -> dict[str, Any] | None:
        """The run's result.json, once written (a cancelled run keeps its finished starts' best)."""
        path = self.out / self.run_name / "result.json"
        if self.running or not path.is_file():
            return None
        from synthesis.result import load_result

        return load_result(path).to_json()

    def status(self) -> dict[str, Any]:
        state = "running" if self.running else ("cancelled" if self.cancelled else "finished")
        out: dict[str, Any] = {"state": state, "run": self.run_name, "done": self.done, "total": self.total,
                               "lines": self.lines, "exit_code": self.exit_code,
                               "exit": EXITS.get(self.exit_code, "") if self.exit_code is not None else ""}
        result = self.result()
        if result is not None:
            out.update(status=result["status"], design=result["design"], objective=result.get("objective"),
                       folder=self.run_name)
        return finite(out)
