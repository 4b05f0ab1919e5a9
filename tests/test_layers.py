"""Layers go one way (issue 13), enforced by import-linter's contracts in pyproject.toml: design rules
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


def test_the_core_contract_names_every_kind_package():
    """The "core knows no kind" contract lists kind packages by name: every registered kind's package
    must be on it (a new kind adds itself there)."""
    import tomllib

    from synthesis.kinds import _REGISTRY

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    contract = next(c for c in config["tool"]["importlinter"]["contracts"] if c["name"] == "the solve core knows no kind")
    packages = {target.split(":")[0] for target in _REGISTRY.values()}
    assert packages <= set(contract["forbidden_modules"]), packages - set(contract["forbidden_modules"])
    independent = next(c for c in config["tool"]["importlinter"]["contracts"] if c["type"] == "independence")
    assert packages == set(independent["modules"]), packages ^ set(independent["modules"])
