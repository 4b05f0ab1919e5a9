"""Exact sensitivities of a :class:`~synthesis.core.problem.Problem`'s rules w.r.t. its design.

The decision vector is x = (z, a): z the design coordinates (``x[:n_design]``), a auxiliary variables
(e.g. the crank angles of precision points) pinned by the structural equality rows h(z, a) = 0 that
depend on a -- one row per auxiliary.  By the implicit function theorem da/dz = -(dh/da)^-1 dh/dz, so a
rule row g(z, a(z)) has the total derivative

    dg/dz = dg/dz|_a - dg/da (dh/da)^-1 dh/dz,

and with the design an affine function of the coordinates, d = d0 + J z, dg/dd = (dg/dz) J^-1.  Every
partial derivative is CasADi AD; the linear algebra is on their numeric values (analysis) or, for the
robust transcription, on symbols with the sensitivity matrix S = da/dz as extra decision variables held
by the rows dh/da S + dh/dz = 0.  The core knows no kind: which entries are design coordinates and how
they map to the design is the caller's.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from synthesis.core.problem import Problem


class PinningError(ValueError):
    """The auxiliary variables are not pinned by as many structural equality rows as there are of them."""


def pinning_rows(problem: Problem, n_design: int, structural=None) -> ca.SX:
    """h(z, a): the structural equality rows (expr - value) that depend on the auxiliaries a.  No such row
    at all: the auxiliaries are free choices of the optimiser (e.g. free timing), held where they are.
    ``structural``: these rows instead of the problem's (the same rows before the operating conditions were
    substituted)."""
    a = problem.x[n_design:]
    rows = []
    if a.numel():
        for expr, lb, ub in (problem.structural if structural is None else structural):
            if lb is None or ub is None or lb != ub:
                continue
            v = ca.vec(ca.SX(expr))
            for i in range(v.numel()):
                if ca.depends_on(v[i], a):
                    rows.append(v[i] - lb)
    h = ca.vertcat(*rows) if rows else ca.SX(0, 1)
    if h.numel() and h.numel() != a.numel():
        raise PinningError(f"problem {problem.name}: {a.numel()} auxiliary variables but {h.numel()} structural "
                           f"equality rows pin them; sensitivities need one row per auxiliary")
    return h


def row_margins(rule) -> ca.SX:
    """The margins (>= 0 holds) of a rule as the NLP holds it, in the rule's unit: of its ``nlp_rows`` where they are
    the rule itself (``Rule.rows_are_the_rule``: the exact smallest distance over a turn for sampled distances, one
    row per branch of a max()), each side of each inequality row (equality rows left out: a robust solve keeps them
    as they are); else of its value (rows in other terms -- squared speeds, cos of an angle -- have margins of
    another size)."""
    def sides(e, lb, ub) -> list:
        v = ca.vec(ca.SX(e))
        return ([v - ca.DM(np.asarray(lb, float))] if lb is not None else []) + \
               ([ca.DM(np.asarray(ub, float)) - v] if ub is not None else [])

    inequalities = [] if not rule.rows_are_the_rule else [
        (e, lb, ub) for e, lb, ub in rule.rows()
        if not (lb is not None and ub is not None and np.array_equal(np.asarray(lb), np.asarray(ub)))]
    return ca.vertcat(*([m for row in inequalities for m in sides(*row)] or sides(rule.expr, rule.lower, rule.upper)))


def rule_vector(problem: Problem, margins: bool = False) -> tuple[ca.SX, list[slice]]:
    """Every rule's value (``Rule.expr``, a vector for sampled rules) stacked, and each rule's slice; ``margins``:
    instead the margins of the rows the NLP holds each rule by (:func:`row_margins`, limits 0 and none)."""
    parts, slices, at = [], [], 0
    for rule in problem.rules:
        v = row_margins(rule) if margins else ca.vec(ca.SX(rule.expr))
        parts.append(v)
        slices.append(slice(at, at + v.numel()))
        at += v.numel()
    return (ca.vertcat(*parts) if parts else ca.SX(0, 1)), slices


@dataclass
class Point:
    """The rules at one design: values (stacked as :func:`rule_vector`) and their total derivatives
    w.r.t. the design variables (rows x n_design, design units), and the decision vector used."""

    x: np.ndarray
    values: np.ndarray
    jacobian: np.ndarray


class Sensitivity:
    """Numeric rule values and implicit-function derivatives of a problem, at any design."""

    def __init__(self, problem: Problem, n_design: int, design_jacobian: np.ndarray | None = None,
                 margins: bool = False):
        self.problem = problem
        self.margins = margins          # rule_vector's form: the rules' values, or their NLP rows' margins
        self.n_design = n_design
        self.J = np.eye(n_design) if design_jacobian is None else np.asarray(design_jacobian, float)
        x, p = problem.x, problem.parameters
        self.h = pinning_rows(problem, n_design)
        g, self.slices = rule_vector(problem, margins)
        self._g = ca.Function("rules_and_jacobian", [x, p], [g, ca.jacobian(g, x)])
        self._h = ca.Function("pinning_and_jacobian", [x, p], [self.h, ca.jacobian(self.h, x)])

    @property
    def n_aux(self) -> int:
        """Auxiliaries pinned by structural rows (0 when they are held where they are)."""
        return self.h.numel()

    def pin(self, x0: np.ndarray, p=None, tol: float = 1e-11, iterations: int = 60) -> np.ndarray:
        """x0 with its auxiliaries moved onto h(z, a) = 0 (Newton on a, z held; AD Jacobian)."""
        x = np.array(x0, dtype=float)
        if not self.n_aux:
            return x
        p = self._p(p)
        n = self.n_design
        for _ in range(iterations):
            h, H = (np.asarray(v, float) for v in self._h(x, p))
            h = h.ravel()
            if not (np.all(np.isfinite(h)) and np.all(np.isfinite(H))):
                # the kinematics are undefined here (a linkage that does not assemble): no Newton step exists
                raise ArithmeticError(f"the structural rows of {self.problem.name} are not finite at this design "
                                      f"(its mechanism does not assemble there), so its auxiliary variables cannot be "
                                      f"pinned")
            if np.max(np.abs(h)) <= tol * max(1.0, np.max(np.abs(x[n:]))):
                return x
            x[n:] -= np.linalg.lstsq(H[:, n:], h, rcond=None)[0]
        h = np.asarray(self._h(x, p)[0], float).ravel()
        if np.max(np.abs(h)) > 1e-8:
            raise ArithmeticError(f"the auxiliary variables of {self.problem.name} do not converge onto their "
                                  f"structural rows (residual {np.max(np.abs(h)):.3g})")
        return x

    def at(self, x: np.ndarray, p=None) -> Point:
        """Rule values and dg/dd at a decision vector whose auxiliaries are pinned (see :meth:`pin`)."""
        p = self._p(p)
        x = np.asarray(x, float)
        n = self.n_design
        g, G = (np.asarray(v, float) for v in self._g(x, p))
        dz = G[:, :n]
        if self.n_aux:
            _, H = (np.asarray(v, float) for v in self._h(x, p))
            dz = dz - G[:, n:] @ np.linalg.solve(H[:, n:], H[:, :n])
        return Point(x, g.ravel(), np.linalg.solve(self.J.T, dz.T).T)

    def operating(self, x: np.ndarray, p=None) -> tuple[tuple[str, ...], tuple[str, ...], np.ndarray] | None:
        """(names, units, dg/dw): the total derivative of every rule row w.r.t. each operating condition w the
        problem was written in (rows x conditions, their units), each rule at the values it was resolved at
        (its scenario's), the auxiliaries following by the implicit function theorem through the structural rows
        (dg/dw = dg/dw|_a - dg/da (dh/da)^-1 dh/dw); None for a problem without operating conditions."""
        if self.margins:        # derivatives of the rules' values, not of their rows' margins: not in this form
            return None
        src = self.problem.operating_source
        if src is None or not src.names:
            return None
        p = self._p(p)
        x = np.asarray(x, float)
        n, X, P, W = self.n_design, self.problem.x, self.problem.parameters, src.symbols
        w0 = [src.nominal[k] for k in src.names]
        solve_aux = None
        if self.n_aux:
            h = pinning_rows(self.problem, n, src.structural)
            H = ca.Function("pinning_w", [X, P, W], [ca.jacobian(h, X), ca.jacobian(h, W)])
            Hx, Hw = (np.asarray(v, float) for v in H(x, p, w0))
            solve_aux = np.linalg.solve(Hx[:, n:], Hw)          # (dh/da)^-1 dh/dw
        out = np.zeros((self.slices[-1].stop if self.slices else 0, len(src.names)))
        for k, (expr, values) in enumerate(src.rules):
            e = ca.vec(ca.SX(expr))
            if e.numel() == 0 or (not ca.depends_on(e, W) and (solve_aux is None or not np.any(solve_aux))):
                continue
            f = ca.Function("rule_w", [X, P, W], [ca.jacobian(e, W), ca.jacobian(e, X)])
            Gw, Gx = (np.asarray(v, float) for v in f(x, p, [values[name] for name in src.names]))
            if solve_aux is not None:
                Gw = Gw - Gx[:, n:] @ solve_aux
            out[self.slices[k]] = Gw
        return src.names, src.units, out

    def _p(self, p):
        return np.zeros(0) if p is None else np.atleast_1d(np.asarray(p, float))


def total_jacobian(expr: ca.SX, problem: Problem, n_design: int, S: ca.SX, J_inv: np.ndarray) -> ca.SX:
    """Symbolic dg/dd of rows ``expr``: (dg/dz + dg/da S) J^-1 with S = da/dz a matrix of symbols."""
    G = ca.jacobian(expr, problem.x)
    dz = G[:, :n_design]
    if S.numel():
        dz = dz + ca.mtimes(G[:, n_design:], S)
    return ca.mtimes(dz, ca.DM(J_inv))


def linear_worst(values: np.ndarray, lower, upper, jacobian: np.ndarray, box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per sample: the nominal margin and the linearised worst-case margin min(g - lo, up - g) - sum_j
    |dg/dd_j| box_j (lower / upper as in a Rule; None for an open side)."""
    spread = np.abs(jacobian) @ box
    lo = np.full_like(values, np.inf) if lower is None else values - lower
    hi = np.full_like(values, np.inf) if upper is None else upper - values
    return np.minimum(lo, hi), np.minimum(lo, hi) - spread
