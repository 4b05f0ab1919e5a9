"""A :class:`~synthesis.core.problem.Problem` as an NLP: decision vector, rows and their bounds.

Two forms.  *Normal*: every rule's inequality rows are moved inside their limits by the problem's
back-off (equalities kept), plus the objective's rows.  *Elastic*: every relaxable rule gets one
slack s_k >= 0 on all its rows, lb - scale*s <= row <= ub + scale*s, and the objective is sum s_k:
the smallest relaxation, in units of each rule's typical margin; rules whose slack stays positive
are the ones that conflict.  Rules named hard stay hard (their slack is fixed at 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import casadi as ca
import numpy as np

from synthesis.core.problem import MaxMinMargin, ObjectiveParts, Problem, Row


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

    @property
    def n_x(self) -> int:
        return self.problem.x.numel()


def _backed_off(problem: Problem, rule) -> list[Row]:
    rows = []
    for expr, lb, ub in rule.rows():
        if lb is not None and ub is not None and lb == ub:
            rows.append((expr, lb, ub))
        else:
            rows.append((expr, None if lb is None else lb + problem.backoff(rule, lb),
                         None if ub is None else ub - problem.backoff(rule, ub)))
    return rows


def _max_min_margin(problem: Problem, objective: MaxMinMargin) -> ObjectiveParts:
    """max tau s.t. every backed-off rule row is at least tau x its rule's scale inside its limits."""
    tau = ca.SX.sym("min_normalised_margin")
    rows: list[Row] = []
    for rule in problem.rules:
        for expr, lb, ub in _backed_off(problem, rule):
            if lb is not None and ub is not None and lb == ub:
                continue          # an equality has no margin to maximise
            if lb is not None:
                rows.append(((expr - lb) / rule.scale - tau, 0.0, None))
            if ub is not None:
                rows.append(((ub - expr) / rule.scale - tau, 0.0, None))
    return ObjectiveParts(f=-tau, extra=tau, extra_lb=[-np.inf], extra_ub=[objective.upper], extra_init=[0.0],
                          rows=rows)


def transcribe(problem: Problem, elastic: bool = False) -> Transcription:
    hard = [elastic and rule.name in problem.hard_in_elastic for rule in problem.rules]
    g = _Rows()
    g.add(problem.structural)
    if elastic:
        slack = ca.SX.sym("slack", len(problem.rules))
        for k, rule in enumerate(problem.rules):
            if hard[k]:
                g.add(rule.rows(), k)
                continue
            relax = rule.scale * slack[k]
            for expr, lb, ub in rule.rows():
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
            g.add(_backed_off(problem, rule), k)
        objective = problem.objective
        if isinstance(objective, MaxMinMargin):
            objective = _max_min_margin(problem, objective)
        g.add(objective.rows)
        extra, extra_lb, extra_ub = objective.extra, list(objective.extra_lb), list(objective.extra_ub)
        extra_init = np.array(objective.extra_init, dtype=float)
        f = objective.f
    return Transcription(
        problem=problem, elastic=elastic, w=ca.vertcat(problem.x, extra), f=f,
        g=ca.vertcat(*g.exprs) if g.exprs else ca.SX(0, 1),
        lbw=np.concatenate([problem.lbx, np.asarray(extra_lb, float)]),
        ubw=np.concatenate([problem.ubx, np.asarray(extra_ub, float)]),
        lbg=np.array(g.lbg, float), ubg=np.array(g.ubg, float), owner=g.owner, extra_init=extra_init, hard=hard)
