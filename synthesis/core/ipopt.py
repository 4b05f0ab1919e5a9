"""IPOPT through CasADi: the only module that calls ``nlpsol``.

A :class:`CompiledNLP` is built once per problem and process (the expression graph and IPOPT's
setup are the expensive part) and solves from as many starts as it is given.  IPOPT's output of
each solve is captured from file descriptor 1 (:mod:`synthesis.core.ipopt_log`), so no log file is left
behind, in workers or not.

IPOPT sees every variable at its *nominal scale*, the kind's own unit: w = s * z elementwise, IPOPT works on z,
and nothing outside this module sees z (starts, bounds, the returned point and the multipliers are mapped in and
out; :attr:`CompiledNLP.t`, ``f_function`` and ``g_function`` stay in the kind's units).  s is read from the
units the problem declares, not guessed from numbers: solved with every length ``factor`` times its number in
the kind's unit (``SolveMethod.length_factor``; 1e-3: metres for mm), a variable of length power p (mm, m/s: 1, mm^2: 2,
deg, rad, ratios: 0) has s = factor**p and the objective is divided by factor**p of its unit alike, so IPOPT
sees the kind's variables and objective whatever the length unit (the scale cases of the extreme-case matrix,
tests/extreme/test_scale.py), and each row is divided by factor**p of its declared unit alike (g / s_g), so
IPOPT's tolerances, restoration phase and multipliers are those of the kind's NLP in every unit.  (Until
2026-11-24 the rows stayed in the new unit, 1000x smaller in metres: IPOPT then judged their violations in metres,
gave up on locally infeasible starts later or stopped early on a degenerate optimum with multipliers 1000x larger
-- tillage_redesign, planting redesign_from_example2: tests/extreme/test_scale.py.)  In the kind's own units every s
is 1 and IPOPT sees the kind's NLP unchanged.
An earlier rule read the unit from each variable's box (the power of 1000 bringing its width into [1, 1000)),
and so took a chain speed bounded [0.4, 0.62] m/s for a length in metres and scaled it by 1e-3 (the combing chain's
finite-difference solve went from 13 to 140 iterations), and an unboxed start over 1000 for kilometres (the robust
sensitivity variables of planting's tolerance-box redesigns).  A narrow box is not a unit choice; a declared
unit is.
The scaled NLP (s and the objective's scale are its parameters) is built on the first start that needs it, so
one build serves every start.

A kind may watch the iterations of a solve (``CompiledNLP(..., watched=True)``, then ``solve(...,
watch=rule)``): ``rule(iteration, f)`` is called at every IPOPT iteration with the objective in the problem's
units and stops the solve (``User_Requested_Stop``) when it returns True -- a deterministic early cut of a
hopeless start, decided by iterations and objective, not by time (a free-timing path synthesis).

How a CompiledNLP solves is one explicit value, its :class:`SolveMethod` (``CompiledNLP(problem, method=...)``,
or :meth:`CompiledNLP.reconfigure` on one a kind built); the default is IPOPT with CasADi's exact derivatives, the
nominal scaling and the kind's own units, and only the bench (:mod:`synthesis.bench.generic`) and the tests ask for
another:

* ``derivatives="finite_difference"``: IPOPT is given function values only -- it differences f and g itself
  (``gradient_approximation`` / ``jacobian_approximation = finite-difference-values``) and keeps a limited-memory
  Hessian -- instead of CasADi's exact derivatives (the exact-against-approximate study; never in a solve:
  docs/ARCHITECTURE.md, "Conventions");
* ``runner``: :meth:`CompiledNLP.solve` hands its start to ``runner(compiled, start, w0, p) -> NLPOutcome``
  instead of IPOPT (a peer method on the same transcribed NLP and starts; a kind's own extra phase before a start,
  such as a path synthesis' fixed-timing fit of its random starts, is IPOPT's, so a peer starts those from the
  start as drawn: :attr:`CompiledNLP.peer_method`);
* ``scaling="none"``: IPOPT is given the raw variables (s = 1), to measure what the nominal scaling does;
* ``length_factor``: IPOPT is handed the problem with every length ``factor`` times its number in the kind's unit
  (1e-3: metres for mm; :mod:`synthesis.core.units`), starts, the returned point and the multipliers mapped to and
  from the kind's units, so the kind and the multistart see mm as always (the scale case of
  tests/extreme/test_scale.py).

A kind's problems are compiled with its build's ``Setting.method`` (:func:`synthesis.core.declared.compile_problem`);
:func:`solved_with_method` is the kind transform that sets it, and reconfigures after the build an NLP a kind
compiled without it (a changed derivative mode or length unit then builds IPOPT's solver again; the seconds of the
discarded build are :attr:`CompiledNLP.discarded_s`, which the bench leaves out of its times).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import casadi as ca
import numpy as np

from synthesis.constraints.base import Rule
from synthesis.core.compiled_code import compile_seconds, load as load_compiled
from synthesis.core.problem import Problem
from synthesis.core.transcribe import Transcription, refuse_empty_rows, transcribe
from synthesis.core.units import objective_factor, row_factors, variable_factors
from synthesis.core.ipopt_log import captured_stdout

#: IPOPT's linear algebra (MUMPS on the OpenBLAS CasADi bundles) sums in another order with more than one thread,
#: so a start's last digits -- and, from a flat optimum, its design -- depended on the machine's cores (a local
#: solve differed from the same solve on a dask worker, whose nanny runs one thread).  One thread: OpenBLAS reads
#: this when the IPOPT plugin loads it, at the first ``nlpsol`` (:func:`_nlpsol`), so an answer is the same on any
#: machine, in any worker.  (The small KKT systems here gain nothing from more threads.)
BLAS_THREADS = "OPENBLAS_NUM_THREADS"


def _nlpsol(*args):
    """``ca.nlpsol(*args)`` with one BLAS thread asked for while it runs (the first call loads the plugin and its
    OpenBLAS); the process's environment is left as it was, for whatever else it runs."""
    before = os.environ.get(BLAS_THREADS)
    os.environ[BLAS_THREADS] = "1"
    try:
        return ca.nlpsol(*args)
    finally:
        if before is None:
            del os.environ[BLAS_THREADS]
        else:
            os.environ[BLAS_THREADS] = before

#: named option presets; a problem picks one by name and may override single options
#: every preset: a final point IPOPT's bound relaxation (bound_relax_factor, 1e-8 by default) left outside a variable's
#: bounds is projected onto them (Ipopt 3.14's default is not to): a solved design lies within the spec's bounds
#: (guide_tube fastest_equal_time's delta_I came out 60.0000006 of [30, 60]; the rows are re-checked on that point)
WITHIN_BOUNDS = {"ipopt.honor_original_bounds": "yes"}

PRESETS: dict[str, dict] = {
    # rule kinds: tight tolerances, and no relaxation of inequality limits, so a returned design
    # meets them rather than falling 1e-8 short
    "tight": {"ipopt.tol": 1e-9, "ipopt.acceptable_tol": 1e-7, "ipopt.constr_viol_tol": 1e-8,
              "ipopt.mu_strategy": "adaptive", "ipopt.bound_relax_factor": 0.0},
    # IPOPT's own barrier strategy and bound handling at two tolerance levels (the clamp cam's and
    # the guide tube's published numbers were computed with them)
    "moderate": {"ipopt.tol": 1e-9, "ipopt.acceptable_tol": 1e-7},
    "precise": {"ipopt.tol": 1e-10, "ipopt.acceptable_tol": 1e-8},
    # the planting arm: many sampled rules; 1e-8 is well below the fine-grid check's resolution
    "standard": {"ipopt.tol": 1e-8, "ipopt.acceptable_tol": 1e-6, "ipopt.mu_strategy": "adaptive"},
    # exact fits (path synthesis): a zero-error fit must come out below 1e-8 mm^2, not stop at a 1e-8
    # KKT residual; monotone barrier (more starts reach the global optimum on the synthetic-truth study)
    "exact_fit": {"ipopt.tol": 1e-12, "ipopt.acceptable_tol": 1e-9, "ipopt.mu_strategy": "monotone",
                  "ipopt.bound_relax_factor": 0.0},
}

#: what ``SolveMethod(derivatives="finite_difference")`` adds to a preset: IPOPT's own forward differences of
#: f and g (it never calls CasADi's gradient or Jacobian) and a limited-memory (L-BFGS) Hessian
FINITE_DIFFERENCE = {"ipopt.hessian_approximation": "limited-memory",
                     "ipopt.gradient_approximation": "finite-difference-values",
                     "ipopt.jacobian_approximation": "finite-difference-values"}
DERIVATIVES = ("exact", "finite_difference")
SCALINGS = ("nominal", "none")

@dataclass(frozen=True)
class SolveMethod:
    """How a :class:`CompiledNLP` solves (module docstring): IPOPT's derivatives ("exact" or "finite_difference"),
    its variables ("nominal": w = s * z, or "none": w), the length unit it sees (``length_factor`` times the kind's)
    and, with a ``runner``, a peer method answering every start instead of IPOPT."""

    derivatives: str = "exact"
    scaling: str = "nominal"
    length_factor: float = 1.0
    runner: Callable | None = None
    compiled: str | None = None     # a folder: IPOPT's functions compiled to C and cached there (compiled_code)

    def __post_init__(self):
        for what, mode, allowed in (("derivatives", self.derivatives, DERIVATIVES),
                                    ("scaling", self.scaling, SCALINGS)):
            if mode not in allowed:
                raise ValueError(f"{what}: {mode!r} is not one of {', '.join(allowed)}")
        factor = float(self.length_factor)
        if not (math.isfinite(factor) and factor > 0.0):
            raise ValueError(f"length_factor: the factor must be a positive number, not {self.length_factor!r}")
        object.__setattr__(self, "length_factor", factor)
        if self.compiled is not None and self.derivatives != "exact":
            raise ValueError(f"compiled: the compiled functions are the exact derivatives, not {self.derivatives!r}")

    def builds_like(self, other: SolveMethod) -> bool:
        """Whether IPOPT's solver built for ``other`` serves this method too (the scaling and the runner are read
        per solve)."""
        return (self.derivatives == other.derivatives and self.length_factor == other.length_factor
                and self.compiled == other.compiled)


EXACT = SolveMethod()


def compiled_in(nlp) -> list[CompiledNLP]:
    """The CompiledNLPs a kind's NLP (:class:`~synthesis.core.kind.KindNLP`) holds: ``compiled``, its ``stages``
    and its reduced form's (``configuration.compiled``).  (One a kind builds later, on first use, is not among
    them: it has the method of the setting it is compiled with.)"""
    forms = [nlp] if nlp.configuration is None else [nlp, nlp.configuration]
    return [c for c in [*(form.compiled for form in forms), *nlp.stages] if c is not None]


def solved_with_method(kind, **changes):
    """``kind`` with every NLP its solve builds solved by its :class:`SolveMethod` with ``changes`` (e.g.
    ``derivatives="finite_difference"``, ``length_factor=1e-3``, ``runner=peer``): a kind transform
    (``Kind.solving_with``), the kind itself untouched.  The build's setting carries the method
    (``Setting.method``, which the core's compile of a kind's problem hands each CompiledNLP); an NLP the kind
    compiled without it is reconfigured after the build (:meth:`CompiledNLP.reconfigure`)."""
    SolveMethod(**changes)          # a bad mode or factor is refused here, before any build
    solving = kind.solving()

    def build(setting, elastic):
        method = dataclasses.replace(setting.method or EXACT, **changes)
        nlp = solving.build(dataclasses.replace(setting, method=method), elastic)
        for compiled in compiled_in(nlp):
            compiled.reconfigure(**changes)
        return nlp
    return kind.solving_with(dataclasses.replace(solving, build=build))


@contextmanager
def answered_by(compiled: list[CompiledNLP], runner: Callable | None) -> Iterator[None]:
    """Each of ``compiled`` answers its solves with ``runner`` while the block runs (its method's runner before and
    after): a look at the start a kind's NLP would hand IPOPT, or at an iterate mapped as an answer."""
    before = [c.method for c in compiled]
    for c in compiled:
        c.reconfigure(runner=runner)
    try:
        yield
    finally:
        for c, method in zip(compiled, before):
            c.method = method


@dataclass
class NLPOutcome:
    """One IPOPT run as it ended: where, how, how long."""

    start: int
    x: np.ndarray               # the full decision vector (x, extra) at return
    objective: float            # f evaluated at the returned x (inf when not a number)
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str
    lam_g: np.ndarray = field(default_factory=lambda: np.zeros(0))   # constraint multipliers at return
    p: np.ndarray = field(default_factory=lambda: np.zeros(0))       # the NLP parameters it was solved with


class _Watch(ca.Callback):
    """IPOPT's intermediate callback: ``rule(iteration, f)`` (set per solve) True stops the solve."""

    def __init__(self, n_w: int, n_g: int, n_p: int):
        ca.Callback.__init__(self)
        self.sizes = {"x": n_w, "lam_x": n_w, "g": n_g, "lam_g": n_g, "f": 1, "lam_p": n_p}
        self.rule: Callable[[int, float], bool] | None = None
        self.scale = 1.0
        self.calls = 0
        self.construct("iteration_watch", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "stop"

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(self.sizes[ca.nlpsol_out(i)], 1)

    def _at_iteration(self, arg):
        iteration = self.calls                  # IPOPT calls it at iteration 0, 1, ...
        self.calls += 1
        stop = self.rule is not None and bool(self.rule(iteration, float(arg[1]) * self.scale))
        return [1 if stop else 0]

    eval = _at_iteration        # the name CasADi's Callback calls (bound so, not defined so: tests/test_fuzz.py)


class CompiledNLP:
    """A transcribed problem with its IPOPT solver, built once and reused for every start."""

    def __init__(self, problem: Problem, elastic: bool = False, derivatives: str | None = None,
                 scaling: str | None = None, length_factor: float | None = None,
                 watched: bool = False, method: SolveMethod | None = None, with_solver: bool = True,
                 robust_start: bool = False):
        """``method`` (default: exact derivatives, nominal scaling, the kind's units, IPOPT), each of
        ``derivatives``, ``scaling`` and ``length_factor`` given replacing its field (a kind's own choice).
        ``with_solver`` False: no IPOPT instance (``solver`` None), the problem is evaluated and never solved (the
        tolerance analysis: IPOPT's setup of the exact Hessian is most of a build on its 10x grid); ``robust_start``:
        each start's extras are followed by the tolerance box's sensitivity and epigraph starts at x0
        (:meth:`~synthesis.core.transcribe.Transcription.full_extra`; a robust solve)."""
        t0 = time.perf_counter()
        self.problem = problem
        self.elastic = elastic
        self.watched = watched
        changes: dict[str, Any] = {k: v for k, v in (("derivatives", derivatives), ("scaling", scaling),
                                     ("length_factor", length_factor)) if v is not None}
        method = EXACT if method is None else method
        self.method = dataclasses.replace(method, **changes) if changes else method
        self.t: Transcription = transcribe(problem, elastic)
        self.with_solver = with_solver
        self.robust_start = robust_start and self.t.robust is not None
        self.discarded_s = 0.0      # seconds of IPOPT setups reconfigure() replaced (the bench leaves them out)
        self.compile_s = 0.0        # seconds of compiling IPOPT's functions to C (SolveMethod.compiled; in build_s)
        if with_solver:
            refuse_empty_rows(problem, self.t)
        self._build_ipopt()
        self.f_function = ca.Function("f", [self.t.w, problem.parameters], [self.t.f])
        self.g_function = ca.Function("g", [self.t.w, problem.parameters], [self.t.g])
        self.build_s = time.perf_counter() - t0     # transcription and IPOPT's setup (the bench reports it)

    @property
    def derivatives(self) -> str:
        return self.method.derivatives

    @property
    def scaling(self) -> str:
        return self.method.scaling

    @property
    def peer_method(self) -> bool:
        """Whether a peer method (the method's runner) answers this NLP's solves rather than IPOPT."""
        return self.method.runner is not None

    def reconfigure(self, **changes) -> None:
        """Solve with this NLP's method with ``changes`` from now on (:class:`SolveMethod`'s fields); a changed
        derivative mode or length unit builds IPOPT's solver again (the transcription is kept), the replaced
        setup's seconds added to :attr:`discarded_s`."""
        method = dataclasses.replace(self.method, **changes)
        if method.builds_like(self.method):
            self.method = method
            return
        discarded = self._ipopt_s
        self.method = method
        self._build_ipopt()
        self.discarded_s += discarded
        self.build_s += self._ipopt_s - discarded

    def _build_ipopt(self) -> None:
        """IPOPT's solver of the method: the kind's NLP, or it in another length unit: w' = u w, g' = c_g g,
        f' = c_f f (synthesis.core.units); ``t`` stays the kind's."""
        t0 = time.perf_counter()
        problem, elastic = self.problem, self.elastic
        factor = self.method.length_factor
        if factor != 1.0 and self.t.robust is not None:
            raise ValueError(f"problem {problem.name}: a length unit change of a tolerance box (robust) problem is "
                             f"not built (its sensitivity variables mix units)")
        n_w = self.t.w.numel()
        self._unit = variable_factors(problem, factor, n_w, elastic)
        self._row_unit = row_factors(problem, factor, self.t.owner, elastic)
        self._objective_unit = objective_factor(problem, factor, elastic)
        self._w = self.t.w
        if factor == 1.0:
            self._f, self._g = self.t.f, self.t.g
        else:
            self._w = ca.SX.sym("w_unit", n_w)
            f, g = ca.substitute([self.t.f, self.t.g], [self.t.w], [self._w / ca.DM(self._unit)])
            self._f, self._g = f * self._objective_unit, g * ca.DM(self._row_unit)
        opts = {"print_time": False, "show_eval_warnings": False, "ipopt.print_level": 5, "ipopt.sb": "yes",
                **WITHIN_BOUNDS, **PRESETS[problem.ipopt], **problem.ipopt_options, "ipopt.max_iter": problem.max_iter,
                **(FINITE_DIFFERENCE if self.method.derivatives == "finite_difference" else {})}
        nlp = {"x": self._w, "f": self._f, "g": self._g}
        if problem.parameters.numel():
            nlp["p"] = problem.parameters
        self._watch = None
        # one watch per solver (the scaled one has n_w + 1 + n_g more parameters: s, the objective's and rows' scales)
        if self.watched:
            self._watch = _Watch(self.t.w.numel(), self.t.g.numel(), problem.parameters.numel())
            opts = {**opts, "iteration_callback": self._watch}
        self._opts = opts
        self.solver = self._ipopt(nlp, opts) if self.with_solver else None
        self._scaled_solver: ca.Function | None = None         # built on the first start solved in another length unit
        self._ipopt_s = time.perf_counter() - t0

    def _ipopt(self, nlp: dict, opts: dict) -> ca.Function:
        """IPOPT's solver of ``nlp``: CasADi's interpreter evaluating its functions, or, with the method's
        ``compiled`` folder, the library of them compiled to C there (:mod:`synthesis.core.compiled_code`; the
        seconds of a compile are added to :attr:`compile_s`)."""
        name = self.problem.name
        if self.method.compiled is None:
            return _nlpsol(name, "ipopt", nlp, opts)
        before = compile_seconds()
        solver = load_compiled(name, nlp, opts, Path(self.method.compiled), lambda n, o: _nlpsol(name, "ipopt", n, o),
                               lambda path: _nlpsol(name, "ipopt", str(path), opts))
        self.compile_s += compile_seconds() - before
        return solver

    def scaled_solver(self) -> ca.Function:
        """IPOPT on z with w = s * z, s (the nominal values) appended to the problem's parameters; built once,
        its build time added to ``build_s``."""
        if self._scaled_solver is None:
            t0 = time.perf_counter()
            w, n, m = self._w, self._w.numel(), self._g.numel()
            z, s, sf = ca.SX.sym("z", n), ca.SX.sym("nominal", n), ca.SX.sym("objective_nominal")
            sg = ca.SX.sym("row_nominal", m)
            f, g = ca.substitute([self._f, self._g], [w], [s * z])
            nlp = {"x": z, "f": f / sf, "g": g / sg, "p": ca.vertcat(self.problem.parameters, s, sf, sg)}
            opts = self._opts
            if self._watch is not None:
                self._scaled_watch = _Watch(n, self.t.g.numel(), nlp["p"].numel())
                opts = {**opts, "iteration_callback": self._scaled_watch}
            self._scaled_solver = self._ipopt(nlp, opts)
            self.build_s += time.perf_counter() - t0
            self._ipopt_s += time.perf_counter() - t0
        return self._scaled_solver

    @property
    def rules(self) -> Sequence[Rule]:
        return self.problem.rules

    @property
    def n_x(self) -> int:
        return self.t.n_x

    def solve(self, start: int, x0, extra0=None, p=None, watch: Callable[[int, float], bool] | None = None,
              x_bounds: tuple[np.ndarray, np.ndarray] | None = None,
              extra_bounds: tuple[np.ndarray, np.ndarray] | None = None) -> NLPOutcome:
        """One IPOPT run from x0 (the problem's x) and extra0 (extra variables; default the transcription's);
        ``watch(iteration, f)`` True stops it (a solver built ``watched=True``; module docstring); ``x_bounds``
        (lower, upper) replace the bounds of the problem's x for this run only (within them: an entry with equal
        bounds is held fixed, e.g. a phase of a continuation); ``extra_bounds`` those of the extra variables
        (any values, lower <= upper: e.g. elastic slacks held at a value).  A peer method (the method's runner) has
        no such run."""
        if self.robust_start:
            extra0 = self.t.full_extra(extra0, x0, p)
        extra0 = self.t.extra_init if extra0 is None else np.asarray(extra0, float)
        p = np.zeros(0) if p is None else np.atleast_1d(np.asarray(p, float))
        lbw, ubw = self._run_bounds(x_bounds, extra_bounds)
        args = dict(x0=np.concatenate([np.asarray(x0, float), extra0]), lbx=lbw, ubx=ubw,
                    lbg=self.t.lbg, ubg=self.t.ubg)
        runner = self.method.runner
        if runner is not None:
            if x_bounds is not None or extra_bounds is not None:
                raise ValueError(f"problem {self.problem.name}: a run with its own bounds has no peer method")
            return runner(self, start, args["x0"], p)
        # into the unit IPOPT is given (all factors 1 in the kind's own units)
        u = self._unit
        c = self._row_unit
        args.update(x0=args["x0"] * u, lbx=lbw * u, ubx=ubw * u, lbg=self.t.lbg * c, ubg=self.t.ubg * c)
        # nominal scaling: IPOPT's z is the kind's unit again, and so are its rows (module docstring); a kind that
        # keeps its own variables (scaling "none": a path synthesis' variables, already in units of its targets'
        # size) still has its rows divided back into its units
        unit_changed = not (np.all(u == 1.0) and self._objective_unit == 1.0 and np.all(c == 1.0))
        nominal = self.scaling == "nominal"
        s = (u if nominal else np.ones_like(u)) if unit_changed else None
        sf = self._objective_unit if nominal and unit_changed else 1.0
        sg = c if unit_changed else np.ones_like(c)
        solver = self.solver
        if s is not None:
            solver = self.scaled_solver()
            args.update(x0=args["x0"] / s, lbx=args["lbx"] / s, ubx=args["ubx"] / s, lbg=args["lbg"] / sg,
                        ubg=args["ubg"] / sg, p=np.concatenate([p, s, [sf], sg]))
        elif p.size:
            args["p"] = p
        if solver is None:
            raise ValueError(f"problem {self.problem.name}: built with_solver=False, so it is evaluated, never solved")
        watcher = None
        if self._watch is not None:
            watcher = self._watch if solver is self.solver else self._scaled_watch
            # IPOPT minimises c_f f / sf (c_f: the objective's length-unit factor; sf = c_f in the scaled solver,
            # 1 in the unscaled one), so sf / c_f gives the rule f in the problem's own units either way
            watcher.rule, watcher.scale, watcher.calls = watch, sf / self._objective_unit, 0
        elif watch is not None:
            raise ValueError("solve(watch=...) needs a CompiledNLP built with watched=True")
        t0 = time.perf_counter()
        try:
            with captured_stdout() as log:
                sol = solver(**args)
        finally:
            if watcher is not None:
                watcher.rule = None
        wall = time.perf_counter() - t0
        stats = solver.stats()
        x = np.asarray(sol["x"]).ravel()
        if s is not None:
            x = s * x
        if s is not None or not np.all(u == 1.0):
            # back to the kind's units; a bound IPOPT returned exactly stays exact (s * (lb / s) may round)
            x = np.clip(x / u, lbw, ubw)
        # f of the returned point, evaluated here: after a failure IPOPT's own f may belong to another
        # point (even 0.0 after Invalid_Number_Detected)
        f = float(self.f_function(x, p))
        # multipliers of the kind's rows: IPOPT's of f / sf and rows c * g / sg are sf * c / (sg c_f) of the kind's
        lam = np.asarray(sol["lam_g"]).ravel() * sf * self._row_unit / (sg * self._objective_unit)
        return NLPOutcome(start, x, f if math.isfinite(f) else math.inf, stats["return_status"],
                          bool(stats["success"]), int(stats["iter_count"]), wall, log(), lam, p)

    def _run_bounds(self, x_bounds, extra_bounds) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) of the decision vector for one run: the transcription's, ``x_bounds`` replacing those of
        the problem's x (within them) and ``extra_bounds`` those of the extra variables (:meth:`solve`)."""
        lbw, ubw = self.t.lbw, self.t.ubw
        if x_bounds is not None:
            n = self.t.n_x
            lo, hi = (np.asarray(b, float) for b in x_bounds)
            if lo.shape != (n,) or hi.shape != (n,) or not (np.all(lbw[:n] <= lo) and np.all(lo <= hi)
                                                            and np.all(hi <= ubw[:n])):      # NaN fails too
                raise ValueError(f"problem {self.problem.name}: x_bounds must be {n} lower and upper values within "
                                 f"the problem's bounds, lower <= upper")
            lbw, ubw = np.concatenate([lo, lbw[n:]]), np.concatenate([hi, ubw[n:]])
        if extra_bounds is not None:
            n, m = self.t.n_x, len(lbw) - self.t.n_x
            lo, hi = (np.asarray(b, float) for b in extra_bounds)
            if lo.shape != (m,) or hi.shape != (m,) or not np.all(lo <= hi):      # NaN fails too
                raise ValueError(f"problem {self.problem.name}: extra_bounds must be {m} lower and upper values, "
                                 f"lower <= upper")
            lbw, ubw = np.concatenate([lbw[:n], lo]), np.concatenate([ubw[:n], hi])
        return lbw, ubw

    def slack_values(self, x: np.ndarray) -> dict[str, float]:
        """Elastic form: each relaxable rule's slack at a returned decision vector, in the rule's unit."""
        return {r.name: float(v) * r.scale
                for r, v, hard in zip(self.rules, x[self.n_x:], self.t.hard) if not hard}

    def active_rules(self, outcome: NLPOutcome, tol: float = 1e-6) -> list[str]:
        """Rules with a row whose multiplier is non-zero at the outcome: the ones that bind.  A row that depends on
        no free variable (a clamp cam's timing hold, 0 by construction of the fixed timing) holds nothing back,
        whatever multiplier IPOPT gives it at a degenerate point (its gradient is zero): it is not named."""
        moving = self._rows_on_free_variables()
        names: list[str] = []
        for i, (k, lam) in enumerate(zip(self.t.owner, outcome.lam_g)):
            if k is not None and abs(lam) > tol and moving[i] and self.rules[k].name not in names:
                names.append(self.rules[k].name)
        return names

    def _rows_on_free_variables(self) -> np.ndarray:
        """Per row of g: does it depend (structurally) on a variable of x whose bounds leave it room?"""
        x = self.problem.x
        free = np.flatnonzero(np.asarray(self.problem.ubx, float) > np.asarray(self.problem.lbx, float))
        rows, cols = ca.jacobian_sparsity(self.t.g, x).get_triplet()
        moving = np.zeros(self.t.g.numel(), bool)
        on_free = np.isin(np.asarray(cols, int), free)
        moving[np.asarray(rows, int)[on_free]] = True
        return moving
