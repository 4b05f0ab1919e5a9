"""An optimisation problem as a kind declares it: no solver named, no transcription chosen.

A :class:`Problem` is the decision vector with its bounds, the *structural* rows (definitions that
must hold exactly, e.g. "phi_a is a stationary point of the rocker"), the design rules
(:class:`constraints.base.Rule`, each with its rows), the objective and the NLP parameters.  How
it becomes an NLP (back-off of inequality limits, the elastic form, the max-min-margin epigraph)
is :mod:`synthesis.core.transcribe`; which solver runs it is :mod:`synthesis.core.ipopt`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import casadi as ca
import numpy as np

from constraints.base import Rule

Row = tuple  # (expr, lb | None, ub | None); a vector expr is one row per element


@dataclass
class ObjectiveParts:
    """f(x, extra) plus the extra decision variables and rows it needs (e.g. an epigraph variable)."""

    f: ca.SX
    extra: ca.SX = field(default_factory=lambda: ca.SX(0, 1))
    extra_lb: Sequence[float] = ()
    extra_ub: Sequence[float] = ()
    extra_init: Sequence[float] = ()
    rows: Sequence[Row] = ()


@dataclass(frozen=True)
class MaxMinMargin:
    """Maximise the smallest normalised margin over every rule row: max tau s.t. (row - lb)/scale >= tau
    and (ub - row)/scale >= tau.  Built by the transcription, since it needs every rule's rows."""

    upper: float = 10.0          # tau is bounded above so an unconstrained rule cannot make it unbounded


#: back-off: how far (in the rule's unit) a rule's inequality row is kept inside ``limit``
Backoff = Callable[[Rule, float], float]


def scaled_backoff(fraction: float) -> Backoff:
    """Keep rows ``fraction`` x the rule's scale inside their limits: IPOPT meets a row only to its
    tolerance, so a returned design meets the exact limit when re-checked, not 1e-12 short of it."""
    return lambda rule, limit: fraction * rule.scale


def relative_backoff(fraction: float) -> Backoff:
    """Keep rows ``fraction`` x max(1, |limit|) inside their limits (for rules whose scale is not a
    margin size, e.g. squared lengths)."""
    return lambda rule, limit: fraction * max(1.0, abs(limit))


def per_rule_backoff(of: Callable[[Rule], float]) -> Backoff:
    """``of(rule)`` x the rule's scale: e.g. zero for rules that are exact rather than sampled."""
    return lambda rule, limit: of(rule) * rule.scale


@dataclass(frozen=True)
class Tolerance:
    """Hold every rule at its linearised worst case in a tolerance box on the design (robust synthesis).

    ``x[:n_design]`` are the design coordinates z, ``x[n_design:]`` auxiliary variables pinned by the
    structural equality rows; the design is d = d0 + J z (``design_jacobian`` J, the identity when
    None); ``box[j]`` is the half-width of design variable j's tolerance (its unit), 0 for none.  Each
    inequality row g of a rule is held at g -/+ sum_j |dg/dd_j| box_j (implicit-function derivatives,
    :mod:`synthesis.core.sensitivity`), the absolute values as epigraph rows (:mod:`synthesis.core.transcribe`).
    """

    n_design: int
    box: np.ndarray
    design_jacobian: np.ndarray | None = None


@dataclass
class Problem:
    """min f  s.t.  structural rows, every rule's rows, lbx <= x <= ubx, with parameters p.

    ``x`` is the whole decision vector the kind works in (design coordinates and any auxiliary
    variables such as the crank angles of precision points); the kind maps it to a design.
    ``hard_in_elastic`` names rules the elastic diagnosis may not relax (those without which the
    kinematics is undefined).  ``ipopt`` names an option preset of :mod:`synthesis.core.ipopt`;
    ``ipopt_options`` override it (e.g. the spec's ``mu_strategy``).
    """

    name: str
    x: ca.SX
    lbx: np.ndarray
    ubx: np.ndarray
    structural: Sequence[Row]
    rules: Sequence[Rule]
    objective: ObjectiveParts | MaxMinMargin
    parameters: ca.SX = field(default_factory=lambda: ca.SX(0, 1))
    backoff: Backoff = field(default_factory=lambda: scaled_backoff(1e-7))
    hard_in_elastic: Sequence[str] = ()
    ipopt: str = "tight"
    ipopt_options: dict = field(default_factory=dict)
    max_iter: int = 500
    #: robust synthesis: hold the rules at the linearised worst case of this tolerance box (None: nominal)
    tolerance: Tolerance | None = None

    def __post_init__(self) -> None:
        self.lbx = np.asarray(self.lbx, dtype=float)
        self.ubx = np.asarray(self.ubx, dtype=float)
        self.rules = list(self.rules)
        names = [r.name for r in self.rules]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"problem {self.name}: rule names must be unique, repeated: {', '.join(dup)}")
