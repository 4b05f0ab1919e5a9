"""The bench studies every solving kind gets from its declared Problem, with no code of its own.

A kind's default bench set (``Kind.bench``) is a few library specs; :func:`library_cases` turns each
into a :class:`~synthesis.bench.BenchCase` whose methods all run the kind's own multistart
(:func:`synthesis.core.solve.run_multistart`: its starts, its fine-grid re-check, its verdict), with
``starts`` capped at the study's start count and one worker:

ipopt_multistart          IPOPT with CasADi's exact derivatives (the reference of every ratio)
ipopt_finite_differences  the same NLP with IPOPT fed function values only: forward differences of f
                          and g and a limited-memory Hessian (:func:`synthesis.core.ipopt.derivatives`)
slsqp                     scipy.optimize.minimize(method="SLSQP") on the same transcribed NLP (the kind's
                          f and g as numeric CasADi Functions, scipy's finite differences, the rows as
                          scipy constraints, maxiter = the spec's max_iter, ftol 1e-9), from the same starts
                          (:func:`synthesis.core.ipopt.solved_with`), stopped at its time budget
                          (``slsqp_budget_s`` per run, shared by the starts)
differential_evolution    scipy's differential_evolution over the same NLP's variables (its bounds; rows
                          as a NonlinearConstraint), one run from the spec's start (x0), default strategy
                          and population, no polish, stopped at the time budget; a variable with no finite
                          bound (a length unbounded above, an epigraph or slack variable) is searched within
                          one decade of its start (:func:`de_bounds`)

Objectives are compared minimised (a maximising kind's objective is negated and the case note says
so); a run reaches the target when every rule holds on the fine grid and its objective is within
TOLERANCE of the best known (see :mod:`synthesis.bench`), so no ratio is ever taken between runs
that ended at different objectives.

Two studies besides: :func:`sample_sweep` (the solve at scaled sample counts of every ``[solver]``
``*samples*`` setting: time, iterations, fine-grid violation, gap to the finest) and the build/solve
split every multistart run reports (``details``: ``build_s`` = prepare + NLP build, ``ipopt_s`` = sum of
the solver's start times, ``recheck_s`` = the rest of the starts' time, mostly the fine-grid re-check).
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time
from pathlib import Path
from typing import Callable

import numpy as np

from synthesis.bench import BenchCase, MethodRun

LIBRARY = Path(__file__).resolve().parents[1] / "problems"
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


FULL = StudySettings()
#: --quick: one start, two sample counts (the spec's own is the AD run, not solved again), no peers, no
#: reference solve, one run per method, the first problem of each kind, no extreme matrix
QUICK = StudySettings(starts=1, factors=(0.5, 1.0), peers=(), reference=False, sweep_budget_s=30.0)


def tolerance(best: float) -> float:
    return max(ABS_TOLERANCE, REL_TOLERANCE * abs(best))


# ---------------------------------------------------------------------------- one measured multistart

def _with_solver(loaded, **update):
    spec = loaded.model
    return dataclasses.replace(loaded, model=spec.model_copy(update={"solver": spec.solver.model_copy(update=update)}))


def measure(loaded, starts: int, seed: int, derivatives: str = "exact", runner: Callable | None = None) -> MethodRun:
    """The kind's multistart on ``loaded`` (one worker), timed: objective (minimised), fine-grid worst
    violation, best-so-far trace, and the build/solve split and iterations in ``details``."""
    from synthesis import kinds
    from synthesis.core import ipopt
    from synthesis.core.kind import Setting
    from synthesis.core.solve import run_multistart

    kind = kinds.get(loaded.kind)
    solving = kind.solver_side()
    spec = loaded.model
    trace: list[tuple[float, float]] = []
    t0 = time.perf_counter()
    with ipopt.derivatives(derivatives), ipopt.solved_with(runner):
        setting = Setting(spec, seed, solving.prepare(spec))
        sign = -1.0 if solving.maximise(setting) else 1.0

        def on_start(report, best) -> None:
            if best.satisfied:
                trace.append((time.perf_counter() - t0, sign * best.outcome.objective))

        run = run_multistart(kind, setting, starts=starts, workers=1, on_start=on_start)
    total = time.perf_counter() - t0
    best = run.best
    ipopt_s = sum(r.outcome.wall_s for r in run.reports)
    objective = sign * best.outcome.objective
    iterations = [r.outcome.iterations for r in run.reports]
    details = {
        "starts": len(run.reports), "successes": sum(bool(r.outcome.success) for r in run.reports),
        "satisfied_starts": sum(r.satisfied for r in run.reports),
        "iterations": iterations, "median_iterations": float(statistics.median(iterations)),
        "best_iterations": best.outcome.iterations, "return_status": best.outcome.return_status,
        "best_start": best.outcome.start, "maximised": sign < 0,
        "build_s": total - run.wall_s, "ipopt_s": ipopt_s, "recheck_s": max(run.wall_s - ipopt_s, 0.0),
        "samples": sample_settings(spec),
    }
    return MethodRun(objective if math.isfinite(objective) else math.inf, best.worst_violation, trace, details)


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


def slsqp_runner(compiled, start: int, w0: np.ndarray, p: np.ndarray, budget_s: float = math.inf):
    """scipy SLSQP on the transcribed NLP from the kind's start; function values only (scipy's differences);
    stopped (StopIteration from its callback) once ``budget_s`` of wall time has passed."""
    from scipy.optimize import minimize

    from synthesis.core.ipopt import NLPOutcome

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
    t0 = time.perf_counter()

    def budget(xk) -> None:        # callback(x): scipy 1.17 prints a callback(intermediate_result) when it drops fixed variables
        if time.perf_counter() - t0 > budget_s:
            raise StopIteration

    res = minimize(f, x0, method="SLSQP", bounds=bounds, constraints=constraints, callback=budget,
                   options={"maxiter": compiled.problem.max_iter, "ftol": 1e-9})
    wall = time.perf_counter() - t0
    x = np.asarray(res.x, float)
    return NLPOutcome(start, x, f(x), f"SLSQP: {res.message}", bool(res.success), int(res.nit), wall, "",
                      np.zeros(len(lbg)))


def slsqp_with_budget(budget_s: float) -> Callable:
    """:func:`slsqp_runner` stopped at ``budget_s`` per start."""
    return lambda compiled, start, w0, p: slsqp_runner(compiled, start, w0, p, budget_s)


def de_runner(budget_s: float, seed: int) -> Callable:
    def run(compiled, start: int, w0: np.ndarray, p: np.ndarray):
        from scipy.optimize import NonlinearConstraint, differential_evolution

        from synthesis.core.ipopt import NLPOutcome

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
        t0 = time.perf_counter()
        res = differential_evolution(lambda z: f(full(z)), list(zip(lbw[free], ubw[free])),
                                     constraints=constraints, x0=base[free], rng=seed, polish=False,
                                     callback=lambda intermediate_result: time.perf_counter() - t0 > budget_s)
        wall = time.perf_counter() - t0
        x = full(np.asarray(res.x, float))
        note = f" (finite bounds derived from the start for {derived} variable(s): {DE_BOUNDS_RULE})" if derived else ""
        return NLPOutcome(start, x, f(x), f"differential_evolution: {res.message}{note}", bool(res.success),
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
        runs = list(reuse()[:settings.sweep_repeats]) if key == own and reuse is not None else []
        reused = len(runs)
        for k in range(len(runs), settings.sweep_repeats):
            tick(f"{loaded.name}: samples {_samples_text(samples)} {k + 1}/{settings.sweep_repeats}")
            runs.append(measure(_with_solver(loaded, **samples), starts, seed))
            tick(None)
        walls = [r.details["build_s"] + r.details["ipopt_s"] + r.details["recheck_s"] for r in runs]
        median = float(statistics.median(walls))
        typical = min(runs, key=lambda r: abs(sum(r.details[k] for k in ("build_s", "ipopt_s", "recheck_s")) - median))
        rows.append({"factor": factor, "samples": samples, "wall_s": walls, "median_s": median,
                     "build_s": typical.details["build_s"], "ipopt_s": typical.details["ipopt_s"],
                     "iterations": typical.details["iterations"],
                     "median_iterations": typical.details["median_iterations"],
                     "objective": typical.objective, "worst_violation": typical.worst_violation,
                     "satisfied": typical.worst_violation == 0 and math.isfinite(typical.objective),
                     "reused_runs": reused})
    finest = rows[-1]["objective"] if rows else math.nan
    for row in rows:
        row["objective_gap"] = (abs(row["objective"] - finest) if math.isfinite(row["objective"]) and math.isfinite(finest)
                                else math.inf)
    reaching = None
    for i, row in enumerate(rows):
        if all(r["worst_violation"] <= VIOLATION_TARGET for r in rows[i:]):
            reaching = i
            break
    return {"problem": loaded.name, "kind": loaded.kind, "starts": starts, "repeats": settings.sweep_repeats,
            "violation_target": VIOLATION_TARGET, "rows": rows, "skipped": skipped,
            "reaching": None if reaching is None else {"samples": rows[reaching]["samples"],
                                                       "median_s": rows[reaching]["median_s"],
                                                       "worst_violation": rows[reaching]["worst_violation"]}}


def _samples_text(samples: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in samples.items())


# ---------------------------------------------------------------------------- the cases

def _method(loaded, starts: int, seed: int, keep: list | None = None, **how) -> Callable[[float], MethodRun]:
    def run(target: float) -> MethodRun:
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
                     + ("; peers (SLSQP, differential_evolution) not run" if not settings.peers else ""),
                     loaded=loaded, single_runs={"slsqp", "differential_evolution"},
                     sweep=lambda tick: sample_sweep(loaded, settings, spec_seed, tick, reuse=lambda: ad_runs),
                     sweep_runs=len({tuple(sorted(scaled_samples(loaded.model, f).items())) for f in settings.factors}
                                    - {tuple(sorted(sample_settings(loaded.model).items()))}) * settings.sweep_repeats,
                     studies=studies or {}, warmup=lambda: measure(loaded, 1, spec_seed))


def library_cases(specs, seed: int, default: list[str], settings: StudySettings | None = None,
                  studies: dict | None = None) -> list[BenchCase]:
    """The kind's bench cases: ``specs`` (LoadedSpec list) or, when None, the ``default`` library files
    (relative to problems/).  ``studies``: extra rows (name -> callable) the kind adds to its first case."""
    from synthesis.spec import load_spec

    if settings is None:
        from synthesis.bench import current_settings
        settings = current_settings()
    if specs is None:
        specs = [load_spec(LIBRARY / f) for f in default[:1 if settings is QUICK else None]]
    return [case_for(s, settings, seed, studies if i == 0 else None) for i, s in enumerate(specs)]
