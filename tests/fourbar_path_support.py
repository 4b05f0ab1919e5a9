"""Helpers of the fourbar_path tests: write a spec as a TOML file, run the CLI."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PATH_LIBRARY = ROOT / "problems" / "fourbar_path"


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return repr(float(v)) if isinstance(v, float) else str(v)


def toml_text(data: dict) -> str:
    """A spec dict (plain values at the top, one level of tables) as TOML."""
    lines = [f"{k} = {_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"\n[{k}]")
            lines += [f"{kk} = {_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def write_spec(folder: Path, data: dict, name: str = "spec.toml") -> Path:
    path = folder / name
    path.write_text(toml_text(data))
    return path


def cli(*args: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "synthesis.cli", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout)
