"""The kind contract: what a kind is (:class:`Kind`), and what its solve side declares (:class:`Solving`).

A kind is one folder, ``synthesis/kinds/<kind>/``, whose package defines a subclass of :class:`Kind` and exports an
instance (``KIND``; a folder holding two kinds exports ``KINDS``).  The registry (:mod:`synthesis.kinds`) finds the
built-in kinds by their folders and other packages' kinds through the ``agrisynth.kinds`` entry-point group.  The
class holds the kind's name, summary and objectives; its methods import the kind's heavy modules when called, so
listing kinds imports none of them and a run imports only its own kind.  docs/ARCHITECTURE.md walks through adding
a kind.

For ``agrisynth studio`` a kind gives its check on a coarser grid (``coarse_check``: a :class:`CoarseCheck`, what
the page evaluates while a slider moves; default: the check on its [solver] sample counts / 10), the mechanism's
poses where its check's facts hold none (``poses``: a :class:`Poses`), and, when its spec may leave part of the
design to the kind (a convex fit of its path's control points), that design written out as free variables
(``explicit_design``; ``solved.toml`` uses it too).  The studio itself names no kind.

A kind that solves returns a :class:`Solving` from ``solving()``: the pieces the one multistart driver
(:mod:`synthesis.core.solve`) needs, none of which names a solver:

    prepare(spec)              anything worked out once per run (a fitted law, a scene), picklable
    build(setting, elastic)    the kind's NLP (a :class:`KindNLP`): ``names``, ``bounds``
                               (n x 2), ``init``, ``compiled`` (the :class:`~synthesis.core.ipopt.CompiledNLP` an
                               elastic diagnosis reads) and ``solve(start, x_design) -> StartOutcome``; built once
                               per process.  Usually the core's: ``declared(problem)``, the kind declaring its
                               problem and its design and start maps (:mod:`synthesis.core.declared`)
    recheck(setting, outcome)  the rules of a returned design on floats, 10x finer (a :class:`Recheck`)
    finish(setting, best)      the result's design, objective, trajectory and kind facts (:class:`Finished`)
    baseline_rules(setting)    the rule table of the spec's given design (or None if it cannot be evaluated)
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

if TYPE_CHECKING:
    from pydantic import BaseModel as SpecModel

    from synthesis.core.bench_case import BenchCase
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec

#: (result of one run, path) -> writes one figure or export of the kind
FigureWriter = Callable[["Result", Path], None]
#: (results compared, output folder) -> the file names written: the kind's overlay figures
CompareWriter = Callable[[list, Path], list]


class Kind(ABC):
    """One problem kind: what agrisynth knows about a mechanism (docs/ARCHITECTURE.md, "The kind contract").

    A kind is a subclass with its name, summary, objectives and example as class attributes, and methods that
    return its parts.  A kind's package defines the subclass in its ``__init__`` and imports its heavy modules
    (check, NLP, plots) inside the methods, so that listing kinds imports none of them and a run imports only its
    own kind.  ``check`` and ``spec_model`` are required; the rest have defaults meaning "the kind has none".
    """

    #: the spec's ``kind = "..."``
    name: str
    #: one line: the mechanism and its seed paper
    summary: str
    #: objective name -> one-line meaning (the first is the default); empty for a kind that only checks
    objectives: dict[str, str] = {}
    #: a library spec to try, relative to the problem library (None: none)
    example: str | None = None
    #: the library specs (relative to the problem library) the bench's generic studies run on by default
    #: (``--quick``: the first); empty, with no bench methods of its own, when the kind has no bench
    bench_specs: tuple[str, ...] = ()
    #: the unit of design variables the spec model gives none (a path's control points: "mm"); "" for none
    design_unit: str = ""
    #: why a ``[tolerance]`` table in ``solve`` is refused for this kind (one clause, said before anything is built);
    #: None: the robust transcription takes it
    robust_refusal: str | None = None
    #: rule name -> what fixes its value where no design variable moves it (:class:`FixedBy`: the spec field of the
    #: input, the field of the rule's limits), named by the pre-solve refusal of such a rule violated
    #: (:mod:`synthesis.core.pinned`) and by the exit-3 message; a rule not named here is described by the fixed design
    #: variables it reads
    fixed_by: dict[str, FixedBy] = {}
    #: design variables that others of the design determine, so a tolerance box (``agrisynth tolerance``, a robust
    #: solve) moves each only with them, never alone: variable -> {other: d variable / d other}.  A box that moved the
    #: clamp cam's four timing segments each alone drew cams whose segments do not fill one turn (no cam at all): its
    #: near dwell closes the turn, -1 for each other segment.
    follows: dict[str, dict[str, float]] = {}

    @abstractmethod
    def spec_model(self) -> type[SpecModel]:
        """The pydantic model a spec of this kind validates against."""

    @abstractmethod
    def check(self, loaded: LoadedSpec) -> Result:
        """Evaluate the spec's given design against every rule (a Result with status "evaluated")."""

    def solving(self) -> Solving | None:
        """The solve side (:class:`Solving`); None for a kind that only checks."""
        return None

    def figures(self) -> dict[str, FigureWriter]:
        """File name -> writer(result, path) of the kind's figures and exports for one run."""
        return {}

    def compare_figures(self) -> CompareWriter | None:
        """The overlay-figure writer of ``agrisynth compare``: (results, folder) -> the file names written."""
        return None

    def bench_cases(self, specs: list[LoadedSpec] | None, seed: int = 0) -> list[BenchCase] | None:
        """A kind with bench methods of its own: its cases on the given specs (None: its default set).  None (the
        default): the bench's generic studies on the given specs or on :attr:`bench_specs`."""
        return None

    def bench_studies(self) -> dict[str, Callable[[], list[dict]]]:
        """Extra rows of the kind's first generic bench case: study name -> rows (planting's derivative errors)."""
        return {}

    def coarse_check(self) -> CoarseCheck | None:
        """The check on a coarser grid for the studio while a slider moves; None: the check with every [solver]
        sample count divided by 10 (:func:`synthesis.core.coarse.of_kind`)."""
        return None

    def poses(self) -> Poses | None:
        """The mechanism's poses for the studio's drawing where the check's facts hold none; None: not needed."""
        return None

    def explicit_design(self, loaded: LoadedSpec, data: dict) -> dict:
        """The spec file data with a design the spec may leave to the kind (a convex fit of its path's control
        points) written out as free variables, so it solves and checks the same and every variable has a place in
        the file (the studio's sliders, solved.toml); the data itself (the same object) when specs always hold their
        whole design."""
        return data

    def bounds_read(self, spec: Any) -> list[str]:
        """The free design variables whose bounds the kind reads besides their value (clamp_cam's spring-shaped law
        is fitted from the spring's stiffness bound and preload range): solved.toml starts each at its solved value
        with its bounds kept, so `check` of it evaluates the solve's design under the same law.  None by default."""
        return []

    def design_affine(self, spec: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(d0, J): the design is d0 + J z for the NLP's first ``n`` decision entries z; the identity by default."""
        return np.zeros(n), np.eye(n)

    def answer_details(self, result: Result) -> dict:
        """What a result holds of its answer beyond ``design`` that :meth:`KindNLP.answer_start` reads; none here."""
        return {}

    def headline(self, result: Result) -> list[str]:
        """The figures an engineer looks at first, one short line each, for the terminal summary and the report's
        first screen (a path's error per target, its rms and maximum); none by default."""
        return []

    def result_tables(self, result: Result) -> list[ResultTable]:
        """Tables of the result's own figures for the report, below its headline (a path's error per target); none
        by default."""
        return []

    def rule_fixed_by(self, rule_name: str) -> FixedBy | None:
        """What fixes a rule's value where no design variable moves it, by the rule's name as the problem gives it;
        by default :attr:`fixed_by` of it, a rule held at an operating scenario (``<rule>@<condition>=<value>``) or one
        of a numbered family (``<rule>[0]``) being its rule's.  A kind whose rule names carry a part's name (a
        tube's) overrides it."""
        base = rule_name.split("@", 1)[0]
        return self.fixed_by.get(base) or self.fixed_by.get(base.split("[", 1)[0])

    @property
    def solves(self) -> bool:
        """Whether the kind has a solve side, read without importing it (it overrides :meth:`solving`)."""
        return type(self).solving is not Kind.solving

    @property
    def benches(self) -> bool:
        """Whether the kind has bench cases, read without importing them (its bench specs or methods)."""
        return bool(self.bench_specs) or type(self).bench_cases is not Kind.bench_cases

    @property
    def writes_explicit_design(self) -> bool:
        """Whether a spec may leave part of the design to the kind (it overrides :meth:`explicit_design`)."""
        return type(self).explicit_design is not Kind.explicit_design

    def solving_with(self, solving: Solving) -> Kind:
        """The same kind solving with another solve side (a transform of this kind's: the tolerance-robust box,
        the operating envelope); everything else is this kind's."""
        return SolvingReplaced(self, solving)


class SolvingReplaced(Kind):
    """A kind whose solve side a transform replaced (:meth:`Kind.solving_with`); the rest is the base kind's."""

    def __init__(self, base: Kind, solving: Solving):
        self.base, self._solving = base, solving
        self.name, self.summary, self.objectives, self.example = base.name, base.summary, base.objectives, base.example
        self.bench_specs = base.bench_specs
        self.design_unit, self.robust_refusal = base.design_unit, base.robust_refusal
        self.fixed_by, self.follows = base.fixed_by, base.follows

    def spec_model(self) -> type[SpecModel]:
        return self.base.spec_model()

    def check(self, loaded: LoadedSpec) -> Result:
        return self.base.check(loaded)

    def solving(self) -> Solving:
        return self._solving

    def figures(self) -> dict[str, FigureWriter]:
        return self.base.figures()

    def compare_figures(self) -> CompareWriter | None:
        return self.base.compare_figures()

    def bench_cases(self, specs: list[LoadedSpec] | None, seed: int = 0) -> list[BenchCase] | None:
        return self.base.bench_cases(specs, seed)

    def bench_studies(self) -> dict[str, Callable[[], list[dict]]]:
        return self.base.bench_studies()

    def coarse_check(self) -> CoarseCheck | None:
        return self.base.coarse_check()

    def poses(self) -> Poses | None:
        return self.base.poses()

    def explicit_design(self, loaded: LoadedSpec, data: dict) -> dict:
        return self.base.explicit_design(loaded, data)

    def bounds_read(self, spec: Any) -> list[str]:
        return self.base.bounds_read(spec)

    def design_affine(self, spec: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        return self.base.design_affine(spec, n)

    def answer_details(self, result: Result) -> dict:
        return self.base.answer_details(result)

    def headline(self, result: Result) -> list[str]:
        return self.base.headline(result)

    def rule_fixed_by(self, rule_name: str) -> FixedBy | None:
        return self.base.rule_fixed_by(rule_name)

    def result_tables(self, result: Result) -> list[ResultTable]:
        return self.base.result_tables(result)

    @property
    def benches(self) -> bool:
        return self.base.benches

    @property
    def writes_explicit_design(self) -> bool:
        return self.base.writes_explicit_design


@dataclass(frozen=True)
class ResultTable:
    """A table of a result's own figures for the report (:meth:`Kind.result_tables`): its title, the column headings
    (each with its unit) and the rows (numbers or text; None where there is no number)."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple, ...]


def own_half_width_refused(follower: str, others) -> str:
    """Why a tolerance box takes no half-width of a variable others determine (:attr:`Kind.follows`), in every
    command's words."""
    return (f"{follower} follows {', '.join(others)} (the kind holds it to them): its half-width is theirs, so give "
            f"theirs and not its own")


@dataclass(frozen=True)
class FixedBy:
    """What fixes a rule's value where no design variable moves it (:attr:`Kind.fixed_by`)."""

    inputs: str     # the spec field whose value is the rule's (``[soil] analysis_depth``)
    limits: str     # the spec field of the rule's limits (``[rules] depth``)


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


def figure_text(value, unit: str = "", digits: int = 3) -> str:
    """A figure of a kind's :meth:`Kind.headline`: ``value`` to ``digits`` significant digits with its unit ("1.59
    mm"), "-" where there is none (a result's null: not measured)."""
    if value is None or isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return "-"
    text = f"{value:.{digits}g}"
    return f"{text} {unit}" if unit else text


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


class KindNLP(ABC):
    """What a kind's ``Solving.build`` returns: its NLP, built once per process and solved once per start.

    The attributes every kind sets: ``names`` (the decision variables a start is drawn in), ``bounds`` (n x 2),
    ``init`` (the spec's given design in those variables) and ``compiled`` (the
    :class:`~synthesis.core.ipopt.CompiledNLP` an elastic diagnosis reads; None for a spec with nothing to
    optimise).  The rest have defaults a kind overrides where it differs."""

    names: list[str]
    bounds: np.ndarray
    init: np.ndarray
    compiled: Any = None
    #: True when ``solve`` may ignore the design it is given (the kind draws its own starts): no start is then
    #: solved from the elastic re-solve's design
    builds_its_own_starts: bool = False
    #: IPOPT problems solved in turn after ``compiled`` (a kind fitting in stages); each is built like it
    stages: Sequence[Any] = ()
    #: a second, reduced form of the problem the kind solves first where it applies (None: none); a transform
    #: that needs the whole problem (the tolerance box) drops it with :meth:`whole_problem_only`
    configuration: Any = None
    #: True when a start's design is mapped before it is solved (e.g. pulled into the region where the linkage
    #: assembles), so the starts IPOPT solves from are not the uniform draws the confidence statement assumes
    maps_its_starts: bool = False

    @property
    def design_names(self) -> list[str]:
        """The result design's key of each of ``names`` (the same names unless the kind's differ)."""
        return self.names

    def x_of(self, design: dict) -> np.ndarray:
        """The decision variables of a result design (its keys: :attr:`design_names`)."""
        return np.array([design[n] for n in self.design_names], dtype=float)

    def whole_problem_only(self) -> None:
        """Solve the whole problem from every start: drop the reduced form (:attr:`configuration`)."""
        self.configuration = None

    def answer_start(self, design: dict, x0: np.ndarray, p: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(x0, p) with the auxiliaries an answer holds (``design`` beyond the ``n`` design entries) put in place
        of the start's guesses, so its rules are read at the answer; the start unchanged by default."""
        return x0, p

    @abstractmethod
    def solve(self, start: int, x_design: np.ndarray) -> Any:
        """One start from ``x_design`` (in ``names``): a :class:`~synthesis.core.outcome.StartOutcome`."""


@dataclass(frozen=True)
class Setting:
    """What a kind's solve pieces receive: the validated spec, the run's seed and what ``prepare`` made, and the
    transforms of the problem the kind declares (docs/ARCHITECTURE.md, "The kind contract"), explicit arguments of
    its build that :func:`synthesis.core.declared.compile_problem` applies."""

    spec: Any
    seed: int = 0
    data: Any = None
    #: every operating condition the kind reads declared as an :class:`~synthesis.core.problem.Operating` symbol,
    #: even where no envelope samples it (resolved at its nominal value): the tolerance analysis then has every
    #: rule's derivative w.r.t. it.  False (a solve): the kind writes them as numbers, the NLP it always was
    operating_symbols: bool = False
    #: the tolerance box the kind's problems are held in (problem -> :class:`~synthesis.core.problem.Tolerance`):
    #: a robust solve (:mod:`synthesis.tolerance.robust`); None: the nominal problem
    tolerance: Callable[[Any], Any] | None = None
    #: False: the problems are compiled without an IPOPT instance (evaluated, never solved: the tolerance analysis)
    solver: bool = True
    #: how the problems are solved (:class:`~synthesis.core.ipopt.SolveMethod`: finite differences, another length
    #: unit, a peer method instead of IPOPT: the bench's and tests' studies); None: IPOPT, exact derivatives
    method: Any = None
    #: the starts are a ``--starts auto`` run's in the kind's own auto order (:attr:`Solving.auto_order`); False:
    #: the fixed order of ``--starts N``
    auto_order: bool = False


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


def _no_auto_order(setting) -> bool:
    return False


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
    #: (setting) -> True: a ``--starts auto`` run numbers its starts in an order of the kind's own, in which start i
    #: is the same whatever the batch (its NLP is built with ``Setting.auto_order``; a start's decision-variable row
    #: is drawn for its index alone), so each batch solves only its new starts and the kind decides which come first
    #: (:class:`synthesis.core.solve.AutoStarts`); False: every batch is the whole ``--starts N`` run
    auto_order: Callable[[Setting], bool] = _no_auto_order
    samples_hint: str = "[solver] samples"
    relax_hint: str = "Loosen those requirements or widen the bounds of the design variables."
    #: (result of a run with status infeasible or failed) -> more words for its exit-3 message, or None
    explain_failure: Callable[[Any], str | None] | None = None
