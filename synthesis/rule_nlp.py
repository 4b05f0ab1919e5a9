"""An IPOPT problem assembled from named rules, shared by the crank_rocker, picker, clamp_cam and
guide_tube kinds.

The decision vector, its bounds, the *structural* rows (definitions that must hold exactly, e.g. "phi_a
is a stationary point of the rocker") and the objective are given by the kind; every
:class:`constraints.base.Rule` contributes its smooth rows.  In *elastic* mode every rule gets one
slack on all its rows and the objective becomes the sum of the slacks: the rules whose slack stays
positive are the ones that conflict (the exit-3 diagnosis).  The solver is built once (``nlpsol``)
and reused for every start; IPOPT's output of each solve is captured from file descriptor 1
(:mod:`synthesis.ipopt_log`), so no log file is ever left behind, in workers or not.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Sequence

import casadi as ca
import numpy as np

from constraints.base import Rule
from synthesis.ipopt_log import captured_stdout

Row = tuple  # (expr, lb | None, ub | None)

#: IPOPT settings of the crank_rocker and picker kinds; a kind may pass its own (``ipopt=``)
TIGHT_IPOPT = {"ipopt.tol": 1e-9, "ipopt.acceptable_tol": 1e-7, "ipopt.constr_viol_tol": 1e-8,
               "ipopt.mu_strategy": "adaptive",
               # no relaxation of inequality limits: a returned design meets them, not 1e-8 short
               "ipopt.bound_relax_factor": 0.0}


@dataclass
class ObjectiveParts:
    """f(x, extra) plus the extra decision variables and rows it needs (e.g. an epigraph variable)."""

    f: ca.SX
    extra: ca.SX = field(default_factory=lambda: ca.SX(0, 1))
    extra_lb: Sequence[float] = ()
    extra_ub: Sequence[float] = ()
    extra_init: Sequence[float] = ()
    rows: Sequence[Row] = ()


@dataclass
class NLPOutcome:
    start: int
    x: np.ndarray               # the full decision vector at IPOPT's return
    objective: float            # f at return, solver units
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str
    lam_g: np.ndarray = field(default_factory=lambda: np.zeros(0))   # constraint multipliers at return


@dataclass
class StartOutcome:
    """One start of a multistart solve, as the kinds report it: the design and objective in spec units."""

    start: int
    design: dict[str, float]
    objective: float
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str

    @classmethod
    def of(cls, out: "NLPOutcome", design: dict[str, float], objective: float, **more) -> "StartOutcome":
        return cls(out.start, design, objective, out.return_status, out.success, out.iterations, out.wall_s,
                   out.log, **more)


class _Rows:
    """Constraint rows g with their bounds, and which rule (index, or None) each row belongs to."""

    def __init__(self) -> None:
        self.exprs: list = []
        self.lbg: list[float] = []
        self.ubg: list[float] = []
        self.owner: list[int | None] = []

    def add(self, rows: Sequence[Row], owner: int | None = None) -> None:
        """Append every element of each (expr, lb, ub); a vector expr gives one row per element."""
        for expr, lb, ub in rows:
            v = ca.vec(ca.SX(expr))
            for i in range(v.numel()):
                self.exprs.append(v[i])
                self.lbg.append(-np.inf if lb is None else lb)
                self.ubg.append(np.inf if ub is None else ub)
                self.owner.append(owner)


def _tightened(rule: Rule, backoff: float) -> list[Row]:
    """The rule's rows with each inequality limit moved inwards by backoff x scale (equalities kept).

    IPOPT meets a constraint only to within its tolerance; the tiny backoff makes a returned design
    satisfy the exact limit when re-checked, instead of missing it by 1e-12.
    """
    shift = backoff * rule.scale
    rows = []
    for expr, lb, ub in rule.rows():
        if lb is not None and ub is not None and lb == ub:
            rows.append((expr, lb, ub))
        else:
            rows.append((expr, None if lb is None else lb + shift, None if ub is None else ub - shift))
    return rows


class RuleNLP:
    """min f  s.t.  structural rows, every rule's rows, lbx <= x <= ubx (or the elastic version).

    ``backoff`` tightens every rule inequality by backoff x the rule's scale (see :func:`_tightened`);
    a callable ``backoff(rule)`` gives each rule its own (e.g. 0 for rules that are not sampled).
    Elastic mode relaxes each rule's rows by scale x its slack, so rows must be in the rule's unit;
    rules named in ``hard_in_elastic`` stay hard there (e.g. the rule without which the kinematics
    is undefined) and their slack is fixed at zero.  ``ipopt``: IPOPT options (default
    :data:`TIGHT_IPOPT`); printing and the iteration limit are set here.
    """

    def __init__(self, name: str, x: ca.SX, lbx, ubx, structural: Sequence[Row], rules: Sequence[Rule],
                 objective: ObjectiveParts, elastic: bool = False, max_iter: int = 500,
                 backoff: float | Callable[[Rule], float] = 1e-7, hard_in_elastic: Sequence[str] = (),
                 ipopt: dict | None = None):
        self.rules = list(rules)
        self.n_x = x.numel()
        self.elastic = elastic
        self._hard = [elastic and rule.name in hard_in_elastic for rule in self.rules]
        backoff_of = backoff if callable(backoff) else (lambda rule: backoff)
        g = _Rows()
        g.add(structural)
        if elastic:
            slack = ca.SX.sym("slack", len(self.rules))
            for k, rule in enumerate(self.rules):
                if self._hard[k]:
                    g.add(rule.rows(), k)
                    continue
                relax = rule.scale * slack[k]     # lb - scale*s <= expr <= ub + scale*s, one slack per rule
                for expr, lb, ub in rule.rows():
                    if lb is not None:
                        g.add([(expr + relax, lb, None)], k)
                    if ub is not None:
                        g.add([(expr - relax, None, ub)], k)
            # a hard rule's slack is fixed at 0: it appears in no row
            extra, extra_lb, extra_ub = slack, [0.0] * len(self.rules), [0.0 if h else np.inf for h in self._hard]
            self._extra_init = np.zeros(len(self.rules))
            f = ca.sum1(slack)
        else:
            for k, rule in enumerate(self.rules):
                g.add(_tightened(rule, backoff_of(rule)), k)
            g.add(objective.rows)
            extra, extra_lb, extra_ub = objective.extra, list(objective.extra_lb), list(objective.extra_ub)
            self._extra_init = np.array(objective.extra_init, dtype=float)
            f = objective.f
        self._owner = g.owner
        self.decision = ca.vertcat(x, extra)
        self.g = ca.vertcat(*g.exprs) if g.exprs else ca.SX(0, 1)
        self.f = f
        self._lbx = np.concatenate([np.asarray(lbx, float), np.asarray(extra_lb, float)])
        self._ubx = np.concatenate([np.asarray(ubx, float), np.asarray(extra_ub, float)])
        self._lbg, self._ubg = np.array(g.lbg, float), np.array(g.ubg, float)
        opts = {"print_time": False, "show_eval_warnings": False, "ipopt.print_level": 5, "ipopt.sb": "yes",
                "ipopt.max_iter": max_iter, **(TIGHT_IPOPT if ipopt is None else ipopt)}
        self.solver = ca.nlpsol(name, "ipopt", {"x": self.decision, "f": f, "g": self.g}, opts)
        self.g_function = ca.Function("g", [self.decision], [self.g])
        self.f_function = ca.Function("f", [self.decision], [f])

    def solve(self, start: int, x0: np.ndarray, extra0: np.ndarray | None = None) -> NLPOutcome:
        """One IPOPT run from x0 (design part) and extra0 (extra variables; default the objective's)."""
        extra0 = self._extra_init if extra0 is None else np.asarray(extra0, float)
        t0 = time.perf_counter()
        with captured_stdout() as log:
            sol = self.solver(x0=np.concatenate([np.asarray(x0, float), extra0]), lbx=self._lbx, ubx=self._ubx,
                              lbg=self._lbg, ubg=self._ubg)
        wall = time.perf_counter() - t0
        stats = self.solver.stats()
        x = np.asarray(sol["x"]).ravel()
        # f of the returned point, evaluated here: after a failure IPOPT's own f may belong to another point
        return NLPOutcome(start, x, float(self.f_function(x)), stats["return_status"],
                          bool(stats["success"]), int(stats["iter_count"]), wall, log(),
                          np.asarray(sol["lam_g"]).ravel())

    def slack_values(self, x: np.ndarray) -> dict[str, float]:
        """Elastic mode: each relaxable rule's slack at a returned decision vector, in the rule's unit."""
        return {r.name: float(v) * r.scale for r, v, hard in zip(self.rules, x[self.n_x:], self._hard) if not hard}

    def active_rules(self, outcome: NLPOutcome, tol: float = 1e-6) -> list[str]:
        """Rules with a row whose multiplier is non-zero at the outcome: the ones that bind."""
        names = []
        for k, lam in zip(self._owner, outcome.lam_g):
            if k is not None and abs(lam) > tol and self.rules[k].name not in names:
                names.append(self.rules[k].name)
        return names


def pull_inside(start: np.ndarray, anchor: np.ndarray, slacks: Callable[[np.ndarray], np.ndarray],
                margin: float) -> np.ndarray:
    """The point nearest ``start`` on the segment anchor -> start where every slack >= margin.

    ``slacks`` must be affine in the point (e.g. Grashof inequalities in the link lengths) and the
    anchor inside; then each slack is linear along the segment and the cut-off is exact.  Used to
    move random starts into the region where the linkage assembles, so IPOPT never starts on NaNs.
    """
    g0, g1 = slacks(anchor) - margin, slacks(start) - margin
    if np.any(g0 < 0.0):
        return start          # no feasible anchor: leave the start as drawn
    t = 1.0
    for a, b in zip(g0, g1):
        if b < 0.0:
            t = min(t, a / (a - b))
    return anchor + t * (start - anchor)
