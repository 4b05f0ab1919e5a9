"""Layers go one way (docs/ARCHITECTURE.md), enforced by import-linter's contracts in pyproject.toml: design rules
import only casadi and numpy, kinematics imports no rules and no solver code, the core knows no kind,
only the CLI uses the terminal libraries."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from conftest import ROOT


def test_import_contracts_hold():
    exe = shutil.which("lint-imports")
    cmd = [exe] if exe else [sys.executable, "-m", "importlinter.cli"]
    proc = subprocess.run([*cmd, "--config", str(ROOT / "pyproject.toml")], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "broken" not in proc.stdout.lower().replace("0 broken", "")


def test_the_contracts_ignore_no_import_and_cover_every_layer():
    """No contract carries an ``ignore_imports`` (a dependency the layers forbid is inverted, not excused), and each
    of the core, kinds, run layer, tolerance, bench, reports and studio is the source of a forbidden contract."""
    import tomllib

    contracts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    assert [c["name"] for c in contracts if c.get("ignore_imports")] == []
    sources = {m for c in contracts if c["type"] == "forbidden" for m in c["source_modules"]}
    for layer in ("synthesis.core", "synthesis.kinds", "synthesis.runs", "synthesis.tolerance", "synthesis.bench",
                  "synthesis.report", "synthesis.studio"):
        assert layer in sources, layer
    # the engine side of the bench plug-in: a kind's bench cases are the kind contract's type, not the bench's
    from synthesis.bench import BenchCase, MethodRun
    from synthesis.core import bench_case

    assert (BenchCase, MethodRun) == (bench_case.BenchCase, bench_case.MethodRun)


@pytest.mark.slow
def test_run_folders_have_one_writer():
    """Every command's run folder (check, solve, tolerance, bench, compare) is moved into place by one function,
    ``RunFolder.fill`` (write into the staging folder, commit, discard on failure): no other code commits one."""
    import ast

    commits = []
    for path in sorted((ROOT / "synthesis").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for func in ast.walk(tree):
            if isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
                commits += [(path.relative_to(ROOT).as_posix(), func.name) for node in ast.walk(func)
                            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                            and node.func.attr == "commit"]
    assert commits == [("synthesis/result.py", "fill")]


def test_every_kind_lives_in_one_folder_under_synthesis_kinds():
    """The layer contracts name the kinds as a whole (``synthesis.kinds.*``): they hold for a new kind only if its
    class is defined in a folder there, like every built-in one; and the folders are the list (each folder's
    package exports its kinds, nothing else names them)."""
    from synthesis import kinds

    folders = {p.name for p in (ROOT / "synthesis" / "kinds").iterdir() if (p / "__init__.py").is_file()}
    seen = set()
    for name in kinds.names():
        module = type(kinds.get(name)).__module__
        assert module.startswith("synthesis.kinds.") and module.count(".") == 2, (name, module)
        seen.add(module.split(".")[2])
    assert seen == folders


def test_the_shared_rules_import_no_other_part_of_agrisynth():
    """The shared design rules live inside the package (synthesis.constraints: a wheel installing a top-level
    package named `constraints` could shadow another's), so their contract forbids each other part of synthesis by
    name: every one, also one added later."""
    import tomllib

    contracts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    rules = next(c for c in contracts if c["source_modules"] == ["synthesis.constraints"])
    parts = {f"synthesis.{p.stem if p.suffix == '.py' else p.name}" for p in (ROOT / "synthesis").iterdir()
             if (p.suffix == ".py" and p.stem != "__init__") or (p / "__init__.py").is_file()}
    assert parts - {"synthesis.constraints"} <= set(rules["forbidden_modules"]), parts - set(rules["forbidden_modules"])
    assert not (ROOT / "constraints").exists()
