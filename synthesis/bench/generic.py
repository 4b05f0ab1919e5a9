"""The bench studies every solving kind gets from its declared Problem, with no code of its own.

A kind's default bench set (``Kind.bench``) is a few library specs; :func:`library_cases` turns each
into a :class:`~synthesis.bench.BenchCase` whose methods all run the kind's own multistart
(:func:`synthesis.core.solve.run_multistart`: its starts, its fine-grid re-check, its verdict), with
``starts`` capped at the study's start count and one worker:

ipopt_multistart          IPOPT with CasADi's exact derivatives (the reference of every ratio)
ipopt_finite_differences  the same NLP with IPOPT fed function values only: forward differences of f
                          and g and a limited-memory Hessian (``SolveMethod(derivatives="finite_difference")``)
ipopt_compiled            (``bench --compiled``) ipopt_multistart with the NLP's functions and exact derivatives
                          compiled to C (``SolveMethod(compiled=...)``): the same runs, evaluated faster
slsqp                     scipy.optimize.minimize(method="SLSQP") on the same transcribed NLP (the kind's
                          f and g as numeric CasADi Functions, scipy's finite differences, the rows as
                          scipy constraints, maxiter = the spec's max_iter, ftol 1e-9), from the same starts
                          (the runner of :class:`synthesis.core.ipopt.SolveMethod`), stopped at the target or its time
                          budget (``slsqp_budget_s`` per run, shared by the starts)
differential_evolution    scipy's differential_evolution over the same NLP's variables (its bounds; rows
                          as a NonlinearConstraint), one run from the spec's start (x0), default strategy
                          and population, no polish, stopped at the target or the time budget; a variable with no finite
                          bound (a length unbounded above, an epigraph or slack variable) is searched within
                          one decade of its start (:func:`de_bounds`)

Objectives are compared minimised (a maximising kind's objective is negated and the case note says
so); a run reaches the target when every rule holds on the fine grid and its objective is within
TOLERANCE of the best known (see :mod:`synthesis.bench`), and every method is timed to the *first*
moment it met the target (:func:`synthesis.bench.time_to_target`), so no ratio is ever taken between
runs that ended at different objectives or at different moments past the target:

* IPOPT methods: the best-so-far trace of :func:`measure` (designs meeting every rule, at the end of
  each start) gives the end of the first start meeting the target, its own re-check left out as a peer's
  target checks are -- the time of a multistart that stops there; the run itself is not stopped (the sample sweep
  reuses the AD runs whole);
* peers: :class:`TargetWatch` checks the iterate of every SLSQP iteration / the best member of every
  differential_evolution generation against the target with the kind's own mapping and re-check, and the
  peer stops at the first that meets it (SLSQP: StopIteration from its callback; DE: its callback returns
  True), its multistart with it; the checks' time is left out of every time and budget and reported as
  ``details["target_check_s"]``.

Two studies besides: :func:`sample_sweep` (the solve at scaled sample counts of every ``[solver]``
``*samples*`` setting: time, iterations, fine-grid violation, gap to the finest) and the build/solve
split every multistart run reports (``details``: ``build_s`` = prepare + NLP build, ``nlp_build_s`` = the NLP
build alone, ``ipopt_s`` = sum of the solver's start times, ``recheck_s`` = the rest of the starts' time, mostly
the fine-grid re-check).
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time
from typing import Any, Callable

import numpy as np
from scipy.optimize import NonlinearConstraint, differential_evolution, minimize

from synthesis import kinds
from synthesis.bench.case import BenchCase, MethodRun
from synthesis.core.ipopt import NLPOutcome, answered_by, compiled_in, solved_with_method
from synthesis.core.kind import KindNLP, Setting
from synthesis.core.solve import _recheck, run_multistart
from synthesis.core.verdict import better, report_of
from synthesis.errors import AgrisynthError
from synthesis.library import LIBRARY
from synthesis.spec import load_spec


#: target = best known + max(ABS_TOLERANCE, REL_TOLERANCE x |best known|)
REL_TOLERANCE = 1e-6
ABS_TOLERANCE = 1e-9
#: a sample count "reaches" when the fine-grid worst violation is at most this (normalised by rule scale)
VIOLATION_TARGET = 1e-6
REFERENCE_SEED_OFFSET = 1000


@dataclasses.dataclass(frozen=True)
class StudySettings:
    """How much each study runs (``agrisynth bench`` full or ``--quick``)."""

    starts: int = 4                      # multistart starts of every method (at most the spec's)
    factors: tuple[float, ...] = (0.25, 0.5, 1.0, 2.0, 4.0)   # sample-count factors of the sweep
    sweep_repeats: int = 1
    peers: tuple[str, ...] = ("slsqp", "differential_evolution")
    de_budget_s: float = 10.0            # differential_evolution: stopped at this wall time (one run)
    slsqp_budget_s: float = 15.0         # SLSQP: this wall time shared by its starts, each stopped at its share
    #: the sweep skips a sample count whose predicted time (the last count's median x the count ratio)
    #: exceeds this; bench.md lists what it skipped
    sweep_budget_s: float = 30.0
    reference: bool = True               # best known from an untimed multistart (the spec's starts, at most ...)
    reference_starts: int = 16           # ... this many)
    #: a folder: the method ipopt_compiled too (IPOPT's functions compiled to C and cached there; the untimed
    #: warm-up compiles them)
    compiled: str | None = None
    #: a kind's default set: its first library problem only (else all of :attr:`Kind.bench_specs`)
    first_problem_only: bool = False


FULL = StudySettings()
#: --quick: one start, two sample counts (the spec's own is the AD run, not solved again), no peers, no
#: reference solve, one run per method, the first problem of each kind, no extreme matrix
QUICK = StudySettings(starts=1, factors=(0.5, 1.0), peers=(), reference=False, sweep_budget_s=30.0,
                      first_problem_only=True)


def tolerance(best: float) -> float:
    return max(ABS_TOLERANCE, REL_TOLERANCE * abs(best))


# ---------------------------------------------------------------------------- one measured multistart

def _with_solver(loaded, **update):
    spec = loaded.model
    return dataclasses.replace(loaded, model=spec.model_copy(update={"solver": spec.solver.model_copy(update=update)}))


class TargetWatch:
    """Time to target of one measured run: the run's clock (its own time, the checks below left out), the
    best-so-far trace of designs meeting every rule, and the check of a peer's iterate against the target.

    :meth:`meets` maps an iterate w of the NLP a peer is solving to the kind's design and objective with the
    same functions the run's end uses -- the kind's NLP's ``solve`` (its start's own mapping, the solver
    replaced by one returning w) and its ``recheck`` (:func:`synthesis.core.verdict.report_of`) -- so a
    design meets the target mid-run exactly when it would at the end.  The peers call it once per SLSQP
    iteration / differential_evolution generation, an iterate unchanged since the last call not again
    (DE's best member often survives generations); its time (``check_s``) is left out of the run's times
    and budgets and reported apart, as are the seconds of solver setups the bench replaced (``discarded_s``:
    :meth:`synthesis.core.ipopt.CompiledNLP.reconfigure`)."""

    def __init__(self, target: float, recheck: Callable | None, t0: float):
        self.target, self.recheck, self.t0 = target, recheck, t0
        self.sign = 1.0
        self.trace: list[tuple[float, float]] = []
        self.check_s = 0.0
        self.discarded_s = 0.0
        self.checks = 0
        self.hit_s: float | None = None
        #: seconds of the kind's re-check of the start that finished last (measure's on_start leaves it out)
        self.last_recheck_s = 0.0
        self._nlp = self._start = self._x0 = None
        self._stages: dict[int, Any] = {}
        self._last: tuple | None = None      # (iterate, its answer): an unchanged iterate is not checked again
        #: start -> the largest miss of the NLP's equality rows by a peer's answer (its last stage's)
        self.equality_miss: dict[int, float] = {}

    def holds_equalities(self, start: int) -> bool:
        """Whether start's answer holds the NLP's equality rows (IPOPT's always do: no miss recorded)."""
        return self.equality_miss.get(start, 0.0) <= EQUALITY_TOL

    def holds(self, report) -> bool:
        """A start's report holds every rule and (a peer's) the NLP's equality rows."""
        return report.satisfied and self.holds_equalities(report.outcome.start)

    @property
    def excluded_s(self) -> float:
        """Seconds of the run that were the bench's, not the method's: the target checks, replaced setups."""
        return self.check_s + self.discarded_s

    def now(self) -> float:
        """Seconds since the run's start, the bench's own seconds left out."""
        return time.perf_counter() - self.t0 - self.excluded_s

    @property
    def checking(self) -> bool:
        return math.isfinite(self.target) and self._nlp is not None

    def begin(self, nlp, start: int, x0) -> None:
        """The kind's NLP is solving ``start`` from ``x0`` (its own coordinates)."""
        self._nlp, self._start, self._x0 = nlp, start, x0
        self._stages = {}

    def finished_stage(self, compiled, outcome) -> None:
        """A solve of ``compiled`` (a stage of the start, for a kind solving several NLPs in turn) returned."""
        self._stages[id(compiled)] = outcome

    def add(self, at: float, objective: float) -> None:
        """A design meeting every rule at ``at`` s with ``objective`` (minimised): into the best-so-far trace."""
        if not self.trace or objective < self.trace[-1][1]:
            self.trace.append((at, objective))
        if self.hit_s is None and objective <= self.target:
            self.hit_s = at

    def meets(self, compiled, w: np.ndarray, p: np.ndarray) -> bool:
        """The iterate w of ``compiled``'s NLP maps to a design meeting every rule on the fine grid with its
        objective at or below the target (and enters the trace when it meets every rule)."""
        if not self.checking:
            return False
        w = np.array(w, float)
        key = (id(compiled), self._start, w.tobytes())
        if self._last is not None and self._last[0] == key:     # the same iterate again (DE's best member kept)
            return self._last[1]
        t = time.perf_counter()
        at = t - self.t0 - self.excluded_s
        met = self._meets(compiled, w, p, at)
        self.check_s += time.perf_counter() - t
        self.checks += 1
        self._last = (key, met)
        return met

    def _meets(self, compiled, w: np.ndarray, p: np.ndarray, at: float) -> bool:
        if equality_miss(compiled, w, p) > EQUALITY_TOL:
            return False
        try:
            f = float(compiled.f_function(w, p))

            def iterate(c, start, w0, p_):
                if c is compiled:
                    return NLPOutcome(start, w, f if math.isfinite(f) else math.inf, "iterate", False, 0, 0.0, "",
                                      np.zeros(len(c.t.lbg)))
                done = self._stages.get(id(c))     # an earlier stage of this start: as it ended
                return done if done is not None else NLPOutcome(start, np.asarray(w0, float), math.inf, "not run",
                                                                False, 0, 0.0, "", np.zeros(len(c.t.lbg)))

            with answered_by(compiled_in(self._nlp), iterate):      # the start's solves answered by w
                outcome = self._nlp.solve(self._start, self._x0)
            report = report_of(outcome, self.recheck)
        except (AgrisynthError, ValueError, ArithmeticError, RuntimeError):
            return False
        objective = self.sign * report.outcome.objective
        if not (report.satisfied and report.worst_violation == 0 and math.isfinite(objective)):
            return False
        self.add(at, objective)
        return objective <= self.target


#: a peer's answer holds the NLP's equality rows to this (relative to max(1, |row value|)), as IPOPT's do (to its
#: constraint tolerance, 1e-8 where a kind asks it): the re-check's rules may allow a band about a pinned value (a
#: crank-rocker's |K - K_required| <= 0.005) that the NLP holds exactly, and an SLSQP iterate inside the band beat
#: IPOPT's exact optimum (gap 0.063 deg, a trial); at 1e-6 differential_evolution's answer to the guide tube's
#: equal-landing-time row missed it by 9.0e-7 s, 7.9e-5 lower in objective than the NLP's optimum (80x the
#: target's tolerance), and was taken for the best known
EQUALITY_TOL = 1e-8


def equality_miss(compiled, w, p) -> float:
    """The largest miss of ``compiled``'s equality rows at w, relative to max(1, |row value|) (0: none)."""
    lbg, ubg = np.asarray(compiled.t.lbg, float), np.asarray(compiled.t.ubg, float)
    eq = np.isfinite(lbg) & (lbg == ubg)
    if not eq.any():
        return 0.0
    g = np.asarray(compiled.g_function(w, p), float).ravel()[eq]
    miss = np.abs(g - lbg[eq]) / np.maximum(1.0, np.abs(lbg[eq]))
    return float(np.max(np.nan_to_num(miss, nan=np.inf)))


class _AnnouncedNLP(KindNLP):
    """The kind's NLP as the multistart sees it, each start's solve announced to the watch first; everything the
    contract reads is the kind's own NLP's."""

    def __init__(self, nlp: KindNLP, watch: TargetWatch):
        self._nlp, self._watch = nlp, watch
        self.names, self.bounds, self.init, self.compiled = nlp.names, nlp.bounds, nlp.init, nlp.compiled
        self.builds_its_own_starts, self.stages, self.configuration = (nlp.builds_its_own_starts, nlp.stages,
                                                                       nlp.configuration)

    @property
    def design_names(self) -> list[str]:
        return self._nlp.design_names

    def x_of(self, design: dict) -> np.ndarray:
        return self._nlp.x_of(design)

    def whole_problem_only(self) -> None:
        self._nlp.whole_problem_only()
        self.configuration = None

    def answer_start(self, design: dict, x0: np.ndarray, p: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        return self._nlp.answer_start(design, x0, p, n)

    def solve(self, start, x0):
        self._watch.begin(self._nlp, start, x0)
        return self._nlp.solve(start, x0)


def watched_kind(kind, watch: TargetWatch, stop: bool):
    """The kind with its NLP announced to ``watch`` and, with ``stop``, its multistart ended at the first
    start whose re-checked design meets the target (besides the kind's own early stop)."""
    solving = kind.solving()

    def build(setting, elastic):
        nlp = solving.build(setting, elastic)
        watch.discarded_s += sum(compiled.discarded_s for compiled in compiled_in(nlp))
        return nlp if elastic else _AnnouncedNLP(nlp, watch)

    def recheck(setting, outcome):
        t = time.perf_counter()
        try:
            return solving.recheck(setting, outcome)
        finally:
            watch.last_recheck_s = time.perf_counter() - t

    def stop_when(setting):
        own = solving.stop_when(setting)
        if not stop:
            return own

        def stop_at_target(report) -> bool:
            at_target = (watch.holds(report) and math.isfinite(report.outcome.objective)
                         and watch.sign * report.outcome.objective <= watch.target)
            return at_target or (own is not None and own(report))
        return stop_at_target
    return kind.solving_with(dataclasses.replace(solving, build=build, stop_when=stop_when, recheck=recheck))


def measure(loaded, starts: int, seed: int, derivatives: str = "exact", runner: Callable | None = None,
            target: float = math.inf, stop_at_target: bool = False, compiled: str | None = None) -> MethodRun:
    """The kind's multistart on ``loaded`` (one worker), timed: objective (minimised), fine-grid worst
    violation, best-so-far trace of designs meeting every rule (its first point at or below ``target`` is the
    run's time to target), and the build/solve split and iterations in ``details``.

    ``derivatives``: IPOPT's ("exact" or "finite_difference").  ``runner(compiled, start, w0, p, watch)`` (a peer):
    answers every start instead of IPOPT; ``target`` finite, each of its iterates is checked against it
    (:class:`TargetWatch`, handed to it; the checks' time is left out of every time and reported as
    ``details["target_check_s"]``), and ``stop_at_target`` ends the peer's start at the first iterate meeting it
    and the multistart at that start.  IPOPT (no runner): a start's time to target is its end (its own re-check
    left out, as a peer's checks are), the time a multistart stopping at the first start meeting the target would
    take; the run itself is not stopped.  ``compiled`` (a folder): IPOPT's functions compiled to C and cached there
    (:mod:`synthesis.core.compiled_code`)."""
    kind = kinds.get(loaded.kind)
    solving = kind.solving()
    spec = loaded.model
    t0 = time.perf_counter()
    watch = TargetWatch(target if runner is not None else math.inf, None, t0)
    method: dict[str, Any] = {"derivatives": derivatives}
    if runner is not None:
        method["runner"] = _recording(runner, watch)
    if compiled is not None:
        method["compiled"] = compiled
    setting = Setting(spec, seed, solving.prepare(spec))
    watch.sign = -1.0 if solving.maximise(setting) else 1.0
    watch.recheck = lambda outcome: _recheck(solving, setting, outcome)

    def on_start(report, best) -> None:
        if watch.holds(report):            # add keeps the best so far: the run's best-so-far trace
            # at the moment the solver returned this start's design, before the re-check confirming it (a peer's
            # time to target is an iterate's, whose check is left out: so is this one's)
            watch.add(watch.now() - watch.last_recheck_s, watch.sign * report.outcome.objective)

    measured = watched_kind(solved_with_method(kind, **method), watch, stop_at_target and runner is not None)
    run = run_multistart(measured, setting, starts=starts, workers=1, on_start=on_start)
    total = time.perf_counter() - t0 - watch.excluded_s
    out = _measured_run(run, watch, total, spec, peer=runner is not None, stop_at_target=stop_at_target)
    out.details["objective_unit"] = _objective_unit(solving, setting, run)     # untimed: the answer's own unit
    return out


def _objective_unit(solving, setting: Setting, run) -> str | None:
    """The unit of the kind's objective as its result states it (its ``finish`` of the run's best start), or None
    where the answer cannot be finished."""
    try:
        unit = solving.finish(setting, run.best).objective.get("unit")
    except Exception:       # noqa: BLE001 - a unit is a label: a best start the kind cannot finish has none
        return None
    return unit if isinstance(unit, str) else None


def _recording(runner: Callable, watch: TargetWatch) -> Callable:
    """The method's runner: the peer, handed the watch, each answer recorded as its start's stage (the start's
    answer is its last stage's, for a kind solving several NLPs in turn) with its miss of the equality rows."""
    def run(compiled, start, w0, p):
        out = runner(compiled, start, w0, p, watch)
        watch.finished_stage(compiled, out)
        watch.equality_miss[start] = equality_miss(compiled, out.x, p)
        return out
    return run


def _measured_run(run, watch: TargetWatch, total: float, spec, peer: bool, stop_at_target: bool) -> MethodRun:
    """The MethodRun of a measured multistart: its best start holding the NLP's equality rows, and the details."""
    best, sign = run.best, watch.sign
    if not watch.holds(best):              # a peer's answer off the NLP's equality rows is not its answer
        for report in run.reports:
            if watch.holds(report) and (not watch.holds(best) or better(report, best, sign < 0)):
                best = report
    unheld = not watch.holds(best) and best.satisfied
    ipopt_s = sum(r.outcome.wall_s for r in run.reports)
    objective = sign * best.outcome.objective
    iterations = [r.outcome.iterations for r in run.reports]
    details = {
        "starts": len(run.reports), "successes": sum(bool(r.outcome.success) for r in run.reports),
        "satisfied_starts": sum(r.satisfied for r in run.reports),
        "iterations": iterations, "median_iterations": float(statistics.median(iterations)),
        "best_iterations": best.outcome.iterations, "return_status": best.outcome.return_status,
        "best_start": best.outcome.start, "maximised": sign < 0,
        # run.wall_s includes building the NLP (run.build_s, one worker here): the build is the rest of the total
        "build_s": total - (run.wall_s - run.build_s - watch.check_s), "ipopt_s": ipopt_s,
        "recheck_s": max(run.wall_s - run.build_s - watch.check_s - ipopt_s, 0.0), "nlp_build_s": run.build_s,
        "samples": sample_settings(spec),
    }
    if peer:
        details |= {"target_checks": watch.checks, "target_check_s": watch.check_s,
                    "stopped_at_target": watch.hit_s is not None and stop_at_target,
                    "equality_miss": max(watch.equality_miss.values(), default=0.0)}
    if unheld:       # no start held them: its rules may pass, but it did not solve the NLP the others did
        objective = math.inf
    return MethodRun(objective if math.isfinite(objective) else math.inf, best.worst_violation, watch.trace, details,
                     trace_satisfied=True, excluded_s=watch.excluded_s)


# ---------------------------------------------------------------------------- peers on the same NLP

def _nlp_functions(compiled, p):
    """f(w), g(w) as numbers (the last g is cached: SLSQP asks for the rows twice per point)."""
    cache: dict = {}

    def f(w):
        v = float(compiled.f_function(w, p))
        return v if math.isfinite(v) else 1e30

    def g(w):
        key = w.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = np.nan_to_num(np.asarray(compiled.g_function(w, p), float).ravel(), nan=1e30)
        return cache[key]
    return f, g


def slsqp_runner(compiled, start: int, w0: np.ndarray, p: np.ndarray, budget_s: float = math.inf,
                 watch: TargetWatch | None = None):
    """scipy SLSQP on the transcribed NLP from the kind's start; function values only (scipy's differences);
    stopped (StopIteration from its callback, which scipy honours for SLSQP) once ``budget_s`` of wall time
    has passed, or -- measured with a target (``watch``) -- at the first iteration whose iterate meets the target
    (checked once per iteration; the check's time left out of the budget and the wall time)."""
    t = compiled.t
    f, g = _nlp_functions(compiled, p)
    lbg, ubg = t.lbg, t.ubg
    eq = np.isfinite(lbg) & (lbg == ubg)
    lo, hi = np.isfinite(lbg) & ~eq, np.isfinite(ubg) & ~eq
    constraints = []
    if eq.any():
        constraints.append({"type": "eq", "fun": lambda w: g(w)[eq] - lbg[eq]})
    if lo.any() or hi.any():
        constraints.append({"type": "ineq", "fun": lambda w: np.concatenate([(g(w) - lbg)[lo], (ubg - g(w))[hi]])})
    bounds = [(a if math.isfinite(a) else None, b if math.isfinite(b) else None) for a, b in zip(t.lbw, t.ubw)]
    x0 = np.clip(w0, t.lbw, t.ubw)
    checked0 = watch.check_s if watch is not None else 0.0
    t0 = time.perf_counter()
    at_target = []

    def own_s() -> float:       # the run's own seconds: the target checks left out
        return time.perf_counter() - t0 - ((watch.check_s - checked0) if watch is not None else 0.0)

    def budget(xk) -> None:        # callback(x): scipy 1.17 prints a callback(intermediate_result) when it drops fixed variables
        if watch is not None and watch.meets(compiled, xk, p):
            at_target.append(True)
            raise StopIteration
        if own_s() > budget_s:
            raise StopIteration

    res = minimize(f, x0, method="SLSQP", bounds=bounds, constraints=constraints, callback=budget,
                   options={"maxiter": compiled.problem.max_iter, "ftol": 1e-9})
    wall = own_s()
    x = np.asarray(res.x, float)
    status = "SLSQP: stopped at the target" if at_target else f"SLSQP: {res.message}"
    return NLPOutcome(start, x, f(x), status, bool(res.success), int(res.nit), wall, "", np.zeros(len(lbg)))


def slsqp_with_budget(budget_s: float) -> Callable:
    """:func:`slsqp_runner` stopped at ``budget_s`` per start: ``runner(compiled, start, w0, p, watch=None)``."""
    return lambda compiled, start, w0, p, watch=None: slsqp_runner(compiled, start, w0, p, budget_s, watch)


def de_runner(budget_s: float, seed: int) -> Callable:
    """scipy differential_evolution on the transcribed NLP (one run from the start), stopped at ``budget_s``
    of wall time or -- measured with a target (the :class:`TargetWatch` it is handed) -- at the first generation
    whose best member meets the target (its callback returns True; checked once per generation, the check's time
    left out of the budget and the wall time): ``runner(compiled, start, w0, p, watch=None)``."""
    def run(compiled, start: int, w0: np.ndarray, p: np.ndarray, watch: TargetWatch | None = None):
        t = compiled.t
        lbw, ubw, derived = de_bounds(t.lbw, t.ubw, w0)
        f, g = _nlp_functions(compiled, p)
        free = ubw > lbw
        base = np.clip(np.asarray(w0, float), lbw, ubw)

        def full(z):
            w = base.copy()
            w[free] = z
            return w

        constraints = [NonlinearConstraint(lambda z: g(full(z)), t.lbg, t.ubg)] if len(t.lbg) else []
        checked0 = watch.check_s if watch is not None else 0.0
        t0 = time.perf_counter()
        at_target: list[np.ndarray] = []

        def own_s() -> float:
            return time.perf_counter() - t0 - ((watch.check_s - checked0) if watch is not None else 0.0)

        def generation(intermediate_result) -> bool:
            w = full(np.asarray(intermediate_result.x, float))
            if watch is not None and watch.meets(compiled, w, p):
                at_target.append(w)
                return True
            return own_s() > budget_s

        res = differential_evolution(lambda z: f(full(z)), list(zip(lbw[free], ubw[free])),
                                     constraints=constraints, x0=base[free], rng=seed, polish=False,
                                     callback=generation)
        wall = own_s()
        # stopped at the target: the member that met it (scipy returns the same best member)
        x = at_target[0] if at_target else full(np.asarray(res.x, float))
        note = f" (finite bounds derived from the start for {derived} variable(s): {DE_BOUNDS_RULE})" if derived else ""
        message = "stopped at the target" if at_target else res.message
        return NLPOutcome(start, x, f(x), f"differential_evolution: {message}{note}", bool(res.success),
                          int(res.nit), wall, "", np.zeros(len(t.lbg)))
    return run


#: how :func:`de_bounds` closes a bound that is infinite (bench.md and the case note repeat it)
DE_BOUNDS_RULE = ("a variable with an infinite bound searched within one decade of its start value w0 "
                  "([w0 / 10, 10 w0] for w0 > 0, else w0 -+ 10 max(1, |w0|)), within its own finite bound")


def de_bounds(lbw, ubw, w0) -> tuple[np.ndarray, np.ndarray, int]:
    """differential_evolution needs a finite box: a variable whose lower or upper bound is infinite (a length
    the kind leaves unbounded above, an epigraph or slack variable) gets :data:`DE_BOUNDS_RULE`'s interval
    around the spec's start; the variable's finite bound is kept.  (lower, upper, how many were derived)."""
    lo, hi = np.array(lbw, float), np.array(ubw, float)
    w0 = np.clip(np.asarray(w0, float), lo, hi)
    open_ = ~(np.isfinite(lo) & np.isfinite(hi))
    span = 10.0 * np.maximum(1.0, np.abs(w0))
    d_lo = np.where(w0 > 0, w0 / 10.0, w0 - span)
    d_hi = np.where(w0 > 0, w0 * 10.0, w0 + span)
    lo = np.where(open_ & ~np.isfinite(lo), d_lo, np.where(open_, np.maximum(lo, d_lo), lo))
    hi = np.where(open_ & ~np.isfinite(hi), d_hi, np.where(open_, np.minimum(hi, d_hi), hi))
    return lo, np.maximum(hi, lo), int(open_.sum())


# ---------------------------------------------------------------------------- sample counts

def sample_fields(model) -> dict[str, tuple[int, int, int]]:
    """``[solver]`` integer settings whose name says "samples": name -> (lowest, highest, multiple of)."""
    out = {}
    for name, info in type(model.solver).model_fields.items():
        if "samples" not in name or info.annotation is not int:
            continue
        lo, hi, mult = 1, 10**6, 1
        for m in info.metadata:
            lo = getattr(m, "ge", None) or lo
            hi = getattr(m, "le", None) or hi
            mult = getattr(m, "multiple_of", None) or mult
        out[name] = (lo, hi, mult)
    return out


def sample_settings(model) -> dict[str, int]:
    return {name: getattr(model.solver, name) for name in sample_fields(model)}


def scaled_samples(model, factor: float) -> dict[str, int]:
    """Every sample setting x factor, rounded to its multiple and kept within its allowed range."""
    out = {}
    for name, (lo, hi, mult) in sample_fields(model).items():
        n = max(1, round(getattr(model.solver, name) * factor / mult)) * mult
        out[name] = int(min(max(n, lo), hi))
    return out


def sample_sweep(loaded, settings: StudySettings, seed: int = 0,
                 tick: Callable[[str | None], None] = lambda what: None,
                 reuse: Callable[[], list[MethodRun]] | None = None) -> dict:
    """The solve at each factor of the spec's sample counts: median wall time, iterations, fine-grid
    worst violation and the objective's gap to the finest run; and the first count at which the
    violation falls (and stays) at or below VIOLATION_TARGET.

    ``reuse()``: runs already made at the spec's own counts with the same starts and seed (the case's
    ipopt_multistart runs), taken for that count instead of solving it again.  A count whose predicted
    time (the last count's median x the ratio of the factors) exceeds ``settings.sweep_budget_s`` is
    not run; the table's ``skipped`` lists it."""
    starts = min(settings.starts, loaded.model.solver.starts)
    own = tuple(sorted(sample_settings(loaded.model).items()))
    rows = []
    skipped = []
    seen = set()
    for factor in settings.factors:
        samples = scaled_samples(loaded.model, factor)
        key = tuple(sorted(samples.items()))
        if key in seen:
            continue
        seen.add(key)
        free = key == own and reuse is not None and len(reuse()) > 0     # measured already
        predicted = rows[-1]["median_s"] * factor / rows[-1]["factor"] if rows else 0.0
        if not free and predicted > settings.sweep_budget_s:
            for k in range(settings.sweep_repeats if key != own or reuse is None else 0):
                tick(f"{loaded.name}: samples {_samples_text(samples)} skipped (over budget)")
                tick(None)
            skipped.append({"factor": factor, "samples": samples, "predicted_s": predicted,
                            "budget_s": settings.sweep_budget_s})
            continue
        # the spec's own counts: the AD runs already made, those nearest their median first (the first alone was
        # the slowest of three in a trial, and the sweep's times then turned back)
        made = list(reuse()) if key == own and reuse is not None else []
        middle = statistics.median([r.wall_s for r in made]) if made else 0.0
        runs = sorted(made, key=lambda r: abs(r.wall_s - middle))[:settings.sweep_repeats]
        reused = len(runs)
        for k in range(len(runs), settings.sweep_repeats):
            tick(f"{loaded.name}: samples {_samples_text(samples)} {k + 1}/{settings.sweep_repeats}")
            runs.append(measure(_with_solver(loaded, **samples), starts, seed))
            tick(None)
        rows.append(_sweep_row(factor, samples, runs, reused))
    finest = rows[-1]["objective"] if rows else math.nan
    for row in rows:
        row["objective_gap"] = (abs(row["objective"] - finest) if math.isfinite(row["objective"]) and math.isfinite(finest)
                                else math.inf)
    return {"problem": loaded.name, "kind": loaded.kind, "starts": starts, "repeats": settings.sweep_repeats,
            "violation_target": VIOLATION_TARGET, "rows": rows, "skipped": skipped, "reaching": _reaching(rows)}


def _sweep_row(factor: float, samples: dict, runs: list[MethodRun], reused: int) -> dict:
    """A sample count's row: the median of its runs' times (build, IPOPT, re-check) and the typical run's figures."""
    walls = [r.details["build_s"] + r.details["ipopt_s"] + r.details["recheck_s"] for r in runs]
    median = float(statistics.median(walls))
    typical = min(runs, key=lambda r: abs(sum(r.details[k] for k in ("build_s", "ipopt_s", "recheck_s")) - median))
    return {"factor": factor, "samples": samples, "wall_s": walls, "median_s": median,
            "build_s": typical.details["build_s"], "ipopt_s": typical.details["ipopt_s"],
            "iterations": typical.details["iterations"], "median_iterations": typical.details["median_iterations"],
            "objective": typical.objective, "worst_violation": typical.worst_violation,
            "satisfied": typical.worst_violation == 0 and math.isfinite(typical.objective), "reused_runs": reused}


def _reaching(rows: list[dict]) -> dict | None:
    """The first sample count from which on the violation is at most VIOLATION_TARGET, or None."""
    for i, row in enumerate(rows):
        if all(r["worst_violation"] <= VIOLATION_TARGET for r in rows[i:]):
            return {"samples": row["samples"], "median_s": row["median_s"], "worst_violation": row["worst_violation"]}
    return None


def _samples_text(samples: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in samples.items())


# ---------------------------------------------------------------------------- the cases

def _method(loaded, starts: int, seed: int, keep: list | None = None, **how) -> Callable[[float], MethodRun]:
    """run(target): :func:`measure`; a peer (``runner``) checks its iterates against the target and stops there."""
    def run(target: float) -> MethodRun:
        if how.get("runner") is not None:
            out = measure(loaded, starts, seed, target=target, stop_at_target=True, **how)
        else:
            out = measure(loaded, starts, seed, **how)
        if keep is not None:
            keep.append(out)
        return out
    return run


def case_for(loaded, settings: StudySettings = FULL, seed: int = 0, studies: dict | None = None) -> BenchCase:
    """The generic bench case of one spec: IPOPT (AD), IPOPT (finite differences) and the peers, one
    sample sweep (``case.sweep``)."""
    starts = min(settings.starts, loaded.model.solver.starts)
    spec_seed = loaded.model.solver.seed + seed
    ad_runs: list[MethodRun] = []        # the sweep takes these for the spec's own sample counts
    methods = {"ipopt_multistart": _method(loaded, starts, spec_seed, ad_runs),
               "ipopt_finite_differences": _method(loaded, starts, spec_seed, derivatives="finite_difference")}
    if settings.compiled is not None:
        methods["ipopt_compiled"] = _method(loaded, starts, spec_seed, compiled=settings.compiled)
    if "slsqp" in settings.peers:
        methods["slsqp"] = _method(loaded, starts, spec_seed,
                                   runner=slsqp_with_budget(settings.slsqp_budget_s / max(starts, 1)))
    if "differential_evolution" in settings.peers:
        methods["differential_evolution"] = _method(loaded, 1, spec_seed,
                                                    runner=de_runner(settings.de_budget_s, spec_seed))
    best_known = None
    if settings.reference:
        def best_known() -> float:
            run = measure(loaded, min(loaded.model.solver.starts, settings.reference_starts),
                          spec_seed + REFERENCE_SEED_OFFSET)
            return run.objective if run.worst_violation == 0 else math.inf
    return BenchCase(problem=loaded.name, kind=loaded.kind, methods=methods, best_known=best_known, tolerance=tolerance,
                     note=f"{starts} start(s) per method"
                     + (f"; SLSQP stopped at {settings.slsqp_budget_s / max(starts, 1):g} s per start"
                        if "slsqp" in settings.peers else "")
                     + (f"; differential_evolution: 1 run, stopped at {settings.de_budget_s:g} s ({DE_BOUNDS_RULE})"
                        if "differential_evolution" in settings.peers else "")
                     + (f"; best known: an untimed multistart ({min(loaded.model.solver.starts, settings.reference_starts)}"
                        " starts, another seed)" if settings.reference
                        else "; best known: the best any run reached")
                     + ("; peers (SLSQP, differential_evolution) not run" if not settings.peers else "")
                     + ("; ipopt_compiled: the same IPOPT runs with the NLP's functions compiled to C (compiled in "
                        "the untimed warm-up)" if settings.compiled is not None else ""),
                     loaded=loaded, single_runs={"slsqp", "differential_evolution"},
                     sweep=lambda tick: sample_sweep(loaded, settings, spec_seed, tick, reuse=lambda: ad_runs),
                     sweep_runs=len({tuple(sorted(scaled_samples(loaded.model, f).items())) for f in settings.factors}
                                    - {tuple(sorted(sample_settings(loaded.model).items()))}) * settings.sweep_repeats,
                     studies=studies or {}, warmup=lambda: _warm_up(loaded, spec_seed, settings.compiled))


def _warm_up(loaded, seed: int, compiled: str | None) -> None:
    """One untimed start of each IPOPT method's build: the imports and caches a first run would pay, and with
    ``compiled`` the library compiled, so no timed run includes a compile."""
    measure(loaded, 1, seed)
    if compiled is not None:
        measure(loaded, 1, seed, compiled=compiled)


def library_cases(specs, seed: int, default: list[str], settings: StudySettings = FULL,
                  studies: dict | None = None) -> list[BenchCase]:
    """The kind's bench cases: ``specs`` (LoadedSpec list) or, when None, the ``default`` library files
    (relative to problems/; the first only with ``settings.first_problem_only``, :data:`QUICK`'s).  ``studies``: extra
    rows (name -> callable) the kind adds to its first case."""
    if specs is None:
        specs = [load_spec(LIBRARY / f) for f in default[:1 if settings.first_problem_only else None]]
    return [case_for(s, settings, seed, studies if i == 0 else None) for i, s in enumerate(specs)]
