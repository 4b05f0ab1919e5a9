"""How sure is "optimal"?  Distinct local optima among a multistart's starts, and a Bayesian estimate of how many
were not seen and of the probability that the best found is the global optimum within the bounds.

The estimate is Boender and Rinnooy Kan's (C. G. E. Boender and A. H. G. Rinnooy Kan, "Bayesian stopping rules for
multistart global optimization methods", Mathematical Programming 37 (1987) 59-80).  Its model:

- each start is drawn at random from the design box and its local solve ends at the optimum whose *basin* (region
  of attraction) holds the start; the basins cover the box and do not overlap;
- the number of optima K has a uniform (improper) prior on 1, 2, ...; given K, the basins' relative sizes have a
  uniform prior on the simplex (a Dirichlet(1, ..., 1) distribution).

After N starts that reached W distinct optima, the posterior of K is

    p(k | N, W)  proportional to  k! (k - 1)! / ((k - W)! (N + k - 1)!),    k >= W,

whose mean is W (N - 1) / (N - W - 2) (finite when N >= W + 3); the posterior expected share of the box held by
the basins not yet seen is W (W + 1) / (N (N - 1)).  Boender and Rinnooy Kan stop when the expected number of
optima not yet seen is below one half.  We add one quantity of the same model: if the global optimum's basin is any
of the K basins, none favoured (its size drawn like the others'), the probability that it is among the W seen is
the posterior mean of W / K, which is (N - W - 1) / (N - 1).

Where the model fails: the starts are not uniform in the box (a kind that builds its own starts, screened or
continued starts, a start map that is not the identity); basins of very unequal size (a global optimum with a tiny
basin is found less often than the model assumes, so the probability is then an overestimate); local solves that
end at a point that is not a local optimum (those starts are left out of N: only starts that converged with every
rule held count).  The result says so beside the numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import gammaln

#: starts whose objectives agree to this relative tolerance (of max(1, |f|)) and whose designs lie within
#: DESIGN_TOLERANCE of each other in the unit box are one optimum.  IPOPT stops at a KKT error of 1e-8 (tol) or,
#: accepted, 1e-6 (acceptable_tol) in its scaled problem; an objective is then known to about the square of the
#: design's error times the curvature, so 1e-6 relative separates optima that differ in the sixth digit and no
#: closer, and 1e-3 of the box in the design keeps two starts that stopped a little apart on a flat valley one.
OBJECTIVE_TOLERANCE = 1e-6
DESIGN_TOLERANCE = 1e-3
#: the posterior sums run to this k beyond W; past it the tail is added in closed form (terms fall as k^(W - N))
_TERMS = 20_000


@dataclass(frozen=True)
class Optimum:
    """One distinct local optimum: its objective, the starts that reached it, the first of them."""
    objective: float
    starts: tuple[int, ...]

    @property
    def count(self) -> int:
        return len(self.starts)


def distinct_optima(objectives, unit_designs, start_ids, *, objective_tolerance: float = OBJECTIVE_TOLERANCE,
                    design_tolerance: float = DESIGN_TOLERANCE) -> list[Optimum]:
    """Group converged starts into distinct optima, best first.

    ``objectives`` (N), ``unit_designs`` (N x n, each design mapped to the unit box by its bounds) and
    ``start_ids`` (N) are of the starts that converged with every rule held.  Two starts are one optimum when their
    objectives agree to ``objective_tolerance`` (relative to max(1, |f|)) and their designs are within
    ``design_tolerance`` (max-norm, unit box); starts are taken in order of objective, each joining the first
    optimum it matches (its representative: the best start of the group), so the grouping is the same for any
    order of the input.
    """
    f = np.asarray(objectives, dtype=float)
    if not len(f):
        return []
    x = np.asarray(unit_designs, dtype=float).reshape(len(f), -1)
    ids = np.asarray(start_ids)
    order = np.lexsort((ids, f))
    groups: list[tuple[float, np.ndarray, list[int]]] = []
    for i in order:
        for g_f, g_x, members in groups:
            close_f = abs(f[i] - g_f) <= objective_tolerance * max(1.0, abs(g_f))
            if close_f and float(np.max(np.abs(x[i] - g_x), initial=0.0)) <= design_tolerance:
                members.append(int(ids[i]))
                break
        else:
            groups.append((float(f[i]), x[i], [int(ids[i])]))
    return [Optimum(g_f, tuple(sorted(members))) for g_f, _, members in groups]


def _log_posterior_terms(n: int, w: int, k: np.ndarray) -> np.ndarray:
    """log of k! (k-1)! / ((k-w)! (n+k-1)!): the unnormalised posterior of K = k."""
    return gammaln(k + 1) + gammaln(k) - gammaln(k - w + 1) - gammaln(n + k)


def _terms(n: int, w: int, k_max: int | None) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(k, the posterior's terms over its first, log of the first term, their sum with the tail): the one place the
    sum is cut (at k_max, a test's proper prior; else past _TERMS terms, its tail added in closed form: the terms
    fall as k^(w - n) (Stirling))."""
    last = k_max if k_max is not None else w + _TERMS
    k = np.arange(w, last + 1, dtype=float)
    logp = _log_posterior_terms(n, w, k)
    p = np.exp(logp - logp[0])
    total = p.sum() + (p[-1] * k[-1] / (n - w - 1) if k_max is None else 0.0)
    return k, p, float(logp[0]), float(total)


def posterior_mean(n: int, w: int, power: float, k_max: int | None = None) -> float:
    """E[K^power | N = n starts, W = w optima] under the uniform prior on K (on w..k_max when given; else on every
    k >= w: the sum converges when n >= w + 2 + power)."""
    k, p, _, total = _terms(n, w, k_max)
    moment = np.sum(p * k ** power)
    if k_max is None:
        moment += p[-1] * k[-1] ** power * k[-1] / (n - w - 1 - power)
    return float(moment / total)


def probability_k(n: int, w: int, k: int, k_max: int | None = None) -> float:
    """P(K = k | N = n, W = w) (the prior as in :func:`posterior_mean`)."""
    _, _, log_first, total = _terms(n, w, k_max)
    return float(np.exp(_log_posterior_terms(n, w, np.array([float(k)]))[0] - (log_first + np.log(total))))


@dataclass(frozen=True)
class Confidence:
    """The confidence statement of one multistart (result.json ``solver.confidence``)."""
    starts_counted: int                  # N: starts that converged with every rule held
    distinct_optima: int                 # W
    starts_at_best: int                  # starts that reached the best optimum
    expected_optima: float | None        # posterior mean of K (None: N < W + 3, not defined)
    expected_unseen: float | None        # expected_optima - W
    unseen_basin_share: float | None     # posterior expected share of the box in basins not seen (N >= 2)
    probability_all_found: float | None  # posterior P(K = W)
    probability_global: float | None     # posterior mean of W / K: the best found is the global optimum
    sure: bool                           # Boender and Rinnooy Kan's rule: expected_unseen < 0.5

    def to_json(self) -> dict:
        return {"starts_counted": self.starts_counted, "distinct_optima": self.distinct_optima,
                "starts_at_best": self.starts_at_best, "expected_optima": self.expected_optima,
                "expected_unseen_optima": self.expected_unseen, "unseen_basin_share": self.unseen_basin_share,
                "probability_all_optima_found": self.probability_all_found,
                "probability_best_is_global": self.probability_global, "stopping_rule_met": self.sure,
                "method": "Boender & Rinnooy Kan (1987), uniform prior on the number of optima and on basin sizes"}


def confidence(optima: list[Optimum]) -> Confidence:
    """The Bayesian statement for the distinct optima of N counted starts (:func:`distinct_optima`)."""
    n = sum(o.count for o in optima)
    w = len(optima)
    best = optima[0].count if optima else 0
    if w == 0:
        return Confidence(0, 0, 0, None, None, None, None, None, False)
    if n < w + 2:             # the posterior is improper: every start found a new optimum, or nearly
        return Confidence(n, w, best, None, None, None, None, None, False)
    share = w * (w + 1) / (n * (n - 1))
    # the posterior mean of W / K is (N - W - 1) / (N - 1) (the sum of posterior_mean(n, w, -1) in closed form;
    # tests/test_confidence.py checks the two agree)
    p_global = (n - w - 1) / (n - 1)
    p_all = probability_k(n, w, w)
    if n < w + 3:
        return Confidence(n, w, best, None, None, share, p_all, p_global, False)
    expected = w * (n - 1) / (n - w - 2)
    return Confidence(n, w, best, expected, expected - w, share, p_all, p_global, expected - w < 0.5)



#: result.json ``solver.confidence`` lists at most this many optima, best first
OPTIMA_SHOWN = 10


def statement(objectives, unit_designs, start_ids, *, maximise: bool = False,
              assumptions_not_met: list[str] | tuple[str, ...] = ()) -> dict:
    """result.json ``solver.confidence``: the :class:`Confidence` fields of the distinct optimum *values* (starts
    whose objectives tie are one optimum, whatever their designs), ``distinct_designs`` (the optima in the unit
    box, :func:`distinct_optima`), the optima (``objective`` as the kind states it, ``starts`` reaching it,
    ``first_start``, ``designs`` at it), at most OPTIMA_SHOWN, best first, and where the model's assumptions are
    known not to hold.  A maximised objective is grouped as its negative (best first)."""
    sign = -1.0 if maximise else 1.0
    f = sign * np.asarray(objectives, dtype=float)
    designs = distinct_optima(f, unit_designs, start_ids)
    # the question is whether a better objective exists: optima of one objective at distinct designs (a valley of
    # equal designs, as an angle that only one of its variables sets, or symmetric twins) are one level,
    # else a flat valley's starts, each stopping somewhere along it, count as ever more optima never all found
    optima = distinct_optima(f, unit_designs, start_ids, design_tolerance=math.inf)
    notes = list(assumptions_not_met)
    if len(designs) > len(optima):
        notes.append(f"{len(designs)} optima at distinct designs share {len(optima)} objective value"
                     f"{'' if len(optima) == 1 else 's'} (a flat valley or symmetric optima): counted as one optimum "
                     f"per value")
    level_of = {i: k for k, o in enumerate(optima) for i in o.starts}
    return {**confidence(optima).to_json(), "distinct_designs": len(designs),
            "optima": [{"objective": sign * o.objective, "starts": o.count, "first_start": o.starts[0],
                        "designs": sum(1 for d in designs if level_of[d.starts[0]] == k)}
                       for k, o in enumerate(optima[:OPTIMA_SHOWN])],
            "assumptions_not_met": notes}
