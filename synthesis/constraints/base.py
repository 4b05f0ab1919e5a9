"""A design rule: named expression(s) with bounds, and its value/limit/margin record.

The same Rule serves both uses: built on floats (``check``) it is evaluated into a
:class:`RuleRecord`; built on CasADi symbols (``solve``) its rows become NLP constraints.  A
vector expression is a semi-infinite rule sampled on a grid; its record reports the worst sample.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np


def symbolic(values) -> bool:
    """Whether any of the values is a CasADi symbol or expression (a rule built for the NLP)."""
    return any(isinstance(v, (ca.SX, ca.MX)) for v in values)


def stack(values):
    """The values of a sampled rule as one vector: ca.vertcat of expressions, a numpy vector of numbers.  On numbers
    (``check``, the fine-grid re-check) vertcat would build a DM at about 2 us a value -- 56 ms for the 24,000
    closure values of a dense re-check -- where numpy takes 0.4 ms; Rule.record reads either."""
    values = list(values)
    if symbolic(values) or any(isinstance(v, ca.DM) for v in values):
        return ca.vertcat(*values)
    return np.asarray(values, dtype=float)


@dataclass(frozen=True)
class Rule:
    """``lower <= expr <= upper`` (either bound may be None), ``expr`` scalar or 1-D."""

    name: str
    expr: Any
    lower: float | None
    upper: float | None
    unit: str
    scale: float                 # typical size of a margin, for normalised margins
    where: str = ""              # where it is evaluated ("at P4", "over P3-P4", "over a turn")
    #: smooth rows for the optimiser when ``expr`` itself is not smooth: [(expr, lb, ub), ...]
    nlp_rows: tuple = field(default=(), compare=False)
    #: why the rule could not be evaluated (numeric designs only)
    missing: str | None = None
    #: a caveat on an evaluated value (e.g. it rests on a fit solved only inaccurately); shown in the table
    note: str | None = field(default=None, compare=False)
    #: the unit of ``nlp_rows`` when it is not ``unit`` (e.g. squared speeds for a speed rule)
    row_unit: str | None = field(default=None, compare=False)
    #: ``nlp_rows`` are the rule itself in its unit and limits, exactly (the smallest distance over a turn for its
    #: samples, one row per branch of a max()), not a rescaled or squared form: a robust solve's promise is read on
    #: them (synthesis.core.sensitivity.row_margins)
    rows_are_the_rule: bool = field(default=False, compare=False)
    #: the rule's rows in a tolerance box, where ``nlp_rows`` pin an equality (a design condition stricter than the
    #: rule's limits) that no box can hold at every corner: inequalities within the rule's own limits
    box_rows: tuple = field(default=(), compare=False)

    def rows(self) -> tuple:
        return self.nlp_rows or ((self.expr, self.lower, self.upper),)

    def record(self) -> "RuleRecord":
        """Evaluate a numeric rule: the worst sample, its margin (>= 0 means satisfied)."""
        limit = [self.lower, self.upper]
        if self.missing is not None:
            return RuleRecord(self.name, None, limit, self.unit, False, None, None, self.where, self.missing)
        values = np.atleast_1d(np.asarray(self.expr, dtype=float)).ravel()
        if np.any(np.isnan(values)):     # NaN is no evidence either way (an infinite radius is): not evaluated
            return RuleRecord(self.name, None, limit, self.unit, False, None, None, self.where,
                              "not evaluated: the value is not a number at this design")
        lo = np.full_like(values, np.inf) if self.lower is None else values - self.lower
        hi = np.full_like(values, np.inf) if self.upper is None else self.upper - values
        margins = np.minimum(lo, hi)
        worst = int(np.argmin(margins))
        margin = float(margins[worst])
        return RuleRecord(self.name, float(values[worst]), limit, self.unit, margin >= 0.0,
                          margin, margin / self.scale, self.where, self.note)


@dataclass(frozen=True)
class RuleRecord:
    """One row of the rule table and of result.json ``rules``."""

    name: str
    value: float | None
    limit: list                  # [lower, upper], None for an open side
    unit: str
    satisfied: bool
    margin: float | None         # distance to the nearer limit, in ``unit``; < 0 = violation
    normalised_margin: float | None
    where: str = ""
    note: str | None = None

    @property
    def limit_text(self) -> str:
        return limit_text(self.limit)

    def to_json(self) -> dict:
        return {
            "name": self.name, "value": self.value, "limit": self.limit, "unit": self.unit,
            "satisfied": self.satisfied, "margin": self.margin,
            "normalised_margin": self.normalised_margin, "where": self.where, "note": self.note,
        }


def limit_text(limit, ge: str = ">=", le: str = "<=", none: str = "-") -> str:
    """[lo, hi] as "[lo, hi]", ">= lo", "<= hi" or ``none`` (symbols replaceable, e.g. for HTML)."""
    lo, hi = (None if v is None else v + 0.0 for v in limit)      # + 0.0: a limit of -0.0 reads "0", not "-0"
    if lo is not None and hi is not None:
        return f"[{lo:g}, {hi:g}]"
    if lo is None and hi is None:
        return none
    return f"{ge} {lo:g}" if lo is not None else f"{le} {hi:g}"


def not_evaluated(name: str, lower, upper, unit: str, where: str, why: str) -> Rule:
    """A rule whose inputs do not exist for this design (e.g. the claw never reaches the soil)."""
    return Rule(name, None, lower, upper, unit, 1.0, where, missing=why)
