"""A run's figures drawn side by side: one group of writers per core, each group in a process forked from this one.

A check or solve draws five to eight files from the result alone; one of them, the animation, takes as long as the
rest together.  Drawn one after another they are most of a check's wall time.  A forked process starts with this
process's imports (matplotlib is loaded once) and the result in memory, so nothing is pickled or imported again:
each group writes its files into the run's folder and sends back, per file, whether it was written and what the
libraries said while drawing it.  This process draws the last group itself.  Where the platform cannot fork, or
one core is all there is, the writers run here in order; the files and notes are the same either way.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from synthesis.core.library_log import captured_warnings

#: the files that take about as long as all others together: each gets a group of its own
SLOW_SUFFIXES = (".gif",)


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


def groups(names: list[str], cores: int) -> list[list[str]]:
    """The writers split into at most ``cores`` groups: each slow file alone, the rest dealt round the others (or,
    with no group left for them, into the slow ones' groups)."""
    if cores <= 1:
        return [list(names)] if names else []
    slow = [n for n in names if n.endswith(SLOW_SUFFIXES)]
    rest = [n for n in names if n not in slow]
    out: list[list[str]] = [[n] for n in slow[:cores - 1]]
    for n in slow[len(out):]:            # more slow files than cores but one: the last slow group takes them
        out[-1].append(n)
    spare = max(cores - len(out), 1 if rest else 0)
    shares: list[list[str]] = [[] for _ in range(spare)]
    for k, n in enumerate(rest):
        (shares[k % spare] if spare else out[k % len(out)]).append(n)
    return [g for g in out + shares if g]


def draw_all(writers: dict[str, Callable[[Path], None]], folder: Path, cores: int | None = None) -> list[Drawn]:
    """Run every writer on ``folder / name``; returns the outcomes in the writers' order."""
    names = list(writers)
    parts = groups(names, cores or _cores())
    forks = "fork" in multiprocessing.get_all_start_methods() and len(parts) > 1
    if not forks:
        return [_draw(n, writers[n], folder / n) for n in names]
    children = []
    try:
        for group in parts[:-1]:
            read, write = os.pipe()
            pid = os.fork()
            if pid == 0:                                    # the child: draw, report, leave without cleanup
                _child(group, writers, folder, read, write)
            os.close(write)
            children.append((pid, read, group))
        outcomes = {d.name: d for d in (_draw(n, writers[n], folder / n) for n in parts[-1])}
        for pid, read, group in children:
            outcomes.update(_collected(pid, read, group))
        children.clear()
    finally:
        for pid, read, _ in children:                       # an interrupt here: the children go with the run
            _end(pid, read)
    return [outcomes[n] for n in names]


def _child(group: list[str], writers: dict, folder: Path, read: int, write: int) -> None:
    code = 1
    try:
        os.close(read)
        # the run's process decides what a signal means; the child only ends with it
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        # plain JSON: what a file's drawing sent back is data, never code to run
        data = json.dumps([dataclasses.asdict(_draw(n, writers[n], folder / n)) for n in group]).encode()
        with os.fdopen(write, "wb") as pipe:
            pipe.write(data)
        code = 0
    finally:
        os._exit(code)          # never run the parent's exit handlers, atexit or finally blocks in the child


def _collected(pid: int, read: int, group: list[str]) -> dict[str, Drawn]:
    with os.fdopen(read, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    if data:
        return {d["name"]: Drawn(**d) for d in json.loads(data)}
    why = f"the drawing process ended ({_status_text(status)}) before it reported"
    return {n: Drawn(n, f"RuntimeError: {why}", "") for n in group}


def _status_text(status: int) -> str:
    if os.WIFSIGNALED(status):
        return f"signal {os.WTERMSIG(status)}"
    return f"exit code {os.WEXITSTATUS(status)}"


def _end(pid: int, read: int) -> None:
    try:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    except (ProcessLookupError, ChildProcessError):
        pass
    os.close(read)
