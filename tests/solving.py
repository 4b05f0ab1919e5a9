"""Test helpers over the kind contract: solve a loaded spec, re-check a design as the solve does."""

from __future__ import annotations

from types import SimpleNamespace

from synthesis import kinds
from synthesis.core.kind import Setting
from synthesis.core.solve import solve_spec as run_solve  # noqa: F401 - re-exported for the tests


def recheck_rules(spec, design: dict) -> list:
    """The rules (floats) of ``design`` as the multistart's fine-grid re-check evaluates them."""
    solving = kinds.get(spec.kind).solver_side()
    setting = Setting(spec, spec.solver.seed, solving.prepare(spec))
    return solving.recheck(setting, SimpleNamespace(design=design, details={})).rules


def diagnose_infeasible(loaded, result, reports):
    """The exit-3 error the CLI raises for this result."""
    from synthesis.core.solve import exit_error

    return exit_error(kinds.get(loaded.kind), result, reports)


def baseline_rules(loaded):
    from synthesis.core import solve

    return solve.baseline_rules(kinds.get(loaded.kind), loaded)


# --- through the CLI, as a user runs it -------------------------------------------------------------------

def cli_run(*args: str, cwd):
    """``python -m synthesis.cli ARGS`` in ``cwd``; stdout and stderr captured as text."""
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "synthesis.cli", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300)


def spec_with(tmp_path, source, replacements: list[tuple[str, str]], name: str = "spec.toml"):
    """A copy of the spec file ``source`` with each (old, new) replaced once (old must be there)."""
    text = source.read_text()
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / name
    path.write_text(text)
    return path


def strict_json(path) -> dict:
    """result.json parsed with NaN and Infinity refused (the contract: never a non-finite number)."""
    import json

    def refuse(constant):
        raise AssertionError(f"{path}: {constant} in result.json")
    return json.loads(path.read_text(), parse_constant=refuse)


def modules_after_runs(tmp_path, runs: list[list[str]]) -> list[str]:
    """The modules one process has imported after the CLI commands ``runs`` (each a list of arguments),
    for the tests that a run builds only what its scene needs."""
    import json
    import subprocess
    import sys

    out = tmp_path / "modules.json"
    script = ("import json, sys\n"
              "from synthesis.cli import cli\n"
              f"for args in {runs!r}:\n"
              "    try:\n"
              "        cli.main(args, standalone_mode=False)\n"
              "    except SystemExit:\n"
              "        pass\n"
              f"open({str(out)!r}, 'w').write(json.dumps(sorted(sys.modules)))\n")
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(out.read_text())
