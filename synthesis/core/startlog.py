"""``starts.jsonl``: every finished start of a solve, one JSON line each, appended and flushed as it finishes.

The first line is a header naming the run (kind, name, sha256 of the spec file, starts, seed, agrisynth
version) and their ``fingerprint``; ``agrisynth solve SPEC --resume RUN_DIR`` reads the starts back only
when the fingerprint of the new run is the same, and solves only the starts that are not there.  A
start's line holds its whole outcome (design, objective, IPOPT's status, log and decision vector), every
float exactly (JSON numbers round-trip), so the resumed run re-checks and chooses exactly as the
uninterrupted one would.  JSON has no NaN or infinity: such a float is written as ``{"$f": "nan"}``.
A line that cannot be read (cut off by a crash) is skipped: that start is solved again.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path
from typing import Any, Iterator, NamedTuple

import numpy as np

from synthesis import __version__
from synthesis.core.ipopt import NLPOutcome
from synthesis.core.outcome import StartOutcome
from synthesis.errors import OutputError
from synthesis.files import open_regular, parse_json

FILENAME = "starts.jsonl"
FORMAT = 1
#: a starts.jsonl larger than this is refused rather than read
MAX_BYTES = 2 * 1024**3
#: a line longer than this is not read (its start is solved again): a start's line holds its IPOPT log and
#: decision vector, tens of kilobytes
MAX_LINE_BYTES = 64 * 1024**2


#: a ``--starts auto`` run's line before each batch's starts: ``{"auto_batch": total}`` (those starts are of a run of
#: that many; a resumed run reads the last batch's only) or, in a kind's own order, ``{"auto_batch": total, "nested":
#: true}`` (start i is the same in every batch, so a resumed run keeps the earlier batches' starts too)
BATCH = "auto_batch"


def fingerprint(kind: str, name: str, spec_sha256: str, starts: int, seed: int,
                auto: dict | None = None) -> tuple[dict, str]:
    """The settings that decide a run's starts, and their sha256 (what --resume must match); ``auto``: a
    ``--starts auto`` run's settings (``starts`` then its most starts)."""
    settings = {"kind": kind, "name": name, "spec_sha256": spec_sha256, "starts": int(starts), "seed": int(seed),
                "agrisynth": __version__, **({} if auto is None else {"starts_auto": auto})}
    return settings, hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()


def _enc(v: Any) -> Any:
    if isinstance(v, (bool, str)) or v is None:
        return v
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else {"$f": repr(v)}
    if isinstance(v, np.ndarray):
        return {"$a": [_enc(x) for x in v.ravel().tolist()], "dtype": str(v.dtype), "shape": list(v.shape)}
    if isinstance(v, tuple):
        return {"$t": [_enc(x) for x in v]}
    if isinstance(v, list):
        return [_enc(x) for x in v]
    if isinstance(v, dict):
        if not all(isinstance(k, str) for k in v):
            raise TypeError("a dict with keys that are not strings")
        return {k: _enc(x) for k, x in v.items()}
    if isinstance(v, NLPOutcome):
        return {"$nlp": {k: _enc(getattr(v, k)) for k in ("start", "x", "objective", "return_status", "success",
                                                          "iterations", "wall_s", "lam_g", "p")}}
    raise TypeError(f"cannot record a {type(v).__name__}")


def _dec(v: Any) -> Any:
    if isinstance(v, list):
        return [_dec(x) for x in v]
    if not isinstance(v, dict):
        return v
    if len(v) == 1 and "$f" in v:
        return float(v["$f"])
    if "$a" in v and set(v) == {"$a", "dtype", "shape"}:
        return np.array([_dec(x) for x in v["$a"]], dtype=v["dtype"]).reshape(v["shape"])
    if len(v) == 1 and "$t" in v:
        return tuple(_dec(x) for x in v["$t"])
    if len(v) == 1 and "$nlp" in v:
        return NLPOutcome(**{k: _dec(x) for k, x in v["$nlp"].items()}, log="")
    return {k: _dec(x) for k, x in v.items()}


def encode(outcome: Any) -> dict:
    """A start's outcome as a JSON-able dict (TypeError when it holds something JSON cannot)."""
    if not isinstance(outcome, StartOutcome):
        raise TypeError(f"cannot record a {type(outcome).__name__}")
    fields = ("start", "design", "objective", "return_status", "success", "iterations", "wall_s", "log", "raw",
              "details")
    return {"outcome": {k: _enc(getattr(outcome, k)) for k in fields}}


#: what each field of a recorded outcome must be: a line that says otherwise was not written by agrisynth (or was
#: damaged since), and its start is solved again rather than carried into the result
_FIELD_TYPES: dict[str, tuple] = {"start": (int,), "design": (dict,), "objective": (int, float),
                                  "return_status": (str,), "success": (bool,), "iterations": (int,),
                                  "wall_s": (int, float), "log": (str,), "raw": (NLPOutcome, type(None)),
                                  "details": (dict,)}


def decode(line: dict) -> StartOutcome:
    """The outcome a line records; TypeError (the line is skipped, its start solved again) when it is not one."""
    recorded = line["outcome"]
    if not isinstance(recorded, dict):
        raise TypeError("an outcome that is not a table")
    fields = {k: _dec(v) for k, v in recorded.items()}
    for name, types in _FIELD_TYPES.items():
        value = fields.get(name)
        if name in fields and (not isinstance(value, types) or isinstance(value, bool) and bool not in types):
            raise TypeError(f"field {name} is a {type(value).__name__}")
    if fields.get("start", -1) < 0 or not all(isinstance(k, str) for k in fields.get("design", {})):
        raise TypeError("a negative start or a design not keyed by name")
    out = StartOutcome(**fields)
    if out.raw is not None:
        out.raw.log = out.log
    return out


class StartLog:
    """Appends one line per finished start to ``path`` (flushed at once), after a header line."""

    def __init__(self, path: Path, settings: dict, print_: str):
        self.path = path
        #: the starts appended since the last batch mark (an auto run's batch in progress)
        self.since_batch = 0
        self.fh = open(path, "a", encoding="utf-8")
        self._line({"agrisynth_starts": FORMAT, "fingerprint": print_, "settings": settings})

    def _line(self, data: dict) -> None:
        self.fh.write(json.dumps(data, allow_nan=False, separators=(",", ":")) + "\n")
        self.fh.flush()

    def append(self, outcome: Any) -> None:
        try:
            data = encode(outcome)
            json.dumps(data, allow_nan=False)
        except (TypeError, ValueError) as exc:        # kept as a note; a resumed run solves this start again
            data = {"unrecorded": getattr(outcome, "start", None), "why": str(exc)}
        self._line(data)
        self.since_batch += 1

    def batch(self, total: int, nested: bool = False) -> None:
        """A ``--starts auto`` run begins its batch of ``total`` starts (``nested``: in the kind's own order)."""
        self._line({BATCH: int(total), "nested": True} if nested else {BATCH: int(total)})
        self.since_batch = 0

    def close(self) -> None:
        self.fh.close()


def settings_of(folder: Path) -> dict:
    """The settings in the header line of ``folder/starts.jsonl`` ({} when there is none to read)."""
    path = Path(folder) / FILENAME
    try:
        with open_regular(path, MAX_BYTES, FILENAME, OutputError) as fh:
            line = parse_json(fh.readline(MAX_LINE_BYTES), path, OutputError)
    except (OSError, OutputError):
        return {}
    settings = line.get("settings") if isinstance(line, dict) else None
    return settings if isinstance(settings, dict) else {}


def _lines(fh) -> Iterator[bytes | None]:
    """The lines of ``fh``, None for one longer than MAX_LINE_BYTES (read past, never held whole)."""
    while True:
        line = fh.readline(MAX_LINE_BYTES + 1)
        if not line:
            return
        if len(line) <= MAX_LINE_BYTES or line.endswith(b"\n"):
            yield line
            continue
        while line and not line.endswith(b"\n"):      # the rest of an over-long line
            line = fh.readline(MAX_LINE_BYTES)
        yield None


class Resumed(NamedTuple):
    """What a ``--resume`` reads of an interrupted run's starts.jsonl, in one pass."""

    #: the finished starts of the batch it was solving (a fixed run's: all of them)
    finished: dict[int, StartOutcome]
    #: a ``--starts auto`` run's batch it was solving and whether it was nested (its last ``auto_batch`` line; None:
    #: none there)
    last_batch: tuple[int, bool] | None
    #: its *finished* batches before that one, in order: (each one's total, its starts), when the batches are not
    #: nested (a nested run's log keeps every batch's starts in the last one's); empty otherwise.  A resumed run counts
    #: them again as the interrupted run had: its answer is never worse than a finished batch's, and the result an
    #: interrupt leaves is the best of them and the batch in progress
    previous: list[tuple[int, dict[int, StartOutcome]]]


def read(folder: Path, print_: str) -> dict[int, StartOutcome]:
    """The finished starts recorded in ``folder/starts.jsonl`` of a run with fingerprint ``print_``.

    OutputError (exit 2) when there is no such file or it belongs to a run with other settings."""
    return read_resumed(folder, print_).finished


def read_resumed(folder: Path, print_: str) -> Resumed:
    """:func:`read`'s starts, and the batch marks around them (:class:`Resumed`)."""
    path = Path(folder) / FILENAME
    if not os.path.lexists(path):
        raise OutputError(f"--resume {folder}: no {FILENAME} there (not a solve run folder)")
    finished: dict[int, StartOutcome] = {}
    mark: tuple[int, bool] | None = None      # the batch being read (an auto run's), and the one before it
    previous: list[tuple[int, dict[int, StartOutcome]]] = []
    with open_regular(path, MAX_BYTES, FILENAME, OutputError) as fh:
        header = None
        for text in _lines(fh):
            try:
                line = None if text is None else parse_json(text, path, OutputError)
            except OutputError:
                line = None
            if not isinstance(line, dict):
                continue          # cut off by a crash (or not a start's line): that start is solved again
            if "agrisynth_starts" in line:
                if header is None:
                    header = line
                if line.get("fingerprint") != print_:
                    given = line.get("settings")
                    settings = given if isinstance(given, dict) else {}
                    mine = ", ".join(f"{k} {v}" for k, v in sorted(settings.items()) if k != "spec_sha256")
                    raise OutputError(f"--resume {folder}: that run had other settings or another spec file "
                                      f"({mine or 'unknown'}; spec sha256 {str(settings.get('spec_sha256'))[:12]}); "
                                      f"resume with the same spec file, --starts and --seed")
                continue
            if header is None:
                raise OutputError(f"--resume {folder}: {FILENAME} has no header line; not written by agrisynth")
            if BATCH in line:             # an auto run's next batch: its starts are another run's ...
                if not line.get("nested"):
                    # a batch is begun only when the one before has finished without stopping the run
                    if mark is not None and finished:
                        previous.append((mark[0], dict(finished)))
                    finished.clear()
                mark = (line[BATCH], line.get("nested") is True) if isinstance(line.get(BATCH), int) else None
                continue                  # ... unless nested: start i is the same in every batch
            if "outcome" in line:
                try:
                    out = decode(line)
                except (TypeError, ValueError, KeyError, AttributeError):
                    continue
                finished[out.start] = out
    if header is None:
        raise OutputError(f"--resume {folder}: {FILENAME} is empty")
    return Resumed(finished, mark, previous)
