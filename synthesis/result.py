"""The Result of a run, its JSON form (DESIGN.md contract) and the atomic writing of a run folder."""

from __future__ import annotations

import json
import os
import platform
import shutil
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable

from synthesis.errors import ResultError

STATUSES = ("optimal", "feasible", "infeasible", "failed", "evaluated")
#: version of the result.json layout; readers refuse a newer one rather than misread it
SCHEMA_VERSION = 2
#: version 2 moved the kind's own facts under "facts" and gave every solve the same tail:
#: "starts", "elastic", "baseline_design", "fine_grid_worst_violation" (version 1 had them all at the
#: top level, mixed with the kind's facts); version 1 files are still read
RUN_KEYS = ("starts", "elastic", "baseline_design", "fine_grid_worst_violation")


def versions() -> dict[str, str]:
    import casadi

    from synthesis import __version__

    return {"agrisynth": __version__, "casadi": casadi.__version__, "python": platform.python_version()}


@dataclass
class Result:
    kind: str
    name: str
    spec_sha256: str
    status: str
    design: dict[str, float]
    rules: list[dict[str, Any]]
    objective: dict[str, Any] | None = None
    trajectory: dict[str, Any] | None = None
    solver: dict[str, Any] | None = None
    versions: dict[str, str] = field(default_factory=versions)
    starts: list[dict[str, Any]] | None = None           # solve: one row per start (core.solve.starts_table)
    elastic: dict[str, Any] | None = None                # solve: the elastic diagnosis when no start satisfied every rule
    baseline_design: dict[str, Any] | None = None        # solve: the spec's given design
    fine_grid_worst_violation: float | None = None       # solve: of the returned design
    extra: dict[str, Any] = field(default_factory=dict)   # the kind's facts (precision points, ...): "facts"

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"status {self.status!r} is not one of {STATUSES}")

    @property
    def all_satisfied(self) -> bool:
        return all(r["satisfied"] for r in self.rules)

    def violated(self) -> list[dict[str, Any]]:
        return [r for r in self.rules if not r["satisfied"]]

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        if data["objective"] is None:
            del data["objective"]
        if data["solver"] is None:
            del data["solver"]
        if data["trajectory"] is None:
            del data["trajectory"]
        for key in RUN_KEYS:
            if data[key] is None and self.solver is None:      # a check has no run tail
                del data[key]
        data["facts"] = data.pop("extra")
        data["schema_version"] = SCHEMA_VERSION
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "Result":
        known = {"kind", "name", "spec_sha256", "status", "design", "rules", "objective", "trajectory",
                 "solver", "versions"}
        args = {k: data[k] for k in (*known, *RUN_KEYS) if k in data}
        if data.get("schema_version", 1) >= 2:
            args["extra"] = dict(data.get("facts") or {})
        else:       # version 1: the kind's facts and the run's tail side by side at the top level
            args["extra"] = {k: v for k, v in data.items()
                             if k not in known and k not in RUN_KEYS and k != "schema_version"}
        return cls(**args)


REQUIRED_KEYS = ("kind", "name", "spec_sha256", "status", "design", "rules")


def load_result(path: str | Path) -> Result:
    """Read a run folder's result.json (or the file itself); ResultError (exit 2) says what is wrong."""
    path = Path(path)
    if path.is_dir():
        path = path / "result.json"
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise ResultError(f"{path}: no such result file (give a run folder or its result.json)") from None
    except OSError as exc:
        raise ResultError(f"{path}: cannot read: {exc.strerror}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        # a cut-off write leaves an object that never closes; anything else is plain bad JSON
        what = "truncated" if not text.rstrip().endswith(("}", "]")) else "not valid JSON"
        raise ResultError(f"{path}: {what} ({exc.msg}: line {exc.lineno}, column {exc.colno}); "
                          f"re-run the check or solve that wrote it") from None
    if not isinstance(data, dict):
        raise ResultError(f"{path}: expected a JSON object, got {type(data).__name__}")
    version = data.get("schema_version", 1)     # results written before the key existed are version 1
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise ResultError(f"{path}: schema_version {version!r} is not a positive integer")
    if version > SCHEMA_VERSION:
        raise ResultError(f"{path}: schema_version {version} is newer than this agrisynth reads "
                          f"({SCHEMA_VERSION}); upgrade agrisynth to read it")
    missing = [k for k in REQUIRED_KEYS if k not in data]
    if missing:
        raise ResultError(f"{path}: missing required key(s) {', '.join(missing)}; not an agrisynth result.json")
    problem = _shape_problem(data)
    if problem:
        raise ResultError(f"{path}: {problem}; not a result.json agrisynth wrote (or edited by hand)")
    try:
        return Result.from_json(data)
    except (TypeError, ValueError) as exc:
        raise ResultError(f"{path}: {exc}") from None


def _shape_problem(data: dict) -> str | None:
    """What is wrong with the types of a parsed result.json, or None: readers rely on these."""
    for key in ("kind", "name", "spec_sha256", "status"):
        if not isinstance(data[key], str):
            return f"{key} must be a string, got {type(data[key]).__name__}"
    if data["status"] not in STATUSES:
        return f"status {data['status']!r} is not one of {', '.join(STATUSES)}"
    for key in ("design", "versions", "objective", "solver", "trajectory", "facts", "elastic", "baseline_design"):
        if key in data and data[key] is not None and not isinstance(data[key], dict):
            return f"{key} must be an object, got {type(data[key]).__name__}"
    if "versions" in data and data["versions"] is None:
        return "versions must be an object, got null"
    if "starts" in data and not isinstance(data["starts"], (list, type(None))):
        return f"starts must be a list, got {type(data['starts']).__name__}"
    if not isinstance(data["rules"], list):
        return f"rules must be a list, got {type(data['rules']).__name__}"
    for i, rule in enumerate(data["rules"]):
        if not isinstance(rule, dict):
            return f"rules[{i}] must be an object"
        if not isinstance(rule.get("name"), str) or not isinstance(rule.get("satisfied"), bool):
            return f"rules[{i}] needs a string name and a true/false satisfied"
        limit = rule.get("limit")
        if not (isinstance(limit, list) and len(limit) == 2
                and all(v is None or isinstance(v, (int, float)) for v in limit)):
            return f"rules[{i}] ({rule['name']}): limit must be [lower, upper] with numbers or null"
    return None


def write_run(out_root: Path, result: Result, artifacts: dict[str, Callable[[Path], None]]) -> tuple[Path, bool]:
    """Write ``out_root/<name>/`` atomically: result.json plus each artifact writer's file.

    Everything is written into a temporary sibling folder first and swapped in with renames, so an
    interrupted run never leaves a half-written folder.  Returns (folder, replaced_previous_run).
    """
    def result_json(path: Path) -> None:
        path.write_text(json.dumps(result.to_json(), indent=1, allow_nan=False) + "\n")

    return write_folder(out_root / result.name, {"result.json": result_json, **artifacts})


def write_folder(final: Path, artifacts: dict[str, Callable[[Path], None]]) -> tuple[Path, bool]:
    """Write the folder ``final`` atomically, one file per artifact writer (called in order).

    Returns (final, replaced_previous_folder).
    """
    out_root = final.parent
    out_root.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{final.name}.", dir=out_root))
    os.chmod(staging, 0o777 & ~_UMASK)     # mkdtemp makes it private; a run folder is an ordinary folder
    try:
        for filename, writer in artifacts.items():
            writer(staging / filename)
        replaced = final.exists()
        if replaced:
            old = Path(tempfile.mkdtemp(prefix=f".{final.name}.old.", dir=out_root))
            os.replace(final, old / "run")
            os.replace(staging, final)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(staging, final)
        return final, replaced
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def atomic_write_text(path: Path, text: str) -> None:
    """Write a file via a temporary file and rename."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.chmod(tmp, 0o666 & ~_UMASK)       # mkstemp makes it private; give it the usual mode
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _read_umask() -> int:
    mask = os.umask(0)      # the only portable way to read it; done once, at import, before any threads
    os.umask(mask)
    return mask


_UMASK = _read_umask()
