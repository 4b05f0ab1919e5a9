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
