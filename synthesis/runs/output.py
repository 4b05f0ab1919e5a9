"""A run's folder from opening to written, in one place: opened before any work (a folder that must be kept is
refused, exit 2, before anything runs), the result and its artifacts written atomically into it under the
deferral that keeps a finished answer (docs/ARCHITECTURE.md, "Run folders" and "Interrupts"), discarded when the
run ends any other way.  Every command's folder goes through it (check, solve, tolerance, bench, compare), and it
writes through the one writer of run folders, :meth:`synthesis.result.RunFolder.fill`, which the bench's and the
report's own ``write_bench`` and ``write_comparison`` use as well."""

from __future__ import annotations

import contextlib
import signal
from pathlib import Path
from typing import Callable

from synthesis.core import interrupt
from synthesis.errors import OutputError
from synthesis.report import run_artifacts
from synthesis.result import RunFolder, atomic_write_text, open_run_folder, write_run
from synthesis.runs.events import ResultWritten, SignalAfterResult, Subscriber


def text_file(text: str):
    """An artifact writer of a text file (ipopt.log, warnings.log, solved.toml)."""
    return lambda path: atomic_write_text(path, text)


class RunOutput:
    """``with RunOutput(out, name, ...) as output:`` the run's staging folder, discarded unless :meth:`write` put
    the result in place (an OutputError keeps it: the message names where the run is kept)."""

    def __init__(self, out: Path, name: str, *, force: bool = False, spec: Path | None = None, suffix: str = "",
                 replaceable: Path | None = None, resumed_from: Path | None = None):
        self.out = Path(out)
        self.folder = open_run_folder(self.out, name, force=force, spec=spec, suffix=suffix, replaceable=replaceable,
                                      resumed_from=resumed_from)
        self.written = False

    @classmethod
    def around(cls, folder: RunFolder) -> RunOutput:
        """The output of a folder opened already (compare's: ``--out`` names the folder itself)."""
        output = cls.__new__(cls)
        output.out, output.folder, output.written = folder.final.parent, folder, False
        return output

    def __enter__(self) -> "RunOutput":
        return self

    def __exit__(self, kind, exc, tb) -> None:
        if exc is not None and not self.written and not isinstance(exc, OutputError):
            self.folder.discard()

    @property
    def staging(self) -> Path:
        return self.folder.staging

    def write(self, result, files: dict, *, given_rules=None, figures: bool = True) -> tuple[Path, bool]:
        """result.json, ``files`` (name: writer), the kind's figures (unless ``figures`` is False) and report.html,
        moved into place; returns (folder, replaced an earlier run)."""
        artifacts = run_artifacts(result, files, given_rules=given_rules, figures=figures)
        folder, replaced = write_run(self.out, result, artifacts, folder=self.folder)
        self.written = True
        return folder, replaced

    def fill(self, write: Callable[[Path], None]) -> tuple[Path, bool]:
        """``write(staging)`` puts the run's files in the staging folder, then moved into place; returns (folder,
        replaced an earlier run)."""
        replaced = self.folder.fill(write)
        self.written = True
        return self.folder.final, replaced

    def write_files(self, files: dict[str, Callable[[Path], None]]) -> tuple[Path, bool]:
        """``files`` (name: writer), moved into place; returns (folder, replaced an earlier run)."""
        return self.fill(lambda staging: self.folder.write(files))

    @contextlib.contextmanager
    def finishing(self, emit: Subscriber):
        """The block that writes a complete result and hands over :class:`ResultWritten`: a signal inside it is noted,
        not obeyed (the exit code stays the result's), and told once the block ends (:class:`SignalAfterResult`)."""
        try:
            with interrupt.deferred(reraise=False):
                yield
        finally:
            signum = interrupt.pending()
            if signum is not None and self.written:
                emit(SignalAfterResult(signal.Signals(signum).name, self.folder.final))

    def finish(self, emit: Subscriber, result, files: dict, *, given_rules=None, details=None) -> tuple[Path, bool]:
        """:meth:`write` then ``emit(ResultWritten)``, the caller being inside :meth:`finishing`."""
        folder, replaced = self.write(result, files, given_rules=given_rules)
        emit(ResultWritten(result, folder, replaced, details))
        return folder, replaced
