"""A :class:`~synthesis.core.problem.Problem` as an NLP: decision vector, rows and their bounds.

Two forms.  *Normal*: every rule's inequality rows are moved inside their limits by the problem's
back-off (equalities kept), plus the objective's rows.  *Elastic*: every relaxable rule gets one
slack s_k >= 0 on all its rows, lb - scale*s <= row <= ub + scale*s, and the objective is sum s_k:
the smallest relaxation, in units of each rule's typical margin; rules whose slack stays positive
are the ones that conflict.  Rules named hard stay hard (their slack is fixed at 0).

*Robust* (either form, when the problem has a :class:`~synthesis.core.problem.Tolerance`: a robust solve's
problems get theirs by :func:`synthesis.core.declared.held_in_box`): every inequality row g of a rule is held at its
linearised worst case in the tolerance box, g - sum_j t_j box_j >= lb and g + sum_j t_j box_j <= ub, with
epigraph variables t_j >= dg/dd_j, t_j >= -dg/dd_j (so t_j >= |dg/dd_j| smoothly).  dg/dd is exact: AD
partials and, where auxiliaries are pinned by structural equalities, the implicit-function sensitivity
S = da/dz held by the rows dh/da S + dh/dz = 0 (:mod:`synthesis.core.sensitivity`).  These extra variables
follow the objective's (or the slacks); :meth:`Transcription.full_extra` gives their start values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import casadi as ca
import numpy as np

from synthesis.core.problem import MaxMinMargin, ObjectiveParts, Problem, Row, Tolerance
from synthesis.core.sensitivity import pinning_rows, total_jacobian
from synthesis.errors import SpecError

class _Robust:
    """The robust rows of a problem's rules in a tolerance box, with their extra variables."""

    def __init__(self, problem: Problem, tol: Tolerance):
        self.problem, self.n = problem, tol.n_design
        J = np.eye(self.n) if tol.design_jacobian is None else np.asarray(tol.design_jacobian, float)
        self.J_inv = np.linalg.inv(J)
        self.box = np.asarray(tol.box, float)
        if self.box.shape != (self.n,) or np.any(self.box < 0):
            raise ValueError(f"problem {problem.name}: a tolerance box needs {self.n} half-widths >= 0")
        self.active = [j for j in range(self.n) if self.box[j] > 0]
        # each active variable's column of D T: its own derivative and those of the variables that follow it
        T = np.eye(self.n) if tol.moves is None else np.asarray(tol.moves, float)
        self.carried = {k: [(i, float(T[i, k])) for i in range(self.n) if i != k and T[i, k] != 0.0]
                        for k in self.active}
        x = problem.x
        z, a = x[:self.n], x[self.n:]
        na = a.numel()
        h = pinning_rows(problem, self.n)
        if not h.numel():                # auxiliaries not pinned by any row (free timing): held where they are
            na, a = 0, ca.SX(0, 1)
        self.S = ca.SX.sym("da_dz", na, self.n)
        self.rows: list[Row] = []
        if na:
            self.rows.append((ca.vec(ca.mtimes(ca.jacobian(h, a), self.S) + ca.jacobian(h, z)), 0.0, 0.0))
        self.extra = [ca.vec(self.S)]
        self.lb = [-np.inf] * (na * self.n)
        self.derivs: list[ca.SX] = []
        self._start: ca.Function | None = None
        self._hjac = ca.Function("pinning_jacobians", [x, problem.parameters],
                                 [ca.jacobian(h, a) if na else ca.SX(0, 0), ca.jacobian(h, z) if na else ca.SX(0, self.n)])

    def _active_columns(self, D: ca.SX) -> ca.SX:
        """The columns of D T of the variables the box moves on their own: each one's derivative and those of the
        variables that follow it (times d follower / d it); D's own columns where none follows another."""
        if not any(self.carried.values()):
            return D[:, self.active]
        columns = []
        for k in self.active:
            column = D[:, k]
            for i, c in self.carried[k]:
                column = column + c * D[:, i]
            columns.append(column)
        return ca.horzcat(*columns)

    def hold(self, rule, rows: Sequence[Row]) -> list[Row]:
        """``rows`` of ``rule`` held at their linearised worst case (equalities kept as they are)."""
        return self.hold_rows(rule.name, rows)

    def hold_rows(self, name: str, rows: Sequence[Row]) -> list[Row]:
        """``rows`` (of the rule or structural row ``name``) held at their linearised worst case."""
        out: list[Row] = []
        for expr, lb, ub in rows:
            if (lb is not None and ub is not None and lb == ub) or not self.active:
                out.append((expr, lb, ub))
                continue
            e = ca.vec(ca.SX(expr))
            D = self._active_columns(total_jacobian(e, self.problem, self.n, self.S, self.J_inv))
            T = ca.SX.sym(f"abs_sensitivity_{name}", e.numel(), len(self.active))
            self.extra.append(ca.vec(T))
            self.lb += [0.0] * T.numel()
            self.derivs.append(ca.vec(D))
            self.rows += [(ca.vec(T - D), 0.0, None), (ca.vec(T + D), 0.0, None)]
            spread = ca.mtimes(T, ca.DM(self.box[self.active]))
            if lb is not None:
                out.append((e - spread, lb, None))
            if ub is not None:
                out.append((e + spread, None, ub))
        return out

    @property
    def w(self) -> ca.SX:
        return ca.vertcat(*self.extra)

    def start(self, x0: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Start values of the extras at x0: S = -(dh/da)^-1 dh/dz there, t = |dg/dd| (+ a little)."""
        if self._start is None:
            self._start = ca.Function("robust_start", [self.problem.x, ca.vec(self.S), self.problem.parameters],
                                      [ca.vertcat(*self.derivs) if self.derivs else ca.SX(0, 1)])
        Ha, Hz = (np.asarray(v, float) for v in self._hjac(x0, p))
        try:
            S = -np.linalg.solve(Ha, Hz) if Ha.size else np.zeros((0, self.n))
        except np.linalg.LinAlgError:
            S = np.zeros(Hz.shape)
        if not np.all(np.isfinite(S)):
            S = np.zeros(Hz.shape)
        s = S.ravel(order="F")          # ca.vec is column-major
        t = np.abs(np.asarray(self._start(x0, s, p), float).ravel())
        t = np.where(np.isfinite(t), t, 0.0)
        return np.concatenate([s, 1.01 * t + 1e-9])


class _Rows:
    """Constraint rows g with their bounds, and which rule (index, or None) each row belongs to."""

    def __init__(self) -> None:
        self.exprs: list = []
        self.lbg: list[float] = []
        self.ubg: list[float] = []
        self.owner: list[int | None] = []

    def add(self, rows: Sequence[Row], owner: int | None = None) -> None:
        for expr, lb, ub in rows:
            v = ca.vec(ca.SX(expr))
            for i in range(v.numel()):
                self.exprs.append(v[i])
                self.lbg.append(-np.inf if lb is None else float(lb))
                self.ubg.append(np.inf if ub is None else float(ub))
                self.owner.append(owner)


@dataclass
class Transcription:
    """The NLP a solver sees: min f(w; p) s.t. lbg <= g(w; p) <= ubg, lbw <= w <= ubw, w = (x, extra)."""

    problem: Problem
    elastic: bool
    w: ca.SX
    f: ca.SX
    g: ca.SX
    lbw: np.ndarray
    ubw: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    owner: list                  # rule index (or None: structural / objective row) of each row of g
    extra_init: np.ndarray       # default start of the extra variables (epigraph, slacks)
    hard: list[bool]             # per rule: kept hard in the elastic form
    robust: _Robust | None = None           # the tolerance box's rows and variables (robust form)
    n_own_extra: int = 0                    # extras of the objective / slacks (the robust ones follow)

    def full_extra(self, own: np.ndarray | None, x0: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
        """Every extra variable's start: ``own`` (the objective's or slacks'; default the transcription's)
        then, in the robust form, the sensitivity and epigraph variables evaluated at x0."""
        own = self.extra_init[:self.n_own_extra] if own is None else np.asarray(own, float)
        if self.robust is None or len(own) != self.n_own_extra:
            return own
        p = np.zeros(0) if p is None else np.atleast_1d(np.asarray(p, float))
        return np.concatenate([own, self.robust.start(np.asarray(x0, float), p)])

    @property
    def n_x(self) -> int:
        return self.problem.x.numel()


#: the elastic form's back-off, in rule scales: above what separates the rows IPOPT holds from the check's reading
#: of the same rule at the returned design (up to 8.4e-8 of the scale: planting's entry angle, transmission angle
#: and collinearity, each held on its limit by an infeasible spec's elastic design and failed by `check elastic.toml`
#: at 1e-8), below the slack a diagnosis counts as relaxing a rule (synthesis.core.verdict.SLACK_TOL, 1e-6: at 1e-6
#: a rule touching a design held at its bound was named as relaxed), far below any miss it reports (3-4 digits).
#: 3e-7 cost the crank-rocker at a 179 deg swing its elastic re-solve (max_iter: "nothing known about conflicts")
ELASTIC_BACKOFF = 1e-7


def _rows_of(rule, robust: bool) -> tuple:
    """The rule's NLP rows; in a tolerance box its box form where it has one (an equality it pins, e.g. equal
    landing times, cannot hold at every corner of a box)."""
    return rule.box_rows if robust and rule.box_rows else rule.rows()


def _backed_off(problem: Problem, rule, robust: bool = False, backoff=None) -> list[Row]:
    """The rule's rows, each inequality moved inside its limits by ``backoff(rule, limit)`` (default the problem's; a
    range narrower than its two back-offs comes out empty: :func:`refuse_empty_rows` says so before IPOPT is handed
    it)."""
    backoff = problem.backoff if backoff is None else backoff
    rows = []
    for expr, lb, ub in _rows_of(rule, robust):
        if lb is not None and ub is not None and lb == ub:
            rows.append((expr, lb, ub))
        else:
            rows.append((expr, None if lb is None else lb + backoff(rule, lb),
                         None if ub is None else ub - backoff(rule, ub)))
    return rows


def _elastic_backoff(rule, limit: float) -> float:
    return ELASTIC_BACKOFF * rule.scale


def refuse_empty_rows(problem: Problem, t: "Transcription") -> None:
    """SpecError naming the first rule whose backed-off rows leave no room (lower limit above upper): IPOPT would fail
    every start on it ("Ill-posed problem detected").  Evaluating such a problem (a check, the tolerance analysis) is
    fine; solving it is not."""
    for row in np.flatnonzero(t.lbg > t.ubg):
        owner = t.owner[row]
        if owner is None:
            continue
        rule = problem.rules[owner]
        lo, hi = rule.lower, rule.upper
        width = "" if lo is None or hi is None else f" [{lo:g}, {hi:g}] {rule.unit}"
        # the back-off of the rule's first two-sided row, in the rows' unit (a squared rule's is in its square)
        row_lo = next((lb for _, lb, ub in rule.rows() if lb is not None and ub is not None),
                      lo if lo is not None else hi)
        backoff = problem.backoff(rule, row_lo)
        raise SpecError(f"rule {rule.name}: its limits{width} are closer together than the solver's back-off allows "
                        f"(it holds each side {backoff:g} {rule.row_unit or rule.unit} inside, so a returned design "
                        f"meets the limits when re-checked): widen the rule's limits, or lower [solver] backoff where "
                        f"the spec has it")


def _max_min_margin(problem: Problem, objective: MaxMinMargin, hold=lambda rule, rows: rows,
                    robust: bool = False) -> ObjectiveParts:
    """max tau s.t. every backed-off rule row is at least tau x its rule's scale inside its limits (in the
    robust form: its linearised worst case in the tolerance box, ``hold``)."""
    tau = ca.SX.sym("min_normalised_margin")
    rows: list[Row] = []
    for rule in problem.rules:
        for expr, lb, ub in hold(rule, _backed_off(problem, rule, robust)):
            if lb is not None and ub is not None and lb == ub:
                continue          # an equality has no margin to maximise
            if lb is not None:
                rows.append(((expr - lb) / rule.scale - tau, 0.0, None))
            if ub is not None:
                rows.append(((ub - expr) / rule.scale - tau, 0.0, None))
    return ObjectiveParts(f=-tau, extra=tau, extra_lb=[-np.inf], extra_ub=[objective.upper], extra_init=[0.0],
                          rows=rows)


def transcribe(problem: Problem, elastic: bool = False) -> Transcription:
    tol = problem.tolerance
    robust = None if tol is None else _Robust(problem, tol)
    in_box = robust is not None
    hold = robust.hold if robust is not None else (lambda rule, rows: rows)
    hard = [elastic and rule.name in problem.hard_in_elastic for rule in problem.rules]
    g = _Rows()
    held = set(problem.robust_structural) if in_box else set()
    for i, row in enumerate(problem.structural):       # in their order: a nominal NLP's rows are as they were
        g.add(robust.hold_rows(f"structural_{i}", [row]) if robust is not None and i in held else [row])
    if elastic:
        slack = ca.SX.sym("slack", len(problem.rules))
        for k, rule in enumerate(problem.rules):
            # a rule the answer holds sits on its limit there, to IPOPT's tolerance: the elastic rows hold each side
            # ELASTIC_BACKOFF x the rule's scale inside, so the rules its diagnosis says hold do hold when the
            # returned design is re-checked (combing_chain's window_top missed by 1.3e-11 deg, "binding")
            rows = _backed_off(problem, rule, in_box, _elastic_backoff)
            if hard[k]:
                g.add(hold(rule, rows), k)
                continue
            relax = rule.scale * slack[k]
            for expr, lb, ub in hold(rule, rows):
                if lb is not None:
                    g.add([(expr + relax, lb, None)], k)
                if ub is not None:
                    g.add([(expr - relax, None, ub)], k)
        extra, extra_lb = slack, [0.0] * len(problem.rules)
        extra_ub = [0.0 if h else np.inf for h in hard]          # a hard rule's slack appears in no row
        extra_init = np.zeros(len(problem.rules))
        f = ca.sum1(slack)
    else:
        for k, rule in enumerate(problem.rules):
            g.add(hold(rule, _backed_off(problem, rule, in_box)), k)
        objective = problem.objective
        if isinstance(objective, MaxMinMargin):
            objective = _max_min_margin(problem, objective, hold, in_box)
        g.add(objective.rows)
        extra, extra_lb, extra_ub = objective.extra, list(objective.extra_lb), list(objective.extra_ub)
        extra_init = np.array(objective.extra_init, dtype=float)
        f = objective.f
    n_own = int(ca.SX(extra).numel())
    if robust is not None:
        g.add(robust.rows)
        w_robust = robust.w
        extra = ca.vertcat(extra, w_robust)
        extra_lb = list(extra_lb) + robust.lb
        extra_ub = list(extra_ub) + [np.inf] * len(robust.lb)
        extra_init = np.concatenate([np.asarray(extra_init, float), np.zeros(w_robust.numel())])
    return Transcription(
        problem=problem, elastic=elastic, w=ca.vertcat(problem.x, extra), f=f,
        g=ca.vertcat(*g.exprs) if g.exprs else ca.SX(0, 1),
        lbw=np.concatenate([problem.lbx, np.asarray(extra_lb, float)]),
        ubw=np.concatenate([problem.ubx, np.asarray(extra_ub, float)]),
        lbg=np.array(g.lbg, float), ubg=np.array(g.ubg, float), owner=g.owner, extra_init=extra_init, hard=hard,
        robust=robust, n_own_extra=n_own)
