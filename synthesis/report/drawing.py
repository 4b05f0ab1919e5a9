"""A run's figures drawn side by side: one group of writers per core, each group in a process forked from this one.

A check or solve draws five to eight files from the result alone; one of them, an animation, takes two to three
times a still figure's time.  Drawn one after another they are most of a check's wall time; shared out by how long
each takes (:func:`groups`), the groups end about together.  A forked process starts with this process's imports
(matplotlib is loaded once) and the result in memory, so nothing is pickled or imported again: each group writes
its files into the run's folder and sends back, per file, whether it was written and what the libraries said while
drawing it.  This process draws the last group itself.  Where the platform cannot fork, or
one core is all there is, the writers run here in order; the files and notes are the same either way.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import json
import multiprocessing
import os
import signal
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from synthesis.core.library_log import captured_warnings

#: the files that take longest, an animation: each starts a group of its own, drawn in a forked process whenever
#: there are other files for this process to draw
SLOW_SUFFIXES = (".gif",)
#: how long a file takes to draw, by suffix, in still figures (planting's: an animation 0.5 s, a figure 0.15 to 0.35
#: s, the DXF 0.2 s with ezdxf's import); anything else (text: a log, a CSV) is nearly free
WEIGHTS = {".gif": 2.5, ".png": 1.0, ".svg": 1.0, ".pdf": 1.0, ".dxf": 1.0}
TEXT_WEIGHT = 0.05


@dataclass(frozen=True)
class Drawn:
    """One file's outcome: written, or why not (``error``: "TypeError: ..."), and what the libraries said."""

    name: str
    error: str | None
    said: str


def _draw(name: str, writer: Callable[[Path], None], path: Path) -> Drawn:
    try:
        with captured_warnings() as text:
            writer(path)
        return Drawn(name, None, text())
    except Exception as exc:    # noqa: BLE001 - reported on the page, the run's result is kept
        path.unlink(missing_ok=True)
        return Drawn(name, f"{type(exc).__name__}: {exc}", "")


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:          # not on every platform
        return os.cpu_count() or 1


def _weight(name: str) -> float:
    return WEIGHTS.get(Path(name).suffix.lower(), TEXT_WEIGHT)


def groups(names: list[str], cores: int) -> list[list[str]]:
    """The writers split into at most ``cores`` groups, the last one this process's: each slow file in a forked group
    of its own (with more slow files than cores but one, the last such group takes the rest of them); then the
    other files, heaviest first (:data:`WEIGHTS`), each to the group with the least to draw so far (the first of
    equals).  Within a group the files keep the writers' order."""
    if cores <= 1:
        return [list(names)] if names else []
    slow = [n for n in names if n.endswith(SLOW_SUFFIXES)]
    rest = [n for n in names if n not in slow]
    out: list[list[str]] = [[n] for n in slow[:cores - 1]]
    for n in slow[len(out):]:            # more slow files than cores but one: the last slow group takes them
        out[-1].append(n)
    out += [[] for _ in range(max(cores - len(out), 1 if rest else 0))]
    load = [sum(_weight(n) for n in group) for group in out]
    for n in sorted(rest, key=_weight, reverse=True):
        k = min(range(len(out)), key=load.__getitem__)
        out[k].append(n)
        load[k] += _weight(n)
    order = {n: i for i, n in enumerate(names)}
    return [sorted(g, key=order.__getitem__) for g in out if g]


def draw_all(writers: dict[str, Callable[[Path], None]], folder: Path, cores: int | None = None) -> list[Drawn]:
    """Run every writer on ``folder / name``; returns the outcomes in the writers' order.  A group whose process
    cannot be started (no process or pipe left) is drawn here, in turn."""
    names = list(writers)
    parts = groups(names, cores or _cores())
    outcomes: dict[str, Drawn] = {}
    children: list[_Child] = []
    try:
        if "fork" in multiprocessing.get_all_start_methods():
            for group in parts[:-1]:
                child = _Child.start(group, writers, folder)
                if child is None:
                    outcomes.update((n, _draw(n, writers[n], folder / n)) for n in group)
                else:
                    children.append(child)
        else:
            parts = [names]
        outcomes.update((n, _draw(n, writers[n], folder / n)) for n in parts[-1])
        while children:
            outcomes.update(children.pop(0).collect(folder))
    finally:
        for child in children:                  # an interrupt or error here: the drawing ends with the run
            child.end()
    return [outcomes[n] for n in names]


class _Child:
    """A forked process drawing one group: it sends one JSON line per file as it finishes it."""

    def __init__(self, pid: int, read: int, group: list[str]):
        self.pid, self.read, self.group = pid, read, group

    @classmethod
    def start(cls, group: list[str], writers: dict, folder: Path) -> "_Child | None":
        """The group's drawing process, or None when none can be started (the caller draws the group itself)."""
        try:
            read, write = os.pipe()
        except OSError:
            return None
        try:
            pid = os.fork()
        except OSError:
            os.close(read)
            os.close(write)
            return None
        if pid == 0:                                        # the child: draw, report, leave without cleanup
            _child(group, writers, folder, read, write)
        os.close(write)
        return cls(pid, read, group)

    def collect(self, folder: Path) -> dict[str, Drawn]:
        """Each file's outcome as the process reported it; a file it never reported (it died first) is named with
        why, and whatever it left of that file is removed."""
        try:
            with os.fdopen(self.read, "rb") as pipe:
                data = pipe.read()
        finally:
            self.read = -1
            _, status = os.waitpid(self.pid, 0)
            self.pid = -1
        out: dict[str, Drawn] = {}
        for line in data.decode(errors="replace").splitlines():
            try:
                drawn = Drawn(**json.loads(line))
            except (ValueError, TypeError):     # a line cut short as the process died: that file is not reported
                continue
            if drawn.name in self.group:
                out[drawn.name] = drawn
        why = f"RuntimeError: the drawing process ended ({_status_text(status)}) before it reported"
        for name in self.group:
            if name not in out:
                (folder / name).unlink(missing_ok=True)
                for left in folder.glob(f".{name}.*"):      # an atomic write's temporary file
                    left.unlink(missing_ok=True)
                out[name] = Drawn(name, why, "")
        return out

    def end(self) -> None:
        """Kill and reap the process (still running: the run is being interrupted) and close its pipe."""
        if self.pid > 0:
            with contextlib.suppress(OSError):
                os.kill(self.pid, signal.SIGKILL)
            with contextlib.suppress(OSError):
                os.waitpid(self.pid, 0)
        if self.read >= 0:
            with contextlib.suppress(OSError):
                os.close(self.read)


def _child(group: list[str], writers: dict, folder: Path, read: int, write: int) -> None:
    code = 1
    try:
        os.close(read)
        # the run's process decides what a signal means: the child ignores both and ends only with it
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        _die_with_parent()
        with os.fdopen(write, "wb") as pipe:
            for name in group:
                # plain JSON, a line per file as it is done: what a drawing sent back is data, never code to run
                pipe.write(json.dumps(dataclasses.asdict(_draw(name, writers[name], folder / name))).encode() + b"\n")
                pipe.flush()
        code = 0
    finally:
        os._exit(code)          # never run the parent's exit handlers, atexit or finally blocks in the child


def _die_with_parent() -> None:
    """Linux's PR_SET_PDEATHSIG: the kernel kills this process when the run's process dies (even by SIGKILL), so no
    drawing goes on writing into a run that no longer exists; elsewhere the run's interrupt kills it."""
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)     # PR_SET_PDEATHSIG = 1


def _status_text(status: int) -> str:
    if os.WIFSIGNALED(status):
        return f"signal {os.WTERMSIG(status)}"
    return f"exit code {os.WEXITSTATUS(status)}"
