"""Design rules, one small module per family; each builds :class:`constraints.base.Rule` objects
from floats (check) or CasADi symbols (solve)."""

from constraints.base import Rule, RuleRecord, not_evaluated

__all__ = ["Rule", "RuleRecord", "not_evaluated"]
