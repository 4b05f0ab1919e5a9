"""Reading files a user names (spec files, result files, run folders' markers and start logs) without ever hanging
or exhausting memory: every file agrisynth reads from a path it was given goes through :func:`open_regular`
(a regular file of bounded size, never a FIFO or a device), and every JSON one through :func:`parse_json`
(UTF-8, bounded nesting, finite numbers), each refusal one line naming the file.  :func:`loads` is that JSON
parser alone, for JSON that is no file (the studio's request bodies)."""

from __future__ import annotations

import contextlib
import json
import math
import os
import stat
from pathlib import Path
from typing import Any, BinaryIO, Iterator

#: JSON nested deeper than this is refused: agrisynth writes no file nested more than about ten levels, and
#: the readers of a parsed file (finite_only, the start log's decoder, the report) recurse over it
MAX_JSON_DEPTH = 64


def shown(value: Any, width: int = 60) -> str:
    """``repr(value)`` cut to ``width`` characters (a message never echoes a huge input back)."""
    text = repr(value)
    return text if len(text) <= width else text[:width - 3] + "..."


def _checked(path: Path, st: os.stat_result, limit: int, what: str, error: type[Exception]) -> None:
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{path}: is a folder, not a {what}")
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{path}: not a regular file (a pipe, socket or device cannot be a {what})")
    if st.st_size > limit:
        raise error(f"{path}: {st.st_size} bytes is larger than a {what} may be ({limit} bytes)")


@contextlib.contextmanager
def open_regular(path: Path, limit: int, what: str, error: type[Exception]) -> Iterator[BinaryIO]:
    """``path`` opened for reading (binary) if it is a regular file of at most ``limit`` bytes; ``error`` (one
    line) otherwise.  A FIFO or a device is never opened (it could block, never end, or act on being opened);
    the file is opened non-blocking and looked at again once open, so one swapped in between cannot block either."""
    try:
        _checked(path, os.stat(path), limit, what, error)
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except OSError as exc:
        raise error(f"{path}: cannot read ({exc.strerror})") from None
    try:
        _checked(path, os.fstat(fd), limit, what, error)
        os.set_blocking(fd, True)
        fh = os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
    with fh:
        yield fh


def read_regular(path: Path, limit: int, what: str, error: type[Exception]) -> bytes:
    """The bytes of ``path`` if it is a regular file of at most ``limit`` bytes (:func:`open_regular`); ``error``
    (one line) otherwise."""
    with open_regular(path, limit, what, error) as fh:
        try:
            raw = fh.read(limit + 1)
        except OSError as exc:
            raise error(f"{path}: cannot read ({exc.strerror})") from None
    if len(raw) > limit:
        raise error(f"{path}: larger than a {what} may be ({limit} bytes)")
    return raw


def _no_constant(name: str):
    raise ValueError(f"{name} is not a JSON number (JSON has no NaN or infinity)")


def _finite_float(text: str) -> float:
    """A JSON number as a float; one too large for a float (1e400 would read as infinity) is refused."""
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text[:40]} is too large a number (no float holds it)")
    return value


def _too_deep(data: Any, limit: int) -> bool:
    """Whether ``data`` (parsed JSON) nests lists and objects more than ``limit`` deep (iteratively: no recursion)."""
    stack = [(data, 0)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, (dict, list)):
            if depth >= limit:
                return True
            stack.extend((v, depth + 1) for v in (item.values() if isinstance(item, dict) else item))
    return False


def parse_json(raw: bytes, path: Path | str, error: type[Exception], name: str = "a file agrisynth wrote", *,
               hint: str = "", redo: str | None = None) -> Any:
    """The JSON value in ``raw`` (the bytes of ``path``), or ``error`` (one line naming ``path``): bytes that are
    not UTF-8, text that is not JSON (``hint`` added: what to give instead), JSON cut off or invalid (``redo``:
    what to do about it), nested deeper than :data:`MAX_JSON_DEPTH`, NaN, infinity, or a number no float holds.
    ``name``: what the file should have been ("a result.json")."""
    not_ours = f"not {name} agrisynth wrote"
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not a UTF-8 text file (byte {exc.start}); {not_ours}") from None
    try:
        return loads(text)
    except json.JSONDecodeError as exc:
        # a cut-off write leaves an object that opens and never closes; a file that does not even open one is not
        # JSON at all (a report.html, a spec): say so, not "truncated"
        if not text.lstrip().startswith(("{", "[")):
            raise error(f"{path}: not JSON, so not {name}{hint}") from None
        what = "truncated" if not text.rstrip().endswith(("}", "]")) else "not valid JSON"
        raise error(f"{path}: {what} ({exc.msg}: line {exc.lineno}, column {exc.colno}); "
                    f"{redo or not_ours}") from None
    except ValueError as exc:       # nested too deeply, NaN / Infinity, or an integer of thousands of digits
        what = "a number of thousands of digits" if "integer string conversion" in str(exc) else str(exc)[:120]
        raise error(f"{path}: {what}; {not_ours}") from None


def loads(text: str | bytes) -> Any:
    """``json.loads(text)`` refusing (ValueError, one line) what no agrisynth input holds: NaN and infinity, a number
    no float holds, nesting deeper than :data:`MAX_JSON_DEPTH` (or than the parser's recursion allows).  The one
    JSON parser of input: files (:func:`parse_json`) and the studio's request bodies."""
    try:
        data = json.loads(text, parse_constant=_no_constant, parse_float=_finite_float)
    except RecursionError:
        raise ValueError("nested too deeply") from None
    if _too_deep(data, MAX_JSON_DEPTH):
        raise ValueError(f"nested more than {MAX_JSON_DEPTH} levels deep")
    return data


def read_json(path: Path, limit: int, what: str, error: type[Exception], name: str = "a file agrisynth wrote", *,
              hint: str = "", redo: str | None = None) -> Any:
    """The JSON value in the file ``path``: :func:`read_regular` (``what``: the file's description in its
    refusals) then :func:`parse_json`."""
    return parse_json(read_regular(path, limit, what, error), path, error, name, hint=hint, redo=redo)
