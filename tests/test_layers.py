"""Layers go one way (docs/ARCHITECTURE.md), enforced by import-linter's contracts in pyproject.toml: design rules
import only casadi and numpy, kinematics imports no rules and no solver code, the core knows no kind,
only the CLI uses the terminal libraries."""

from __future__ import annotations

import shutil
import subprocess
import sys

from conftest import ROOT


def test_import_contracts_hold():
    exe = shutil.which("lint-imports")
    cmd = [exe] if exe else [sys.executable, "-m", "importlinter.cli"]
    proc = subprocess.run([*cmd, "--config", str(ROOT / "pyproject.toml")], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "broken" not in proc.stdout.lower().replace("0 broken", "")


def test_every_kind_lives_in_one_folder_under_synthesis_kinds():
    """The layer contracts name the kinds as a whole (``synthesis.kinds.*``): they hold for a new kind only if its
    package is a folder there, like every registered one."""
    from synthesis.kinds import _REGISTRY

    for name, target in _REGISTRY.items():
        package = target.split(":")[0]
        assert package.startswith("synthesis.kinds.") and package.count(".") == 2, (name, package)
        assert (ROOT / package.replace(".", "/") / "__init__.py").is_file(), (name, package)
