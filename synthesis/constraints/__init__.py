"""Design rules, one small module per family; each builds :class:`synthesis.constraints.base.Rule` objects
from floats (check) or CasADi symbols (solve)."""

from synthesis.constraints.base import Rule, RuleRecord, not_evaluated

__all__ = ["Rule", "RuleRecord", "not_evaluated"]
