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

STATUSES = ("optimal", "feasible", "infeasible", "failed", "evaluated")


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
    extra: dict[str, Any] = field(default_factory=dict)   # kind-specific (precision points, ...)

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
        extra = data.pop("extra")
        data.update(extra)
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "Result":
        known = {"kind", "name", "spec_sha256", "status", "design", "rules", "objective", "trajectory",
                 "solver", "versions"}
        args = {k: data[k] for k in known if k in data}
        args["extra"] = {k: v for k, v in data.items() if k not in known}
        return cls(**args)


def load_result(path: str | Path) -> Result:
    path = Path(path)
    if path.is_dir():
        path = path / "result.json"
    return Result.from_json(json.loads(path.read_text()))


def write_run(out_root: Path, result: Result, artifacts: dict[str, Callable[[Path], None]]) -> tuple[Path, bool]:
    """Write ``out_root/<name>/`` atomically: result.json plus each artifact writer's file.

    Everything is written into a temporary sibling folder first and swapped in with renames, so an
    interrupted run never leaves a half-written folder.  Returns (folder, replaced_previous_run).
    """
    out_root.mkdir(parents=True, exist_ok=True)
    final = out_root / result.name
    staging = Path(tempfile.mkdtemp(prefix=f".{result.name}.", dir=out_root))
    try:
        (staging / "result.json").write_text(json.dumps(result.to_json(), indent=1, allow_nan=False) + "\n")
        for filename, writer in artifacts.items():
            writer(staging / filename)
        replaced = final.exists()
        if replaced:
            old = Path(tempfile.mkdtemp(prefix=f".{result.name}.old.", dir=out_root))
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
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)
