"""An optimisation problem as a kind declares it: no solver named, no transcription chosen.

A :class:`Problem` is the decision vector with its bounds, the *structural* rows (definitions that
must hold exactly, e.g. "phi_a is a stationary point of the rocker"), the design rules
(:class:`synthesis.constraints.base.Rule`, each with its rows), the objective and the NLP parameters.  How
it becomes an NLP (back-off of inequality limits, the elastic form, the max-min-margin epigraph)
is :mod:`synthesis.core.transcribe`; which solver runs it is :mod:`synthesis.core.ipopt`.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass, field
from typing import Callable, Sequence

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule

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
    #: the unit of each extra variable and of each row (:mod:`synthesis.core.units`; None: not declared)
    extra_units: Sequence[str] | None = None
    row_units: Sequence[str] | None = None


@dataclass(frozen=True)
class MaxMinMargin:
    """Maximise the smallest normalised margin over every rule row: max tau s.t. (row - lb)/scale >= tau
    and (ub - row)/scale >= tau.  Built by the transcription, since it needs every rule's rows."""

    upper: float = 10.0          # tau is bounded above so an unconstrained rule cannot make it unbounded


#: back-off: how far (in the rule's unit) a rule's inequality row is kept inside ``limit``
Backoff = Callable[[Rule, float], float]


#: a problem's back-off where it gives none: each row this many of its rule's scales inside its limits
DEFAULT_BACKOFF = 1e-7


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
    #: T (n x n): the design's offsets in the box are T u for the offsets u of the variables the box moves on their
    #: own (a variable others determine moves with them, its own ``box`` entry 0); None: the identity
    moves: np.ndarray | None = None


@dataclass(frozen=True)
class Operating:
    """An operating condition (forward speed, crank speed, friction, ...) the problem's expressions are written
    in: a scalar ``symbol`` standing for it and its ``nominal`` value (used wherever no envelope asks for more)."""

    name: str
    symbol: ca.SX
    nominal: float
    unit: str = ""


@dataclass(frozen=True)
class OperatingSource:
    """What :meth:`Problem._resolve_operating` substituted, kept for sensitivities w.r.t. the operating conditions:
    their ``symbols`` (in ``names`` order), the structural rows and every resolved rule's value before the
    substitution, and the values each rule was resolved at (nominal, or its scenario's)."""

    names: tuple[str, ...]
    units: tuple[str, ...]
    symbols: ca.SX
    structural: tuple
    rules: tuple          # (expression before substitution, {name: value}) per resolved rule, in rule order
    nominal: dict         # name -> nominal value (the structural rows' and the objective's)


@dataclass(frozen=True)
class Envelope:
    """Operating envelope: every rule that depends on an operating condition holds at each scenario, with one
    shared design (a multi-scenario NLP).  ``samples[name]`` are the values sampled of that condition; the
    scenarios are every combination of them."""

    samples: dict[str, tuple[float, ...]]

    def scenarios(self) -> list[dict[str, float]]:
        names = list(self.samples)
        return [dict(zip(names, combo)) for combo in itertools.product(*(self.samples[n] for n in names))]


def scenario_label(values: dict[str, float]) -> str:
    """``forward_speed=0.583`` (several conditions joined by ``,``): the suffix of a rule held at a scenario."""
    return ",".join(f"{n}={v:.4g}" for n, v in values.items())


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
    backoff: Backoff = field(default_factory=lambda: scaled_backoff(DEFAULT_BACKOFF))
    hard_in_elastic: Sequence[str] = ()
    ipopt: str = "tight"
    ipopt_options: dict = field(default_factory=dict)
    max_iter: int = 500
    #: robust synthesis: hold the rules at the linearised worst case of this tolerance box (None: nominal)
    tolerance: Tolerance | None = None
    #: operating conditions the expressions are written in (substituted by their nominal values or, for rules
    #: that depend on one the envelope samples, once per scenario: see :meth:`_resolve_operating`)
    operating: Sequence[Operating] = ()
    envelope: Envelope | None = None
    #: set when the operating conditions are resolved (sensitivities w.r.t. them: :mod:`synthesis.core.sensitivity`)
    operating_source: OperatingSource | None = None
    #: the declared unit of each entry of x, of each structural row and of the objective f (mm, deg, rad, m/s,
    #: mm^2, "" for a plain number ...; :mod:`synthesis.core.units`); None: not declared
    x_units: Sequence[str] | None = None
    structural_units: Sequence[str] | None = None
    objective_unit: str | None = None
    #: indices of structural inequality rows a tolerance box holds at their linearised worst case, as it holds a
    #: rule's rows (a clearance the kind keeps without reporting it as a rule); elsewhere they are as written
    robust_structural: Sequence[int] = ()

    def __post_init__(self) -> None:
        self.lbx = np.asarray(self.lbx, dtype=float)
        self.ubx = np.asarray(self.ubx, dtype=float)
        self.rules = list(self.rules)
        bad = [i for i in self.robust_structural if not 0 <= i < len(self.structural)
               or (self.structural[i][1] is not None and self.structural[i][1] == self.structural[i][2])]
        if bad:
            raise ValueError(f"problem {self.name}: robust_structural {bad} are not structural inequality rows")
        if self.operating:
            self._resolve_operating()
        names = [r.name for r in self.rules]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"problem {self.name}: rule names must be unique, repeated: {', '.join(dup)}")

    def _resolve_operating(self) -> None:
        """Replace the operating symbols by numbers, so every later stage (transcription, sensitivities, the
        solver, the elastic diagnosis) sees an ordinary problem.

        Structural rows and the objective's f take the nominal values, the objective's rows (an epigraph)
        are held at every scenario where they read a sampled condition.  A rule whose rows depend on a condition
        the envelope samples becomes one rule per scenario, ``<rule>@<condition>=<value>``, each with that
        scenario's values (the other conditions nominal); a rule that depends on none stays one rule.  The
        structural rows pin auxiliaries (crank angles of precision points) shared by every scenario, so they
        may not depend on a sampled condition (one copy of the auxiliaries per scenario is not built)."""
        ops = list(self.operating)
        names = [o.name for o in ops]
        if len(set(names)) != len(names):
            raise ValueError(f"problem {self.name}: operating conditions repeated in {names}")
        envelope = self.envelope
        unknown = sorted(set(envelope.samples) - set(names)) if envelope else []
        if unknown:
            raise ValueError(f"problem {self.name}: the envelope samples {', '.join(unknown)}, which the problem "
                             f"does not depend on (its operating conditions: {', '.join(names) or 'none'})")
        syms = ca.vertcat(*[o.symbol for o in ops])
        nominal = {o.name: float(o.nominal) for o in ops}
        sampled = ca.vertcat(*[o.symbol for o in ops if envelope and o.name in envelope.samples])

        def at(expr, values: dict[str, float]):
            if not isinstance(expr, ca.SX):
                return expr
            return ca.substitute(expr, syms, ca.SX(ca.DM([values[n] for n in names])))

        def rows_at(rows, values):
            return tuple((at(e, values), lb, ub) for e, lb, ub in rows)

        def depends(expr) -> bool:
            e = _sx(expr)
            return sampled.numel() > 0 and e.numel() > 0 and ca.depends_on(ca.vec(e), sampled)

        bad = [i for i, (e, _, _) in enumerate(self.structural) if depends(e)]
        if bad:
            raise ValueError(f"problem {self.name}: structural rows {bad} depend on a condition the envelope "
                             f"samples ({', '.join(envelope.samples if envelope else ())}); write them free of it "
                             f"(the auxiliaries they pin are shared by every scenario)")
        source_structural = tuple(self.structural)
        self.structural = list(rows_at(self.structural, nominal))
        rules, hard, sources = [], list(self.hard_in_elastic), []
        for rule in self.rules:
            varies = (any(depends(e) for e, _, _ in (*rule.rows(), *rule.box_rows)) or depends(rule.expr))
            if not varies or envelope is None:      # (a rule varies only with a condition the envelope samples)
                rules.append(dataclasses.replace(rule, expr=at(rule.expr, nominal),
                                                 nlp_rows=rows_at(rule.nlp_rows, nominal),
                                                 box_rows=rows_at(rule.box_rows, nominal)))
                sources.append((rule.expr, dict(nominal)))
                continue
            for scenario in envelope.scenarios():
                values = {**nominal, **scenario}
                label = scenario_label({n: v for n, v in scenario.items()
                                        if depends_on_one(rule, next(o.symbol for o in ops if o.name == n))})
                name = f"{rule.name}@{label}"
                if any(r.name == name for r in rules):
                    continue                # the rule does not depend on this scenario's other conditions
                rules.append(dataclasses.replace(rule, name=name, expr=at(rule.expr, values),
                                                 nlp_rows=rows_at(rule.nlp_rows, values),
                                                 box_rows=rows_at(rule.box_rows, values),
                                                 where=f"{rule.where}, {label}" if rule.where else label))
                sources.append((rule.expr, values))
                if rule.name in self.hard_in_elastic:
                    hard.append(name)
        self.rules = rules
        self.hard_in_elastic = tuple(hard)
        self.operating_source = OperatingSource(tuple(names), tuple(o.unit for o in ops), syms, source_structural,
                                                tuple(sources), dict(nominal))
        if isinstance(self.objective, ObjectiveParts):
            self.objective = _objective_over(self.objective, at, depends, envelope, nominal)
        self.operating = ()           # resolved: a copy of this problem (dataclasses.replace) stays as it is


def _objective_over(objective: ObjectiveParts, at, depends, envelope: Envelope | None, nominal: dict) -> ObjectiveParts:
    """f at the nominal values; the objective's rows (an epigraph: tau >= |e|) once per scenario where they read a
    sampled condition, so a min-max objective is the worst over the envelope."""
    rows, units = [], []
    declared = objective.row_units
    for i, row in enumerate(objective.rows):
        scenarios = envelope.scenarios() if envelope is not None and depends(row[0]) else [{}]
        rows += [(at(row[0], {**nominal, **sc}), row[1], row[2]) for sc in scenarios]
        units += [declared[i]] * len(scenarios) if declared is not None else []
    return dataclasses.replace(objective, f=at(objective.f, nominal), rows=rows,
                               row_units=None if declared is None else units)


def depends_on_one(rule: Rule, symbol: ca.SX) -> bool:
    """Whether any row (or the value) of ``rule`` depends on ``symbol``."""
    exprs = [_sx(e) for e, _, _ in (*rule.rows(), *rule.box_rows)] + [_sx(rule.expr)]
    return any(e.numel() > 0 and ca.depends_on(ca.vec(e), symbol) for e in exprs)


def _sx(expr) -> ca.SX:
    """A rule's or row's expression as SX (an empty one for None or a non-numeric value)."""
    if isinstance(expr, ca.SX):
        return expr
    try:
        return ca.SX(expr)
    except (NotImplementedError, TypeError, RuntimeError):
        return ca.SX(0, 1)
