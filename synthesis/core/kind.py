"""The kind contract: what a kind package exports, and what its solve side declares.

A kind is one package exporting one :class:`Kind` (``KIND``).  Everything in it is a
``"module:attribute"`` string resolved on use, so reading the registry (``agrisynth problems``,
``solve --help``, the bench) imports no kind's code, and a run imports only its own kind.
The registry of kinds is :mod:`synthesis.kinds`.

For ``agrisynth studio`` a kind gives its check on a coarser grid (``coarse_check``: a :class:`CoarseCheck`, what
the page evaluates while a slider moves; default: the check on its [solver] sample counts / 10), the mechanism's
poses where its check's facts hold none (``poses``: a :class:`Poses`), and, when its spec may leave part of the
design to the kind (guide_way's convex fit), that design written out as free variables (``explicit_design``;
``solved.toml`` uses it too).  The studio itself names no kind.

A kind that solves points ``solving`` at a :class:`Solving`: the pieces the one multistart driver
(:mod:`synthesis.core.solve`) needs, none of which names a solver:

    prepare(spec)              anything worked out once per run (a fitted law, a scene), picklable
    build(setting, elastic)    the kind's NLP: ``names``, ``bounds`` (n x 2), ``init``, ``compiled``
                               (the :class:`~synthesis.core.ipopt.CompiledNLP` an elastic diagnosis reads)
                               and ``solve(start, x_design) -> StartOutcome``; built once per process;
                               optionally ``x_of(design) -> x_design`` when the result's design keys are
                               not ``names``, and ``builds_its_own_starts = True`` when ``solve`` may
                               ignore ``x_design`` (no start is then solved from the elastic re-solve's design)
    recheck(setting, outcome)  the rules of a returned design on floats, 10x finer (a :class:`Recheck`)
    finish(setting, best)      the result's design, objective, trajectory and kind facts (:class:`Finished`)
    baseline_rules(setting)    the rule table of the spec's given design (or None if it cannot be evaluated)
"""

from __future__ import annotations

import math

import importlib
from dataclasses import dataclass, field
from typing import Any, Callable


def resolve(target: str) -> Any:
    """``"package.module:attribute"`` -> the attribute (imports the module)."""
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


@dataclass(frozen=True)
class Kind:
    """Everything agrisynth knows about one problem kind."""

    name: str
    summary: str                          # one line: the mechanism and its seed paper
    spec_model: str                       # "module:Class" of the pydantic spec model
    check: str                            # "module:function"(loaded spec) -> Result (status "evaluated")
    figures: dict[str, str] = field(default_factory=dict)   # file name -> "module:writer"(result, path)
    compare: str | None = None            # "module:function"(results, folder) -> [file names]: overlays
    solving: str | None = None            # "module:object" of a Solving; None: the kind is check-only
    objectives: dict[str, str] = field(default_factory=dict)  # objective -> one-line meaning (first = default)
    bench: str | None = None              # "module:function"(specs | None, seed) -> bench cases
    example: str | None = None            # a library spec to try, relative to problems/
    #: "module:object" of a CoarseCheck: the check on a coarser grid (the studio's, while a slider moves);
    #: None: the check with every [solver] sample count divided by 10 (:func:`synthesis.core.coarse.of_kind`)
    coarse_check: str | None = None
    #: "module:object" of a Poses: the mechanism's poses where the check's facts give none (the studio draws them)
    poses: str | None = None
    #: "module:function"(loaded spec, spec file data) -> that data with a design the spec may leave to the kind
    #: (guide_way: the convex fit's control points) written out as free variables, so it solves and checks the
    #: same and every variable has a place in the file (the studio's sliders, solved.toml); None: specs always
    #: hold their whole design
    explicit_design: str | None = None

    @property
    def solves(self) -> bool:
        return self.solving is not None

    def model_class(self):
        return resolve(self.spec_model)

    def checker(self) -> Callable:
        return resolve(self.check)

    def solver_side(self) -> "Solving":
        return resolve(self.solving)


def _the_check(spec) -> str:
    return "agrisynth check's own grid"


@dataclass(frozen=True)
class CoarseCheck:
    """The kind's check on a coarser grid, for ``agrisynth studio`` while a slider moves (the fine grid, on release,
    is ``check`` itself): the same rules, fewer samples, and only the facts the page draws.
    Helpers for the usual cases: :mod:`synthesis.core.coarse`."""

    evaluate: Callable[[Any], Any]               # loaded spec -> Result (status "evaluated"), the check's rules
    note: Callable[[Any], str]                   # spec -> what the coarse grid evaluates, in words (sample counts)
    fine_note: Callable[[Any], str] = _the_check  # spec -> what the fine grid (the check) evaluates, in words


def pose_mm(v: float) -> float | None:
    """A coordinate of a pose as the studio's page gets it: mm to 3 decimals, None where it is not finite."""
    return round(float(v), 3) if math.isfinite(v) else None


@dataclass(frozen=True)
class Poses:
    """The mechanism's poses for the studio's drawing, for a kind whose check's facts hold none (no ``positions``
    or ``joints``): from the kinematics the kind's own figures draw it with, on the trajectory's crank angles."""

    frames: Callable[[Any, int], list]           # (Result, at most this many) -> [{joint: [x, y] mm}], in order
    bars: list[list[str]] | None = None          # links drawn between joints (None: the joints in order)
    #: (Result) -> {name: [[x, y], ...] mm}: rigid outlines in their body's own frame (a cam's profile, a roller),
    #: sent once; a frame places one as {"shape": name, "at": [x, y], "turn_deg": a} (turned about the body's origin)
    shapes: Callable[[Any], dict] | None = None


@dataclass(frozen=True)
class Setting:
    """What a kind's solve pieces receive: the validated spec, the run's seed and what ``prepare`` made."""

    spec: Any
    seed: int = 0
    data: Any = None


@dataclass(frozen=True)
class Finished:
    """The kind's part of a solve's result, from the chosen start."""

    design: dict[str, Any]               # result.json design (spec units): numbers or lists of numbers (schema 3)
    objective: dict[str, Any]            # {name, value, unit}
    facts: dict[str, Any] = field(default_factory=dict)      # kind facts, result.json "facts"
    trajectory: dict[str, Any] | None = None
    solver_settings: dict[str, Any] = field(default_factory=dict)   # sample counts etc., into "solver"
    #: the spec's given design in the result's terms (default: the spec's ``design_values()``)
    baseline_design: dict[str, Any] | None = None
    #: the rule table when the chosen start could not be evaluated (each rule "not evaluated", with why)
    rules: list[dict] | None = None
    #: what a user must know about the answer beyond its rules (result.json solver.status_note, the terminal's note)
    note: str | None = None


def _nothing(spec) -> None:
    return None


def _minimise(setting) -> bool:
    return False


def _no_early_stop(setting):
    return None


@dataclass(frozen=True)
class Solving:
    """The solve side of a kind (see the module docstring)."""

    build: Callable[[Setting, bool], Any]
    recheck: Callable[[Setting, Any], Any]
    finish: Callable[[Setting, Any], Finished]
    baseline_rules: Callable[[Setting], list | None]
    prepare: Callable[[Any], Any] = _nothing
    maximise: Callable[[Setting], bool] = _minimise
    #: where the elastic diagnosis starts: "best" (the least-violating start's design) or "given"
    elastic_from: str = "best"
    #: (setting) -> predicate on a StartReport that ends the multistart at the first start (in start
    #: order) meeting it, or None
    stop_when: Callable[[Setting], Callable[[Any], bool] | None] = _no_early_stop
    samples_hint: str = "[solver] samples"
    relax_hint: str = "Loosen those requirements or widen the bounds of the design variables."
    #: (result of a run with status infeasible or failed) -> more words for its exit-3 message, or None
    explain_failure: Callable[[Any], str | None] | None = None
