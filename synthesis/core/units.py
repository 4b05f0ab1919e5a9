"""Units of an NLP's quantities as powers of length: what a change of the length unit does to a problem.

Every quantity of a :class:`~synthesis.core.problem.Problem` has a declared unit: each variable of ``x``
(``x_units``), each structural row (``structural_units``), each rule (its ``unit``, or ``row_unit`` when its
smooth NLP rows are in another unit), the objective (``objective_unit``) and the objective's extra variables
and rows.  Only the power of length in a unit matters here: changing the length unit so that every length is
``factor`` times its number in the kind's unit (mm -> m: factor 1e-3) multiplies a quantity of length power p
by factor**p (p = 1 for mm, m/s and mm/s^2, 2 for mm^2, -1 for 1/mm, 0 for deg, rad, s, r/min and plain
numbers).  :data:`LENGTH_POWER` is the table; a unit not in it is refused (:func:`length_power`), not guessed.

The factors of a transcription's variables, rows and objective (:func:`variable_factors`, :func:`row_factors`,
:func:`objective_factor`) are what ``synthesis.core.ipopt.SolveMethod(length_factor=...)`` applies to hand IPOPT the problem
in another length unit: w' = c_w w, g' = c_g g (bounds alike, so the kind's back-off carries over exactly),
f' = c_f f -- the same feasible set and minimiser, in the numbers a user working in metres would give IPOPT.
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca
import numpy as np

from synthesis.core.problem import MaxMinMargin, ObjectiveParts

#: unit -> power of length in it.  Lengths mm or m, speeds mm/s or m/s, accelerations mm/s^2 or m/s^2 all
#: carry one length; "1", "-" and "" are plain numbers (ratios, normalised margins)
LENGTH_POWER: dict[str, int] = {
    "mm": 1, "m": 1, "mm/s": 1, "m/s": 1, "mm/s^2": 1, "m/s^2": 1, "mm/rad": 1,
    "mm^2": 2, "m^2": 2, "mm^2/s^2": 2, "m^2/s^2": 2, "mm^2/rad": 2,
    "1/mm": -1, "deg/mm": -1,
    "deg": 0, "rad": 0, "deg^2": 0, "deg/s^2": 0, "s": 0, "ms": 0, "r/min": 0, "rad/s": 0,
    "1": 0, "-": 0, "": 0, "%": 0,
    # forces, torques and stresses are SI whatever the length unit: a follower's spring rate is per length
    "N": 0, "N^2": 0, "N m": 0, "N m/rad": 0, "MPa": 0, "N/mm": -1,
    # so are masses and moments of inertia (a counterweight's kg, a flywheel's kg m^2)
    "kg": 0, "kg m^2": 0,
}


def length_power(unit: str, what: str = "a quantity") -> int:
    """The power of length in ``unit`` (ValueError naming ``what`` for a unit not in :data:`LENGTH_POWER`)."""
    try:
        return LENGTH_POWER[unit]
    except (KeyError, TypeError):
        known = ", ".join(repr(u) for u in LENGTH_POWER)
        raise ValueError(f"{what}: unit {unit!r} is not in the length-power table synthesis.core.units.LENGTH_POWER "
                         f"({known}); add it there with its power of length") from None


def powers(units: Sequence[str] | None, n: int, what: str) -> np.ndarray:
    """Length powers of ``n`` declared units (ValueError when they are missing or not ``n``)."""
    if units is None:
        raise ValueError(f"{what}: no units declared (needed to change the length unit)")
    if len(units) != n:
        raise ValueError(f"{what}: {len(units)} units declared for {n} entries")
    return np.array([length_power(u, what) for u in units], dtype=float)


def rule_factor(rule, factor: float, problem: str = "") -> float:
    """factor**p of the unit of the rule's NLP rows (``row_unit`` when it has one, else its ``unit``)."""
    unit = rule.unit if getattr(rule, "row_unit", None) is None or not rule.nlp_rows else rule.row_unit
    return factor ** length_power(unit, f"problem {problem}: rule {rule.name}")


def _numel(expr) -> int:
    if isinstance(expr, (ca.SX, ca.MX)):
        return int(ca.SX(expr).numel())  # type: ignore[arg-type]  # casadi's stubs give SX() no MX; kept as it was
    return int(np.size(expr))


def variable_factors(problem, factor: float, n_w: int, elastic: bool) -> np.ndarray:
    """factor**p of every variable of the problem's transcription (x, the objective's extras; the elastic
    slacks are in units of each rule's scale, plain numbers): all 1 when factor is 1."""
    out = np.ones(n_w)
    if factor == 1.0:
        return out
    name = f"problem {problem.name}"
    cx = factor ** powers(problem.x_units, problem.x.numel(), f"{name}: x")
    out[:cx.size] = cx
    objective = problem.objective
    if not elastic and isinstance(objective, ObjectiveParts) and _numel(objective.extra):
        ce = factor ** powers(objective.extra_units, _numel(objective.extra), f"{name}: objective extras")
        out[cx.size:cx.size + ce.size] = ce
    return out


def objective_factor(problem, factor: float, elastic: bool) -> float:
    """factor**p of the objective IPOPT minimises (the elastic sum of slacks and the max-min margin are plain
    numbers)."""
    if factor == 1.0 or elastic or not isinstance(problem.objective, ObjectiveParts):
        return 1.0
    return factor ** length_power(problem.objective_unit, f"problem {problem.name}: objective")


def row_factors(problem, factor: float, owner: Sequence, elastic: bool) -> np.ndarray:
    """factor**p of every row of a transcription of ``problem``, ``owner`` its rows' rule indices (structural
    rows first, then each rule's, then the objective's: :mod:`synthesis.core.transcribe`)."""
    out = np.ones(len(owner))
    if factor == 1.0:
        return out
    name = f"problem {problem.name}"
    i = 0
    if problem.structural:
        units = powers(problem.structural_units, len(problem.structural), f"{name}: structural rows")
        for (expr, _, _), q in zip(problem.structural, units):
            n = _numel(expr)
            out[i:i + n] = factor ** q
            i += n
    rule_c = [rule_factor(r, factor, problem.name) for r in problem.rules]
    while i < len(owner) and owner[i] is not None:
        out[i] = rule_c[owner[i]]
        i += 1
    objective = problem.objective
    if not elastic and isinstance(objective, ObjectiveParts) and objective.rows:
        units = powers(objective.row_units, len(objective.rows), f"{name}: objective rows")
        for (expr, _, _), q in zip(objective.rows, units):
            n = _numel(expr)
            out[i:i + n] = factor ** q
            i += n
    if isinstance(objective, MaxMinMargin) and not elastic:
        i = len(owner)              # its rows are margins over each rule's scale: plain numbers
    if i != len(owner):
        raise ValueError(f"{name}: {len(owner) - i} rows of unknown unit after the objective's")
    return out
