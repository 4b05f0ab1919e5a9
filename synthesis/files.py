"""Reading files a user names (spec files, result files) without ever hanging or exhausting memory."""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any


def shown(value: Any, width: int = 60) -> str:
    """``repr(value)`` cut to ``width`` characters (a message never echoes a huge input back)."""
    text = repr(value)
    return text if len(text) <= width else text[:width - 3] + "..."


def read_regular(path: Path, limit: int, what: str, error: type[Exception]) -> bytes:
    """The bytes of ``path`` if it is a regular file of at most ``limit`` bytes (never opens a FIFO or a
    device, which could block or never end); ``error`` (one line) otherwise."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except OSError as exc:
        raise error(f"{path}: cannot read ({exc.strerror})") from None
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{path}: is a folder, not a {what}")
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{path}: not a regular file (a pipe, socket or device cannot be a {what})")
    if st.st_size > limit:
        raise error(f"{path}: {st.st_size} bytes is larger than a {what} may be ({limit} bytes)")
    try:
        with open(path, "rb") as fh:
            raw = fh.read(limit + 1)
    except OSError as exc:
        raise error(f"{path}: cannot read ({exc.strerror})") from None
    if len(raw) > limit:
        raise error(f"{path}: larger than a {what} may be ({limit} bytes)")
    return raw
