"""IPOPT through CasADi: the only module that calls ``nlpsol``.

A :class:`CompiledNLP` is built once per problem and process (the expression graph and IPOPT's
setup are the expensive part) and solves from as many starts as it is given.  IPOPT's output of
each solve is captured from file descriptor 1 (:mod:`synthesis.ipopt_log`), so no log file is left
behind, in workers or not.

IPOPT sees every variable at a *nominal scale*: w = s * z elementwise, IPOPT works on z, and nothing
outside this module sees z (starts, bounds, the returned point and the multipliers are mapped in and out;
:attr:`CompiledNLP.t`, ``f_function`` and ``g_function`` stay in the kind's units).  s_i is the power of
1000 that brings the variable's size -- the width of its box, or its start when it has none -- into
[1, 1000) (:func:`nominal_scale`): a length bounded [5, 400] mm gets s = 1, the same length in metres
s = 1e-3 and x 1e3 s = 1e3, so z is the same number in all three (issue 18's scale case,
tests/extreme/test_scale.py); an objective with |f| >= 1000 at the start is divided by its power of 1000
alike, a small one is not scaled up (a least-squares fit starts near its optimum 0: scaled up, IPOPT's
finite-difference mode missed steering's Table 12 fit; so a metre-sized objective keeps its own scale and
its design settles to ~1e-8 relative instead of ~1e-12).
A start whose every variable already has s = 1 -- every library problem in mm but one ratio of
combing_chain -- is solved by the unscaled NLP exactly as before.  Scaling every variable to size 1 was
measured on the library first and not kept: no fewer iterations overall (x 1.03 .. 1.05), fourbar_path lost
22 of its 52 converging starts, guide_way its solve (box-magnitude scale) and other local optima came out of
the elastic diagnosis.  The scaled NLP (s and the objective's scale are its parameters) is built on the first
start that needs it, so one build serves every start.

A kind may watch the iterations of a solve (``CompiledNLP(..., watched=True)``, then ``solve(...,
watch=rule)``): ``rule(iteration, f)`` is called at every IPOPT iteration with the objective in the problem's
units and stops the solve (``User_Requested_Stop``) when it returns True -- a deterministic early cut of a
hopeless start, decided by iterations and objective, not by time (fourbar_path, issue 19).

Three hooks serve the bench (:mod:`synthesis.bench_generic`) and the tests and nothing else; all are
context-local, so a solve outside them is untouched:

* :func:`derivatives` ``("finite_difference")``: CompiledNLPs built inside give IPOPT function values
  only -- IPOPT differences f and g itself (``gradient_approximation`` / ``jacobian_approximation =
  finite-difference-values``) and keeps a limited-memory Hessian -- instead of CasADi's exact derivatives
  (the exact-against-approximate study; DESIGN.md: never in a solve);
* :func:`solved_with` ``(runner)``: ``CompiledNLP.solve`` hands its start to ``runner(compiled, start,
  w0, p) -> NLPOutcome`` instead of IPOPT (a peer method on the same transcribed NLP and starts);
* :func:`variable_scaling` ``("none")``: CompiledNLPs built inside give IPOPT the raw variables (s = 1),
  to measure what the nominal scaling does.
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import Callable, Iterator

import casadi as ca
import numpy as np

from synthesis.core.problem import Problem
from synthesis.core.transcribe import Transcription, transcribe
from synthesis.ipopt_log import captured_stdout

#: named option presets; a problem picks one by name and may override single options
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

#: what :func:`derivatives` ``("finite_difference")`` adds to a preset: IPOPT's own forward differences of
#: f and g (it never calls CasADi's gradient or Jacobian) and a limited-memory (L-BFGS) Hessian
FINITE_DIFFERENCE = {"ipopt.hessian_approximation": "limited-memory",
                     "ipopt.gradient_approximation": "finite-difference-values",
                     "ipopt.jacobian_approximation": "finite-difference-values"}
DERIVATIVES = ("exact", "finite_difference")
SCALINGS = ("nominal", "none")

_derivatives: ContextVar[str] = ContextVar("agrisynth_ipopt_derivatives", default="exact")
_solve_with: ContextVar[Callable | None] = ContextVar("agrisynth_solve_with", default=None)
_scaling: ContextVar[str] = ContextVar("agrisynth_variable_scaling", default="nominal")


@contextmanager
def _mode(var: ContextVar[str], mode: str, allowed, what: str) -> Iterator[None]:
    """``var`` set to ``mode`` (one of ``allowed``) while the block runs: CompiledNLPs built there read it."""
    if mode not in allowed:
        raise ValueError(f"{what}: {mode!r} is not one of {', '.join(allowed)}")
    token = var.set(mode)
    try:
        yield
    finally:
        var.reset(token)


def derivatives(mode: str):
    """CompiledNLPs built inside get ``mode`` derivatives ("exact" or "finite_difference")."""
    return _mode(_derivatives, mode, DERIVATIVES, "derivatives")


def variable_scaling(mode: str):
    """CompiledNLPs built inside give IPOPT ``mode`` variables ("nominal": w = s * z, or "none": w)."""
    return _mode(_scaling, mode, SCALINGS, "variable_scaling")


def unit_power(size: np.ndarray) -> np.ndarray:
    """1000**floor(log10(size) / 3): the power of 1000 (unit prefix) that brings a positive size into
    [1, 1000); 1 for sizes already there, for 0 and for non-finite sizes."""
    size = np.asarray(size, float)
    ok = np.isfinite(size) & (size > 0)
    exponent = np.floor(np.log10(np.where(ok, size, 1.0)) / 3.0)
    return np.where(ok, 1000.0 ** exponent, 1.0)


def nominal_scale(lbw: np.ndarray, ubw: np.ndarray, w0: np.ndarray) -> np.ndarray:
    """The nominal value s_i of each variable (IPOPT sees z_i = w_i / s_i): the :func:`unit_power` of its size.

    A variable's size is the width of its box, ub - lb, when both bounds are finite and differ, else |w0_i|
    of the start.  A start scales a variable up only when some boxed variable was scaled (the problem is in
    other units): in a problem whose boxes are all in [1, 1000), a start near zero says nothing about how
    large the variable gets.  A length bounded [5, 400] mm: s = 1; in metres [0.005, 0.4]: s = 1e-3; x 1e3:
    s = 1e3 -- z is the same number of mm in all three.
    """
    lbw, ubw, w0 = (np.asarray(v, float) for v in (lbw, ubw, w0))
    with np.errstate(invalid="ignore"):
        width = ubw - lbw
    boxed = np.isfinite(width) & (width > 0)
    start = np.abs(w0)
    boxed_scale = unit_power(width)
    # a start scales up only where the boxed variables show the problem is in other units than mm-like ones
    moved = bool(np.any(boxed & (boxed_scale != 1.0)))
    free = unit_power(start) if moved else np.where(start >= 1000.0, unit_power(start), 1.0)
    return np.where(boxed, boxed_scale, free)


@contextmanager
def solved_with(runner: Callable | None) -> Iterator[None]:
    """``CompiledNLP.solve`` inside calls ``runner(compiled, start, w0, p) -> NLPOutcome`` instead of IPOPT."""
    token = _solve_with.set(runner)
    try:
        yield
    finally:
        _solve_with.reset(token)


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
                 scaling: str | None = None, watched: bool = False):
        t0 = time.perf_counter()
        self.problem = problem
        self.elastic = elastic
        self.derivatives = _derivatives.get() if derivatives is None else derivatives
        self.scaling = _scaling.get() if scaling is None else scaling
        self.t: Transcription = transcribe(problem, elastic)
        opts = {"print_time": False, "show_eval_warnings": False, "ipopt.print_level": 5, "ipopt.sb": "yes",
                **PRESETS[problem.ipopt], **problem.ipopt_options, "ipopt.max_iter": problem.max_iter,
                **(FINITE_DIFFERENCE if self.derivatives == "finite_difference" else {})}
        nlp = {"x": self.t.w, "f": self.t.f, "g": self.t.g}
        if problem.parameters.numel():
            nlp["p"] = problem.parameters
        self._watch = None
        if watched:      # one watch per solver (the scaled one has 2 n_w + 1 more parameters)
            self._watch = _Watch(self.t.w.numel(), self.t.g.numel(), problem.parameters.numel())
            opts = {**opts, "iteration_callback": self._watch}
        self._opts = opts
        self.solver = ca.nlpsol(problem.name, "ipopt", nlp, opts)
        self._scaled_solver = None         # built on the first start that has a variable to scale
        self.f_function = ca.Function("f", [self.t.w, problem.parameters], [self.t.f])
        self.g_function = ca.Function("g", [self.t.w, problem.parameters], [self.t.g])
        self.build_s = time.perf_counter() - t0     # transcription and IPOPT's setup (the bench reports it)

    def scaled_solver(self):
        """IPOPT on z with w = s * z, s (the nominal values) appended to the problem's parameters; built once,
        its build time added to ``build_s``."""
        if self._scaled_solver is None:
            t0 = time.perf_counter()
            w, n = self.t.w, self.t.w.numel()
            z, s, sf = ca.SX.sym("z", n), ca.SX.sym("nominal", n), ca.SX.sym("objective_nominal")
            f, g = ca.substitute([self.t.f, self.t.g], [w], [s * z])
            nlp = {"x": z, "f": f / sf, "g": g, "p": ca.vertcat(self.problem.parameters, s, sf)}
            opts = self._opts
            if self._watch is not None:
                self._scaled_watch = _Watch(n, self.t.g.numel(), nlp["p"].numel())
                opts = {**opts, "iteration_callback": self._scaled_watch}
            self._scaled_solver = ca.nlpsol(self.problem.name, "ipopt", nlp, opts)
            self.build_s += time.perf_counter() - t0
        return self._scaled_solver

    @property
    def rules(self) -> list:
        return self.problem.rules

    @property
    def n_x(self) -> int:
        return self.t.n_x

    def solve(self, start: int, x0, extra0=None, p=None, watch: Callable[[int, float], bool] | None = None) -> NLPOutcome:
        """One IPOPT run from x0 (the problem's x) and extra0 (extra variables; default the transcription's);
        ``watch(iteration, f)`` True stops it (a solver built ``watched=True``; module docstring)."""
        extra0 = self.t.extra_init if extra0 is None else np.asarray(extra0, float)
        p = np.zeros(0) if p is None else np.atleast_1d(np.asarray(p, float))
        args = dict(x0=np.concatenate([np.asarray(x0, float), extra0]), lbx=self.t.lbw, ubx=self.t.ubw,
                    lbg=self.t.lbg, ubg=self.t.ubg)
        runner = _solve_with.get()
        if runner is not None:
            return runner(self, start, args["x0"], p)
        s = nominal_scale(self.t.lbw, self.t.ubw, args["x0"]) if self.scaling == "nominal" else None
        solver = self.solver
        if s is not None and np.all(s == 1.0):
            s = None                       # every variable well scaled: IPOPT sees the kind's own NLP
        sf = 1.0
        if s is not None:
            solver = self.scaled_solver()
            # a large objective in its own unit power at the start (module docstring)
            f0 = abs(float(self.f_function(args["x0"], p)))
            sf = float(unit_power(f0)) if f0 >= 1000.0 else 1.0
            args.update(x0=args["x0"] / s, lbx=self.t.lbw / s, ubx=self.t.ubw / s, p=np.concatenate([p, s, [sf]]))
        elif p.size:
            args["p"] = p
        watcher = None
        if self._watch is not None:
            watcher = self._watch if solver is self.solver else self._scaled_watch
            watcher.rule, watcher.scale, watcher.calls = watch, sf, 0
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
            # back to the kind's units; a bound IPOPT returned exactly stays exact (s * (lb / s) may round)
            x = np.clip(s * x, self.t.lbw, self.t.ubw)
        # f of the returned point, evaluated here: after a failure IPOPT's own f may belong to another
        # point (even 0.0 after Invalid_Number_Detected)
        f = float(self.f_function(x, p))
        return NLPOutcome(start, x, f if math.isfinite(f) else math.inf, stats["return_status"],
                          bool(stats["success"]), int(stats["iter_count"]), wall, log(),
                          np.asarray(sol["lam_g"]).ravel() * sf)

    def slack_values(self, x: np.ndarray) -> dict[str, float]:
        """Elastic form: each relaxable rule's slack at a returned decision vector, in the rule's unit."""
        return {r.name: float(v) * r.scale
                for r, v, hard in zip(self.rules, x[self.n_x:], self.t.hard) if not hard}

    def active_rules(self, outcome: NLPOutcome, tol: float = 1e-6) -> list[str]:
        """Rules with a row whose multiplier is non-zero at the outcome: the ones that bind."""
        names: list[str] = []
        for k, lam in zip(self.t.owner, outcome.lam_g):
            if k is not None and abs(lam) > tol and self.rules[k].name not in names:
                names.append(self.rules[k].name)
        return names
