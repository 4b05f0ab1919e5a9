"""One start of a multistart solve, as a kind's NLP returns it: the design in spec units."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from synthesis.core.ipopt import NLPOutcome


@dataclass
class StartOutcome:
    """``objective`` in report units (the kind's ``Finished.objective`` unit); ``success``: the stage
    that solves the spec's objective converged; ``raw``: IPOPT's outcome of that stage (decision
    vector, multipliers); ``details``: the kind's facts of this start (written to its ``starts`` row)."""

    start: int
    design: dict[str, float]
    objective: float
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str
    raw: NLPOutcome | None = None
    details: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, out: NLPOutcome, design: dict[str, float], objective: float, **details) -> "StartOutcome":
        return cls(out.start, design, objective, out.return_status, out.success, out.iterations, out.wall_s,
                   out.log, out, details)
