"""Rules no design variable moves: found before any start, and a violated one refused with the spec field to change.

A rule's value can be fixed by the spec alone: planting's depth is the soil's analysis depth by that convention's
own definition (the soil is placed that far above the lowest point), a tube the spec gives as numbers keeps its
speeds whatever the free tube does.  Such a rule, violated, makes every start fail, and the elastic diagnosis only
finds out after the whole multistart (39 s for a planting spec asking a 45 mm depth of a 35 mm analysis depth).

The test reads the kind's :class:`~synthesis.core.problem.Problem`: a rule is *pinned* when, on the manifold the
structural equality rows define, its value does not change with any free decision variable.  Written with exact
Jacobians (CasADi's automatic differentiation, no finite differences): the rule's Jacobian w.r.t. the free entries
of x is a constant combination ``C`` of the equality rows' Jacobians at every point sampled, and ``rule - C rows``
(each row written as expression - target) has the same value at every one of them -- the rule's value wherever the
rows hold.  The points are up to 12 drawn in the bounds (seeded): a rule with a branch (fmax, if_else) whose other
side is active at none of them can still be taken for a pinned one -- sampling, not a proof.  (A rule that reads no
free variable at all is the case ``C = 0``.)  A rule whose value depends on the NLP's parameters is not judged.
docs/ARCHITECTURE.md, "Exit codes": a violated pinned rule is bad input, exit 2, before anything is solved.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from synthesis.errors import SpecError
from synthesis.spec.design_info import describe

#: points of the bounds a rule's Jacobian and value are compared at (each one where the model evaluates it) ...
POINTS = 12
#: ... of this many drawn (a design where the linkage cannot assemble evaluates to NaN), the first the bounds' middle
DRAWS = 12
#: the rule's Jacobian equals C x the rows' Jacobian to this relative accuracy (float round-off of equal graphs)
JACOBIAN_RTOL = 1e-8
#: a pinned rule is violated when it misses its limit by more than this fraction of its scale (a value exactly at
#: its limit, 0 <= 0 or a depth of 30 against [20, 30], is read back to round-off: that is no violation)
MARGIN_TOL = 1e-6


@dataclass(frozen=True)
class PinnedRule:
    """A rule whose value no free design variable moves: its value at the spec's inputs (the worst sample of a
    sampled rule), its limits, and the fixed design variables it reads (their spec paths; empty when only other
    inputs fix it)."""

    name: str
    value: float
    lower: float | None
    upper: float | None
    unit: str
    scale: float
    fixed_variables: tuple[str, ...] = ()

    @property
    def margin(self) -> float:
        lo = math.inf if self.lower is None else self.value - self.lower
        hi = math.inf if self.upper is None else self.upper - self.value
        return min(lo, hi)

    @property
    def violated(self) -> bool:
        return self.margin < -MARGIN_TOL * self.scale


def _as_sx(expr) -> ca.SX | None:
    if isinstance(expr, ca.SX):
        return ca.vec(expr)
    try:
        return ca.vec(ca.SX(expr))
    except (NotImplementedError, TypeError, RuntimeError):
        return None


def _points(problem, function, rng) -> list[list[np.ndarray]]:
    """Up to POINTS evaluations of ``function`` (rules, their Jacobian, rows, theirs) at points drawn in the bounds
    where the equality rows and their Jacobian are finite (a rule NaN there is judged on its other points)."""
    lo, hi = problem.lbx, problem.ubx
    base = np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi),
                    np.where(np.isfinite(lo), lo + 1.0, np.where(np.isfinite(hi), hi - 1.0, 0.0)))
    width = np.where(np.isfinite(lo) & np.isfinite(hi), hi - lo, 2.0)
    out = []
    for draw in range(DRAWS):
        x = base if draw == 0 else np.clip(base + (rng.random(base.size) - 0.5) * width, lo, hi)
        values = [np.asarray(v, float) for v in function(x)]
        if np.all(np.isfinite(values[2])) and np.all(np.isfinite(values[3])):
            out.append(values)
    return out


def pinned_rules(problem, design_columns: dict[int, tuple[str, ...]] | None = None) -> list[PinnedRule]:
    """The rules of ``problem`` whose value no free decision variable moves (the module docstring), in rule order.
    ``design_columns``: decision entry -> the spec paths of the design variables it is (to name the fixed ones a
    pinned rule reads).  A rule the model cannot evaluate at two points of the bounds is not judged."""
    x, params = problem.x, problem.parameters
    n = x.numel()
    free = problem.ubx > problem.lbx
    # each row as "expression - target", zero where it holds (a row 'sum of the angles = 360' reads 0 there, not 360)
    equalities = [_row(e, lb) for e, lb, ub in problem.structural if lb is not None and ub is not None and lb == ub]
    # rows that read a parameter are left out (what they pin is not judged: the parameters' values are the kind's)
    rows = [r for r in equalities if r is not None and not (params.numel() and ca.depends_on(r, params))]
    h = ca.vertcat(*rows) if rows else ca.SX(0, 1)
    # a free entry no equality row reads: a rule that reads it is moved by it (its Jacobian column cannot be a
    # combination of the rows' zeros), so the numeric test needs only the rules reading none such
    touched = np.array(ca.which_depends(h, x, 1, False), bool) if h.numel() else np.zeros(n, bool)
    candidates = []
    for rule in problem.rules:
        if rule.missing is not None:
            continue
        e = _as_sx(rule.expr)
        if e is None or e.numel() == 0:
            continue
        if params.numel() and ca.depends_on(e, params):
            continue
        reads = np.array(ca.which_depends(e, x, 1, False), bool)
        if np.any(reads & free & ~touched):
            continue
        candidates.append((rule, e))
    if not candidates:
        return []
    e_all = ca.vertcat(*[e for _, e in candidates])
    function = ca.Function("pinned", [x], [e_all, ca.jacobian(e_all, x), h, ca.jacobian(h, x)])
    every_point = _points(problem, function, np.random.default_rng(0))
    out, offset = [], 0
    for rule, e in candidates:
        k = e.numel()
        rows_k = slice(offset, offset + k)
        offset += k
        points = [p for p in every_point
                  if np.all(np.isfinite(p[0][rows_k])) and np.all(np.isfinite(p[1][rows_k]))][:POINTS]
        if len(points) < 2:         # too few points where the model evaluates it: nothing is known
            continue
        # first over every entry (pinned by inputs that are no design variable), then over the free ones only (the
        # fixed design variables it reads pin it too: named)
        for columns in (np.ones(n, bool), free):
            c = _combination(points[0][1][rows_k][:, columns], points[0][3][:, columns], h.numel())
            if all(_explained(p[1][rows_k][:, columns], c, p[3][:, columns]) for p in points):
                break
        else:
            continue
        used = np.any(c != 0.0, axis=0)
        values = points[0][0][rows_k].ravel() - c[:, used] @ points[0][2].ravel()[used]
        # the value on the rows' manifold must be the same at every point too: a rule with a branch (fmax, if_else)
        # inactive at the first point may move at another, where its Jacobian alone could have been matched
        if not all(_same(values, p[0][rows_k].ravel() - c[:, used] @ p[2].ravel()[used], rule.scale)
                   for p in points[1:]):
            continue
        je, jh = points[0][1][rows_k], points[0][3]
        fixed_read = [] if columns is not free else [
            i for i in range(n) if not free[i] and not _explained(je[:, [i]], c, jh[:, [i]])]
        names = tuple(dict.fromkeys(name for i in fixed_read for name in (design_columns or {}).get(i, ())))
        out.append(PinnedRule(rule.name, _worst(values, rule.lower, rule.upper), rule.lower, rule.upper, rule.unit,
                              rule.scale, names))
    return out


def _row(expr, target) -> ca.SX | None:
    row = _as_sx(expr)
    return None if row is None else row - ca.vec(ca.DM(target))


def _same(a: np.ndarray, b: np.ndarray, scale: float) -> bool:
    """Two readings of a pinned rule's value agree (to round-off of the value and its scale)."""
    size = max(float(np.max(np.abs(a), initial=0.0)), float(np.max(np.abs(b), initial=0.0)), abs(scale))
    return float(np.max(np.abs(a - b), initial=0.0)) <= JACOBIAN_RTOL * max(size, 1e-300)


def _combination(je: np.ndarray, jh: np.ndarray, m: int) -> np.ndarray:
    """The least-squares ``C`` of ``je ~ C jh`` (zero without rows)."""
    if jh.size == 0 or je.size == 0:
        return np.zeros((je.shape[0], m))
    return np.linalg.lstsq(jh.T, je.T, rcond=None)[0].T


def _explained(je: np.ndarray, c: np.ndarray, jh: np.ndarray) -> bool:
    """Whether the rule's Jacobian ``je`` is ``c`` x the rows' ``jh`` (to round-off of their size)."""
    if je.size == 0:
        return True
    fit = c @ jh if jh.size else np.zeros_like(je)
    # relative only: a rule whose derivatives are small in its units (seconds per mm) is not taken for a fixed one
    size = max(float(np.max(np.abs(je))), float(np.max(np.abs(fit))) if fit.size else 0.0)
    return float(np.max(np.abs(je - fit))) <= JACOBIAN_RTOL * size


def _worst(values: np.ndarray, lower, upper) -> float:
    """The sample a record reports: the one with the smallest margin."""
    lo = np.full_like(values, np.inf) if lower is None else values - lower
    hi = np.full_like(values, np.inf) if upper is None else upper - values
    return float(values[int(np.argmin(np.minimum(lo, hi)))])


def _asks(rule: PinnedRule) -> str:
    """"45..50 mm", ">= 40 deg", "<= 30 deg"."""
    unit = f" {rule.unit}" if rule.unit and rule.unit not in ("-", "1") else ""
    if rule.lower is not None and rule.upper is not None:
        return f"{rule.lower:g}..{rule.upper:g}{unit}"
    return f">= {rule.lower:g}{unit}" if rule.lower is not None else f"<= {rule.upper:g}{unit}"


def _listed(names) -> str:
    names = list(names)
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def fixed_by_text(kind, rule: PinnedRule) -> tuple[str, str]:
    """(what fixes the rule, what to do): the fixed design variables it reads where it reads any (a number the spec
    gives where bounds would free it), else the kind's declaration (:attr:`Kind.fixed_by`: the input that alone
    fixes it), else the spec's inputs in general."""
    limits = "the rule's limits"
    declared = kind.rule_fixed_by(rule.name)
    if declared is not None:
        limits = declared.limits
    if rule.fixed_variables:
        fixed = _listed(rule.fixed_variables)
        return (f"{fixed}, given as {'a number' if len(rule.fixed_variables) == 1 else 'numbers'}",
                f"give {fixed} bounds, or change {limits}")
    if declared is not None:
        return declared.inputs, f"change {declared.inputs} or {declared.limits}"
    return "the spec's inputs", f"change the inputs it reads or {limits}"


def message(kind, rule: PinnedRule) -> str:
    """"planting_depth = 35 mm is fixed by [soil] analysis_depth (no design variable moves it); the rule asks 45..50
    mm: change [soil] analysis_depth or [rules] depth"."""
    unit = f" {rule.unit}" if rule.unit and rule.unit not in ("-", "1") else ""
    by, change = fixed_by_text(kind, rule)
    return (f"{rule.name} = {rule.value:.4g}{unit} is fixed by {by} (no design variable moves it); the rule asks "
            f"{_asks(rule)}: {change}")


def design_columns(kind, spec, nlp) -> dict[int, tuple[str, ...]]:
    """Decision entry -> the spec paths (``[arm] l1``) of the design variables it moves: the kind's
    ``design_affine`` of the NLP's first ``len(nlp.names)`` entries."""

    names = list(getattr(nlp, "design_names", nlp.names))
    try:
        _, jacobian = kind.design_affine(spec, len(names))
        paths = describe(spec)
    except (ValueError, TypeError, AttributeError, KeyError):
        return {}

    def written(name: str) -> str:
        path = (paths.get(name) or {}).get("path")
        if not path:
            return name
        table, _, key = path.partition(".")
        return f"[{table}] {key}" if key else path

    jacobian = np.asarray(jacobian, float)
    return {i: tuple(written(names[j]) for j in range(min(len(names), jacobian.shape[0])) if jacobian[j, i] != 0.0)
            for i in range(min(len(names), jacobian.shape[1]))}


def of_nlp(kind, spec, nlp) -> list[PinnedRule]:
    """The pinned rules of a kind's built NLP (none for one with nothing compiled)."""
    compiled = getattr(nlp, "compiled", None)
    problem = getattr(compiled, "problem", None)
    if problem is None:
        return []
    return pinned_rules(problem, design_columns(kind, spec, nlp))


def refuse_violated(kind, spec, nlp) -> list[PinnedRule]:
    """Before any start: a SpecError (exit 2) naming each violated pinned rule, its value, its limit and the spec
    field that fixes it; else the pinned rules (each holding)."""
    pinned = of_nlp(kind, spec, nlp)
    violated = [r for r in pinned if r.violated]
    if violated:
        raise SpecError(f"{kind.name}: " + "; ".join(message(kind, r) for r in violated)
                        + " (no start was solved: no design meets this rule)")
    return pinned


def fixed_fields(kind, pinned: list[PinnedRule], among: list[str]) -> dict[str, str]:
    """Rule name -> what fixes it, of the pinned rules named ``among`` (those an elastic diagnosis gives up on), for
    the exit-3 message (:func:`synthesis.core.verdict.unsatisfied_error`)."""
    return {r.name: fixed_by_text(kind, r)[0] for r in pinned if r.name in among}


__all__ = ["PinnedRule", "pinned_rules", "of_nlp", "refuse_violated", "message", "fixed_fields", "design_columns"]
