"""IPOPT through CasADi: the only module that calls ``nlpsol``.

A :class:`CompiledNLP` is built once per problem and process (the expression graph and IPOPT's
setup are the expensive part) and solves from as many starts as it is given.  IPOPT's output of
each solve is captured from file descriptor 1 (:mod:`synthesis.ipopt_log`), so no log file is left
behind, in workers or not.

Two hooks serve the bench (:mod:`synthesis.bench_generic`) and nothing else; both are context-local,
so a solve outside them is untouched:

* :func:`derivatives` ``("finite_difference")``: CompiledNLPs built inside give IPOPT function values
  only -- IPOPT differences f and g itself (``gradient_approximation`` / ``jacobian_approximation =
  finite-difference-values``) and keeps a limited-memory Hessian -- instead of CasADi's exact derivatives
  (the exact-against-approximate study; DESIGN.md: never in a solve);
* :func:`solved_with` ``(runner)``: ``CompiledNLP.solve`` hands its start to ``runner(compiled, start,
  w0, p) -> NLPOutcome`` instead of IPOPT (a peer method on the same transcribed NLP and starts).
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

_derivatives: ContextVar[str] = ContextVar("agrisynth_ipopt_derivatives", default="exact")
_solve_with: ContextVar[Callable | None] = ContextVar("agrisynth_solve_with", default=None)


@contextmanager
def derivatives(mode: str) -> Iterator[None]:
    """CompiledNLPs built inside get ``mode`` derivatives ("exact" or "finite_difference")."""
    if mode not in DERIVATIVES:
        raise ValueError(f"derivatives: {mode!r} is not one of {', '.join(DERIVATIVES)}")
    token = _derivatives.set(mode)
    try:
        yield
    finally:
        _derivatives.reset(token)


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


class CompiledNLP:
    """A transcribed problem with its IPOPT solver, built once and reused for every start."""

    def __init__(self, problem: Problem, elastic: bool = False, derivatives: str | None = None):
        t0 = time.perf_counter()
        self.problem = problem
        self.elastic = elastic
        self.derivatives = _derivatives.get() if derivatives is None else derivatives
        self.t: Transcription = transcribe(problem, elastic)
        opts = {"print_time": False, "show_eval_warnings": False, "ipopt.print_level": 5, "ipopt.sb": "yes",
                **PRESETS[problem.ipopt], **problem.ipopt_options, "ipopt.max_iter": problem.max_iter,
                **(FINITE_DIFFERENCE if self.derivatives == "finite_difference" else {})}
        nlp = {"x": self.t.w, "f": self.t.f, "g": self.t.g}
        if problem.parameters.numel():
            nlp["p"] = problem.parameters
        self.solver = ca.nlpsol(problem.name, "ipopt", nlp, opts)
        self.f_function = ca.Function("f", [self.t.w, problem.parameters], [self.t.f])
        self.g_function = ca.Function("g", [self.t.w, problem.parameters], [self.t.g])
        self.build_s = time.perf_counter() - t0     # transcription and IPOPT's setup (the bench reports it)

    @property
    def rules(self) -> list:
        return self.problem.rules

    @property
    def n_x(self) -> int:
        return self.t.n_x

    def solve(self, start: int, x0, extra0=None, p=None) -> NLPOutcome:
        """One IPOPT run from x0 (the problem's x) and extra0 (extra variables; default the transcription's)."""
        extra0 = self.t.extra_init if extra0 is None else np.asarray(extra0, float)
        p = np.zeros(0) if p is None else np.atleast_1d(np.asarray(p, float))
        args = dict(x0=np.concatenate([np.asarray(x0, float), extra0]), lbx=self.t.lbw, ubx=self.t.ubw,
                    lbg=self.t.lbg, ubg=self.t.ubg)
        runner = _solve_with.get()
        if runner is not None:
            return runner(self, start, args["x0"], p)
        if p.size:
            args["p"] = p
        t0 = time.perf_counter()
        with captured_stdout() as log:
            sol = self.solver(**args)
        wall = time.perf_counter() - t0
        stats = self.solver.stats()
        x = np.asarray(sol["x"]).ravel()
        # f of the returned point, evaluated here: after a failure IPOPT's own f may belong to another
        # point (even 0.0 after Invalid_Number_Detected)
        f = float(self.f_function(x, p))
        return NLPOutcome(start, x, f if math.isfinite(f) else math.inf, stats["return_status"],
                          bool(stats["success"]), int(stats["iter_count"]), wall, log(),
                          np.asarray(sol["lam_g"]).ravel())

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
