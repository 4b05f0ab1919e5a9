"""A kind's problem as the kind declares it, and the core's build of it (docs/ARCHITECTURE.md, "The kind contract").

A kind declares, for a :class:`~synthesis.core.kind.Setting`, a :class:`Declared`: its
:class:`~synthesis.core.problem.Problem`, the decision entries a start is drawn in (names, bounds, the spec's
given design), its design map (the returned decision vector -> the result's design) and, where a start needs
more than the design itself (auxiliaries guessed, an epigraph variable's start), its start map.  The core
compiles it (:func:`compile_problem`) and solves each start through :class:`DeclaredNLP`; the kind writes
``Solving(build=declared(its_problem), ...)``.

The transforms of a problem are explicit: the setting says them (operating conditions as symbols, a tolerance
box, no IPOPT instance) and :func:`compile_problem` applies them, :func:`held_in_box` being the robust one as a
``Problem -> Problem`` function.  A kind that solves in stages or forms of its own (its own starts, a reduced
form first) keeps its own :class:`~synthesis.core.kind.KindNLP` and compiles each of its problems through
:func:`compile_problem`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from synthesis.core.coordinates import fixed_as_given
from synthesis.core.ipopt import CompiledNLP, NLPOutcome
from synthesis.core.kind import Finished, KindNLP, Setting, Solving
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import Problem
from synthesis.core.verdict import Recheck
from synthesis.result import Result


def held_in_box(problem: Problem, box: Callable[[Problem], Any]) -> Problem:
    """The problem with every rule held at its linearised worst case in the tolerance box ``box(problem)`` gives
    (robust synthesis, :mod:`synthesis.core.transcribe`); a problem with a box of its own keeps it."""
    if problem.tolerance is not None:
        return problem
    return dataclasses.replace(problem, tolerance=box(problem))


def compile_problem(setting: Setting, problem: Problem, elastic: bool = False, **options) -> CompiledNLP:
    """The problem as the setting transforms it, compiled: held in its tolerance box (the robust extras started at
    each start), without an IPOPT instance where it is only evaluated.  ``options``: CompiledNLP's (scaling,
    watched)."""
    tolerance = setting.tolerance
    if tolerance is not None:
        problem = held_in_box(problem, tolerance)
    return CompiledNLP(problem, elastic, with_solver=setting.solver, robust_start=tolerance is not None,
                       method=setting.method,
                       **options)


def _given(x: np.ndarray, elastic: bool) -> tuple[np.ndarray, None]:
    return np.asarray(x, float), None


def _solver_objective(out: NLPOutcome, design: dict, elastic: bool) -> float:
    return out.objective


def _nothing_more(out: NLPOutcome, compiled: CompiledNLP) -> dict:
    return {}


@dataclass
class Declared:
    """A kind's problem and its maps: what the core needs to compile it and to solve a start of it."""

    problem: Problem
    names: list[str]               # the decision entries a start is drawn in (the first of the problem's x)
    bounds: np.ndarray             # n x 2
    init: np.ndarray               # the spec's given design in them
    #: the returned decision vector (x and extras) -> the result's design (spec units)
    design: Callable[[np.ndarray], dict]
    #: (start design, elastic) -> (the problem's x, the extras or None: the transcription's) IPOPT starts from
    start: Callable[[np.ndarray, bool], tuple[np.ndarray, Any]] = _given
    #: (outcome, its design, elastic) -> the objective in report units (default: the NLP's f)
    objective: Callable[[NLPOutcome, dict, bool], float] = _solver_objective
    #: (outcome, compiled) -> the start's details (its ``starts`` row: binding rules, crank angles ...)
    details: Callable[[NLPOutcome, CompiledNLP], dict] = _nothing_more
    #: the result design's key of each of ``names`` (None: the same names)
    design_names: list[str] | None = None
    #: CompiledNLP options (scaling, watched)
    options: dict = field(default_factory=dict)
    #: True when ``start`` moves the design itself (e.g. pulls it into the region where the linkage assembles),
    #: not only guesses the auxiliaries: the starts IPOPT solves from are then not the uniform draws the confidence
    #: statement assumes
    moves_the_design: bool = False


class DeclaredNLP(KindNLP):
    """The core's per-start adapter of a :class:`Declared` problem, built once per process."""

    def __init__(self, declared: Declared, setting: Setting, elastic: bool = False):
        self.declared = declared
        self.names, self.bounds, self.init = list(declared.names), declared.bounds, declared.init
        self.compiled = compile_problem(setting, declared.problem, elastic, **declared.options)

    @property
    def design_names(self) -> list[str]:
        return self.declared.design_names or self.names

    @property
    def maps_its_starts(self) -> bool:     # type: ignore[override]  # a class attribute of KindNLP, read-only here
        return self.declared.moves_the_design

    @property
    def problem(self) -> Problem:
        """The problem as the kind declared it (before any transform)."""
        return self.declared.problem

    def design(self, x: np.ndarray) -> dict:
        """The result design of a decision vector (the kind's design map), a fixed variable as the spec gives it
        (:func:`~synthesis.core.coordinates.fixed_as_given`: a map through other coordinates rounds it)."""
        return fixed_as_given(self.design_names, self.bounds, self.declared.design(x))

    def solve(self, start: int, x_design: np.ndarray) -> StartOutcome:
        d, elastic = self.declared, self.compiled.elastic
        x0, extra0 = d.start(x_design, elastic)
        out = self.compiled.solve(start, x0, extra0=extra0)
        design = self.design(out.x)
        return StartOutcome.of(out, design, d.objective(out, design, elastic), **d.details(out, self.compiled))


@dataclass(frozen=True)
class DeclaredBuild:
    """``Solving.build`` of a kind that declares its problem: (setting, elastic) -> :class:`DeclaredNLP`."""

    declare: Callable[[Setting], Declared]

    def __call__(self, setting: Setting, elastic: bool = False) -> DeclaredNLP:
        return DeclaredNLP(self.declare(setting), setting, elastic)


def declared(declare: Callable[[Setting], Declared]) -> DeclaredBuild:
    """The build of a kind whose ``declare(setting)`` returns its :class:`Declared` problem."""
    return DeclaredBuild(declare)


def named(names: Sequence[str]) -> Callable[[np.ndarray], dict]:
    """The design map of a decision vector whose first entries are the design variables ``names`` themselves."""
    return lambda x: {n: float(v) for n, v in zip(names, x)}


def binding(out: NLPOutcome, compiled: CompiledNLP, names: Sequence[str], bounds: np.ndarray,
            relative: float) -> dict:
    """A start's limits that bind: the rules whose multipliers are non-zero (none in the elastic form) and the free
    design variables within ``relative`` x max(1, |value|) of a bound."""
    xs = out.x[:len(names)]
    rules = [] if compiled.elastic else compiled.active_rules(out)
    at_bound = [n for n, v, (a, b) in zip(names, xs, bounds) if b > a and min(v - a, b - v) <= relative * max(1.0, abs(v))]
    return {"binding_rules": rules, "variables_at_bounds": at_bound}


def rule_table(rules) -> list[dict]:
    """result.json ``rules`` of rules evaluated on floats."""
    return [r.record().to_json() for r in rules]


def evaluated(loaded, rules) -> Result:
    """The check's Result of a spec whose rules, evaluated at its given design, are ``rules``."""
    spec = loaded.model
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=spec.design_values(), rules=rule_table(rules), extra={"source": spec.source})


@dataclass(frozen=True)
class _RulesAt:
    """A kind's ``rules(spec, design)`` on floats as its re-check (of a returned design) or its baseline (the spec's
    given design): a kind whose re-check is its rules at the solver's own samples needs no more."""

    rules: Callable[[Any, dict], list]

    def recheck(self, setting: Setting, outcome) -> Recheck:
        return Recheck(self.rules(setting.spec, outcome.design))

    def baseline(self, setting: Setting) -> list[dict]:
        return rule_table(self.rules(setting.spec, setting.spec.design_values()))


@dataclass(frozen=True)
class _PlainFinish:
    """The result of the best start: its design, its objective as ``name`` in ``unit``, and ``facts(spec, design)``."""

    name: str
    unit: str
    facts: Callable[[Any, dict], dict] | None = None

    def __call__(self, setting: Setting, best) -> Finished:
        design = dict(best.outcome.design)
        return Finished(design=design, objective={"name": self.name, "value": best.outcome.objective, "unit": self.unit},
                        facts=self.facts(setting.spec, design) if self.facts is not None else {})


def rules_solving(declare: Callable[[Setting], Declared], rules: Callable[[Any, dict], list], objective: str,
                  unit: str, facts: Callable[[Any, dict], dict] | None = None, **options) -> Solving:
    """The solve side of a kind whose problem is ``declare``, whose re-check and baseline are ``rules(spec, design)``
    on floats and whose result is the best start's design and objective (``objective`` in ``unit``) with
    ``facts(spec, design)``; ``options``: the rest of :class:`Solving` (maximise, hints ...)."""
    at = _RulesAt(rules)
    return Solving(build=declared(declare), recheck=at.recheck, finish=_PlainFinish(objective, unit, facts),
                   baseline_rules=at.baseline, **options)
