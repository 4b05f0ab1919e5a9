"""Bench cases of kind fourbar_path: IPOPT multistart against scipy's differential_evolution.

Every method gets the same problem and stops at the same target objective (best known + tolerance):

ipopt_multistart        ``run_solve`` exactly as ``agrisynth solve`` runs it (one worker; the inexact and
                        literature sets INEXACT_WORKERS), with the spec's starts and seed and
                        [solver] stop_at_objective = the target
differential_evolution  scipy.optimize.differential_evolution with its default settings (best1bin,
                        popsize 15, maxiter 1000, tol 0.01, Latin-hypercube init, polish), evaluated
                        vectorised (updating "deferred", which vectorisation needs), the rules as
                        scipy constraints, stopped by its callback at the target; seed = the spec's
differential_evolution_equal_budget   (inexact and literature sets) the same DE, same seed, given the CPU
                        seconds the multistart spent in the same round (every worker's: its pool start,
                        NLP builds and screen included, so the budget leans towards DE), no generation
                        limit, no polish; its generation count varies with the machine's speed
published               (literature sets) the best published linkage, scored with this package's
                        objective and fine-grid re-check (no solve: no time ratio)

DE encoding of free timing (every vector meets the sequence rule, so DE never wastes an evaluation
on an infeasible order): theta_1 in [0, 360) deg, N gap weights w_i in [0, 1] and, for direction
"either", a direction variable s in [-1, 1] (counter-clockwise when s >= 0, clockwise otherwise;
"ccw"/"cw" fix it).  The N weights share one turn: gap_i = 360 w_i / sum(w), the first N - 1 are the
steps theta_{i+1} - theta_i (times the direction's sign), the last is the rest of the turn, so the
targets are met in order within at most one turn.  With [rules] order = false the N angles are
independent, each in [0, 360).  DE sees the Grashof rows as a LinearConstraint and the transmission
angle as its exact extremes (cos mu at theta2 = 0 and 180 deg), and evaluates its population with
the complex-number construction (construction.joint_positions, vectorised).  Both results are
re-checked as every solver start is (check.evaluate: the kind's rules on floats).

Problems: the library specs given, or by default the picking arc, six synthetic-truth problems
(mechanism 1 with 6, 10, 18 points, timing free and prescribed), the ten inexact-target problems of
the free-timing study (inexact.py), the literature's target sets (literature.py) and the many-target case: a
coupler curve digitised with 0.2 mm noise at 1,000 points, solved with every start, with the study ``many_targets``
(the CPU seconds of the screen, the NLP's build, a start's solve and the whole ``agrisynth solve`` at 25, 100, 250
and 1,000 targets, timing free and prescribed, and the slope of log(time) against log(n) of each).  Best known: 0 for the synthetic
problems (zero error by construction, tolerance 1e-8 mm^2); for a library spec the objective of
an untimed reference multistart (all starts, no early stop) with a *different* seed (the spec's
seed + REFERENCE_SEED_OFFSET), so the target does not come from the very IPOPT run being timed;
tolerance 1e-6 relative.  A method that misses the target has no time ratio (synthesis.bench).
"""

from __future__ import annotations

import dataclasses
import json
import math
import multiprocessing
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any, Callable, cast

try:
    import resource
except ImportError:          # not POSIX: the budget falls back to wall time x workers
    resource = None  # type: ignore[assignment]  # mypy types the module name as the module

import numpy as np
from scipy.optimize import LinearConstraint, NonlinearConstraint, differential_evolution

from synthesis.core.bench_case import BenchCase, MethodRun
from synthesis import kinds
from synthesis.library import LIBRARY
from synthesis.core.solve import run_solve
from synthesis.kinds.fourbar_path.check import evaluate
from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.kinds.fourbar_path.inexact import BEST_KNOWN, NAMES, inexact_spec
from synthesis.kinds.fourbar_path import literature
from synthesis.core.kind import Setting
from synthesis.kinds.fourbar_path.nlp import PathNLP
from synthesis.kinds.fourbar_path.starts import CLASS_ROWS, StartMaker, forget_screened
from synthesis.kinds.fourbar_path.synthetic import loaded_spec, noisy_truth_data, truth_spec
from synthesis.kinds.fourbar_path.kinematics import BRANCHES, VARIABLES
from synthesis.spec import LoadedSpec, load_spec
from synthesis.spec.reference import write_toml
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec
from synthesis.result import Result

FOURBAR_PATH_LIBRARY = LIBRARY / "fourbar_path"
DEFAULT_SYNTHETIC = [(1, n, timed) for n in (6, 10, 18) for timed in (False, True)]
SYNTHETIC_TOLERANCE = 1e-8          # mm^2: the "recovered" threshold of the tests
LIBRARY_RELATIVE_TOLERANCE = 1e-6
BIG = 1e30                          # objective where the loop does not close (DE needs a number)
REFERENCE_SEED_OFFSET = 1000        # the reference solve's seed: the spec's seed + this
TURN = 360.0 * (1.0 - 1e-12)         # deg: the span the DE gap weights share
SIGNS = {"ccw": (1.0,), "cw": (-1.0,), "either": (1.0, -1.0)}
DE_EQUAL_BUDGET = "differential_evolution_equal_budget"   # its method name (a peer: one run per case)
INEXACT_WORKERS = 2                 # the inexact study's goal is for 2 cores (the answer is the same for any count)


def worst_violation(spec: FourbarPathSpec, design: dict, crank_deg: list[float]) -> float:
    """Largest normalised rule violation as the re-check of a solver start measures it (0 when every
    rule holds; inf where the loop does not close at a target)."""
    ev = evaluate(spec, design, crank_deg, timing="solved")
    if not np.all(np.isfinite(ev.errors_mm)):
        return math.inf
    worst = 0.0
    for rule in ev.rules:
        rec = rule.record()
        if not rec.satisfied:
            worst = max(worst, math.inf if rec.normalised_margin is None else -rec.normalised_margin)
    return worst


# ---------------------------------------------------------------------------- IPOPT multistart

def cpu_seconds() -> float | None:
    """CPU seconds of this process and of its reaped children: the multistart's worker processes when they are this
    process's children (start method "fork"; the pool is shut down and waited for at the end of every solve).  None
    where that does not hold (another start method: the workers are a fork server's children; no ``resource``)."""
    if resource is None or multiprocessing.get_start_method() != "fork":
        return None
    me, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + children.ru_utime + children.ru_stime


def ipopt_multistart(loaded: LoadedSpec, workers: int = 1, spent: list[float] | None = None,
                     stop_at_target: bool = True):
    """The multistart as ``agrisynth solve`` runs it.  ``spent``: each run appends its CPU seconds (every
    worker's), the budget of differential_evolution at equal budget.  ``stop_at_target`` False: every start is run
    (a case with no best known, whose target is only known after its runs)."""
    def run(target: float) -> MethodRun:
        spec = cast(FourbarPathSpec, loaded.model)      # a fourbar_path spec (its kind's bench)
        stop = target if stop_at_target else spec.solver.stop_at_objective
        solver = spec.solver.model_copy(update={"stop_at_objective": stop})
        staged = dataclasses.replace(loaded, model=spec.model_copy(update={"solver": solver}))
        trace: list[tuple[float, float]] = []
        cpu0 = cpu_seconds()
        t0 = time.perf_counter()

        def on_start(report, best) -> None:
            if best.satisfied:
                trace.append((time.perf_counter() - t0, best.outcome.objective))

        result, reports, _ = run_solve(kinds.get("fourbar_path"), staged, workers=workers, on_start=on_start)
        wall = time.perf_counter() - t0
        cpu1 = cpu_seconds()
        # the budget of DE at equal budget: the multistart's CPU seconds, or (where they cannot be read) its wall time
        # times its workers, an upper bound of them
        if cpu0 is not None and cpu1 is not None:
            cpu, basis = cpu1 - cpu0, "cpu"
        else:
            cpu, basis = wall * workers, "wall x workers"
        if spent is not None:
            spent.append(cpu)
        solved, s = _solved(result)
        objective, violation = solved["value"], result.fine_grid_worst_violation
        return MethodRun(math.inf if objective is None else objective, math.inf if violation is None else violation,
                         trace, {"starts": s["starts"], "starts_run": s["starts_run"],
                                 "starts_needed": s["starts_needed"], "best_start": s["best_start"],
                                 "status": result.status, "return_status": s["return_status"],
                                 "workers": workers, "cpu_s": cpu, "cpu_basis": basis,
                                 "median_iterations": float(np.median([r.outcome.iterations for r in reports]))})
    return run


def reference_objective(loaded: LoadedSpec) -> float:
    """The best known objective of a library spec: the full multistart (every start, no early stop),
    untimed, seeded apart from the timed runs (seed + REFERENCE_SEED_OFFSET)."""
    spec = cast(FourbarPathSpec, loaded.model)
    solver = spec.solver.model_copy(update={"stop_at_objective": None,
                                            "seed": spec.solver.seed + REFERENCE_SEED_OFFSET})
    result, _, _ = run_solve(kinds.get("fourbar_path"),
                             dataclasses.replace(loaded, model=spec.model_copy(update={"solver": solver})), workers=1)
    return _solved(result)[0]["value"]


def _solved(result: Result) -> tuple[dict, dict]:
    """A solve's result.json ``objective`` and ``solver`` records (a check's result has neither)."""
    if result.objective is None or result.solver is None:
        raise TypeError(f"{result.name}: not the result of a solve")
    return result.objective, result.solver


# ---------------------------------------------------------------------------- differential evolution

@dataclasses.dataclass(frozen=True)
class DEProblem:
    """The spec in differential_evolution's terms: vectorised objective, bounds, constraints, decoding."""

    spec: FourbarPathSpec

    @property
    def n(self) -> int:
        return len(self.spec.targets.points)

    @property
    def free_timing(self) -> bool:
        return not self.spec.timed

    @property
    def ordered(self) -> bool:
        return self.free_timing and self.spec.rules.order

    @property
    def signs(self) -> tuple[float, ...]:
        return SIGNS[self.spec.rules.direction]

    def bounds(self) -> list[tuple[float, ...]]:
        b: list[tuple[float, ...]] = [tuple(x) for x in self.spec.bounds_array()]
        if self.ordered:
            b += [(0.0, 360.0)] + [(0.0, 1.0)] * self.n + ([(-1.0, 1.0)] if len(self.signs) > 1 else [])
        elif self.free_timing:
            b += [(0.0, 360.0)] * self.n
        return b

    def crank_deg(self, x: np.ndarray) -> np.ndarray:
        """(N, S) crank angles (deg) of columns x (D, S)."""
        if not self.free_timing:
            return np.tile(np.array(self.spec.targets.crank_deg)[:, None], (1, x.shape[1]))
        if not self.ordered:
            return x[9: 9 + self.n]
        weights = x[10: 10 + self.n]
        total = np.sum(weights, axis=0)
        # a hair under a full turn, so rounding in the sums never puts the last target past it
        gaps = TURN * weights[:-1] / np.where(total > 0.0, total, 1.0)    # all weights 0: every gap 0
        sign = self.signs[0] if len(self.signs) == 1 else np.where(x[10 + self.n] >= 0.0, 1.0, -1.0)
        return x[9] + sign * np.vstack([np.zeros((1, x.shape[1])), np.cumsum(gaps, axis=0)])

    def objective(self, x: np.ndarray) -> np.ndarray:
        """Sum of squared distances (mm^2) for each column of x (D, S); BIG where the loop is open."""
        x = np.asarray(x, dtype=float).reshape(len(self.bounds()), -1)
        design = {name: x[i] for i, name in enumerate(VARIABLES)}
        p = joint_positions(design, np.radians(self.crank_deg(x)), BRANCHES[self.spec.branch])["P"]
        t = np.array(self.spec.targets.points)
        f = np.sum(np.abs(p - (t[:, :1] + 1j * t[:, 1:])) ** 2, axis=0)
        return np.where(np.isfinite(f), f, BIG)

    def constraints(self) -> list:
        d = len(self.bounds())
        lim = self.spec.rules
        out = []
        if lim.grashof != "any":
            a = np.zeros((3, d))
            a[:, :4] = CLASS_ROWS[lim.grashof]
            out.append(LinearConstraint(a, 0.0, np.inf))
        if lim.transmission_angle is not None:
            lo, hi = (math.radians(v) for v in lim.transmission_angle)
            out.append(NonlinearConstraint(self._cos_extremes, [-np.inf, math.cos(hi)], [math.cos(lo), np.inf]))
        return out     # no sequence constraint: the encoding of the angles meets it (see the module doc)

    @staticmethod
    def _cos_extremes(x: np.ndarray) -> np.ndarray:
        r1, r2, r3, r4 = (np.asarray(x)[i] for i in range(4))
        base = r3 * r3 + r4 * r4 - r1 * r1 - r2 * r2
        return np.array([(base + 2 * r1 * r2) / (2 * r3 * r4), (base - 2 * r1 * r2) / (2 * r3 * r4)])

    def decode(self, x: np.ndarray) -> tuple[dict, list[float]]:
        x = np.asarray(x, dtype=float)
        design = {name: float(x[i]) for i, name in enumerate(VARIABLES)}
        return design, [float(a) for a in self.crank_deg(x[:, None])[:, 0]]


def differential_evolution_method(loaded: LoadedSpec, budget: list[float] | None = None):
    """scipy's differential_evolution on the spec (DEProblem), stopped at the target.

    ``budget``: equal budget -- the list the IPOPT multistart of the same case appends its CPU seconds to
    (ipopt_multistart's ``spent``; it runs first in every round of the bench).  DE then also stops when its
    own CPU seconds reach the latest of them, with no generation limit and no polish (scipy's polish runs
    after the stop and would spend past the budget); the result is DE's best member at that moment."""
    spec = cast(FourbarPathSpec, loaded.model)
    problem = DEProblem(spec)

    def run(target: float) -> MethodRun:
        trace: list[tuple[float, float]] = []
        evaluated = [0]         # designs whose objective was computed (scipy's nfev counts vectorised calls)
        if budget is not None and not budget:
            raise RuntimeError("differential_evolution at equal budget runs after the IPOPT multistart of its case")
        allowed = budget[-1] if budget else None
        t0, cpu0 = time.perf_counter(), time.process_time()

        def objective(x: np.ndarray) -> np.ndarray:
            f = problem.objective(x)
            evaluated[0] += f.size
            return f

        def callback(intermediate_result) -> bool:
            trace.append((time.perf_counter() - t0, float(intermediate_result.fun)))
            if allowed is not None and time.process_time() - cpu0 >= allowed:
                return True
            return bool(intermediate_result.fun <= target and _feasible(intermediate_result.x))

        def _feasible(x) -> bool:
            for c in problem.constraints():
                if isinstance(c, LinearConstraint):
                    v = c.A @ x
                else:
                    v = np.ravel(c.fun(x))
                if np.any(v < np.asarray(c.lb) - 1e-12) or np.any(v > np.asarray(c.ub) + 1e-12):
                    return False
            return True

        limits = {} if allowed is None else {"maxiter": 10 ** 9, "polish": False}
        with warnings.catch_warnings():
            # scipy's polish (trust-constr, quasi-Newton) warns at every flat step of the linear Grashof rows and
            # where its constraints' Jacobian is singular: noise on the user's terminal, not a finding of the run
            # (its result is re-checked below)
            warnings.filterwarnings("ignore", message="delta_grad == 0.0", category=UserWarning)
            warnings.filterwarnings("ignore", message="Singular Jacobian matrix", category=UserWarning)
            res = differential_evolution(objective, problem.bounds(), constraints=problem.constraints(),
                                         vectorized=True, updating="deferred", rng=spec.solver.seed,
                                         callback=callback, **limits)
        design, crank = problem.decode(res.x)
        fun = float(problem.objective(res.x[:, None])[0])
        trace.append((time.perf_counter() - t0, fun))
        return MethodRun(fun, worst_violation(spec, design, crank), trace,
                         {"generations": int(res.nit), "designs_evaluated": evaluated[0], "scipy_nfev": int(res.nfev),
                          "message": str(res.message), "cpu_s": time.process_time() - cpu0,
                          "budget_cpu_s": allowed,
                          "design": design, "crank_deg": crank})
    return run


# ---------------------------------------------------------------------------- the cases

def case_for(loaded: LoadedSpec, best_known=None, tolerance=None, note: str = "", workers: int = 1,
             equal_budget: bool = False) -> BenchCase:
    """IPOPT multistart (the reference) and differential evolution at its default budget; ``equal_budget``:
    also differential evolution given the CPU seconds the multistart spent in the same round."""
    if best_known is None:
        best_known = lambda: reference_objective(loaded)  # noqa: E731 - untimed, once per case
    if tolerance is None:
        tolerance = lambda best: max(SYNTHETIC_TOLERANCE, LIBRARY_RELATIVE_TOLERANCE * abs(best))  # noqa: E731
    spent: list[float] = []
    methods = {"ipopt_multistart": ipopt_multistart(loaded, workers, spent),
               "differential_evolution": differential_evolution_method(loaded)}
    if equal_budget:
        methods[DE_EQUAL_BUDGET] = differential_evolution_method(loaded, spent)
    return BenchCase(problem=loaded.name, kind="fourbar_path", methods=methods,
                     best_known=best_known, tolerance=tolerance, note=note)


def bench_cases(specs: list[LoadedSpec] | None, seed: int = 0) -> list[BenchCase]:
    """The given specs, or the default set: the library's fourbar_path specs, six synthetic problems,
    the ten inexact-target problems (synthesis.kinds.fourbar_path.inexact) and the literature's target sets
    with their published linkages (synthesis.kinds.fourbar_path.literature)."""
    inexact = specs is None
    if specs is None:
        specs = [load_spec(p) for p in sorted(FOURBAR_PATH_LIBRARY.glob("*.toml"))]
        synthetic = [truth_spec(s, n, timed, {"seed": seed}) for s, n, timed in DEFAULT_SYNTHETIC]
    else:
        synthetic = []
    cases = [case_for(s) for s in specs]
    cases += [case_for(s, best_known=0.0, tolerance=lambda best: SYNTHETIC_TOLERANCE,
                       note="synthetic truth: zero error exists") for s in synthetic]
    if inexact:
        cases += inexact_cases(seed)
        cases += literature_cases(seed)
        cases.append(many_targets_case(seed))
    return cases


def inexact_cases(seed: int = 0, names=None) -> list[BenchCase]:
    """The inexact set: targets no four-bar fits exactly (synthesis.kinds.fourbar_path.inexact), 64 starts on
    INEXACT_WORKERS workers; best known = the best objective any recorded run found (inexact.BEST_KNOWN),
    else (not yet recorded) the untimed reference multistart of a library spec."""
    return [case_for(inexact_spec(n, {"seed": seed}), best_known=BEST_KNOWN.get(n),
                     note="inexact target: best known from the cross-check runs and searches "
                          "(inexact.BEST_KNOWN); "
                          f"{DE_EQUAL_BUDGET}: DE given the CPU seconds (every worker's) of the multistart's run",
                     workers=INEXACT_WORKERS, equal_budget=True) for n in (names or NAMES)]


def literature_cases(seed: int = 0, names=None) -> list[BenchCase]:
    """The literature's target sets (synthesis.kinds.fourbar_path.literature), 64 starts on INEXACT_WORKERS workers,
    DE at its default and at equal budget, and a method ``published``: the best published linkage
    (literature.best_published: the lowest objective among the transcribed competitors within the problem's ranges
    and every rule holding) scored with this package's objective and fine-grid re-check. Best known:
    literature.BEST_KNOWN (the lowest any recorded run found); target 1e-6 relative above it (no absolute floor: the
    objectives go down to 1e-7 units^2).
    """
    def published(name: str, spec):
        def run(target: float) -> MethodRun:
            scores = literature.competitor_scores(name)
            score = literature.best_published(name, scores)
            c = score.competitor
            violation = worst_violation(spec, c.design(), score.crank_deg)
            return MethodRun(score.objective, violation, [(0.0, score.objective)],
                             {"return_status": "not run: the published linkage, scored (no time to compare)",
                              "competitor": c.label, "citation": c.citation, "read_from": c.read_from,
                              "timing": score.timing, "published_error": c.published_error,
                              "published_error_read_from": c.error_read_from,
                              "design": c.design(), "crank_deg": score.crank_deg,
                              "all_competitors": {o.competitor.label: {"objective": o.objective,
                                                                       "rules_hold": o.rules_hold,
                                                                       "outside_ranges": o.outside}
                                                  for o in scores}})
        return run

    cases = []
    for name in names or literature.NAMES:
        loaded = literature.literature_spec(name, {"seed": seed})
        case = case_for(loaded, best_known=literature.BEST_KNOWN.get(name),
                        tolerance=lambda best: LIBRARY_RELATIVE_TOLERANCE * abs(best),
                        note="literature target set: best known from the recorded runs (literature.BEST_KNOWN); "
                             "'published' = the best published linkage, scored with this package's objective; "
                             f"{DE_EQUAL_BUDGET}: DE given the CPU seconds (every worker's) of the multistart's run",
                        workers=INEXACT_WORKERS, equal_budget=True)
        case.methods["published"] = published(name, loaded.model)
        case.single_runs = {"published"}
        cases.append(case)
    return cases


# ---------------------------------------------------------------------------- many targets

#: the many-target study: a noisy coupler curve (synthetic.noisy_truth_data: a digitiser's 0.2 mm) of synthetic
#: mechanism MANY_TARGETS_SEED with each of these target counts, timing free and prescribed
MANY_TARGET_COUNTS = (25, 100, 250, 1000)
MANY_TARGETS_SEED = 1
TIMINGS = {"free": False, "prescribed": True}
#: the starts the study solves one at a time on each set: start 0 (the given design), then the screened, pool and
#: hypercube starts of free timing in turn (the hypercube and placed ones of prescribed timing)
STUDY_STARTS = 8
#: the study's columns whose growth with the target count is fitted (slope of log(value) against log(n))
GROWTH_COLUMNS = ("build_cpu_s", "screen_and_starts_cpu_s", "start_cpu_s", "per_iteration_ms", "whole_solve_s",
                  "whole_solve_cpu_s")


def many_targets_data(n: int, timed: bool, seed: int = 0) -> dict:
    """The spec data of the study's set of ``n`` targets (the solver's seed ``seed``, every other setting the
    spec's default: 64 starts)."""
    return noisy_truth_data(MANY_TARGETS_SEED, n, timed, solver={"seed": seed})


def _median_cpu(job: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """(median CPU seconds of this process, every thread's, over ``repeats`` runs of job(), the last run's value)."""
    times, out = [], None
    for _ in range(repeats):
        t0 = time.process_time()
        out = job()
        times.append(time.process_time() - t0)
    return float(np.median(times)), out


def whole_solve(data: dict) -> dict:
    """``agrisynth solve`` of the spec ``data`` on one worker, in a child process (imports, the multistart, the
    report and figures all counted): its wall seconds, its CPU seconds (None where they cannot be read), exit code,
    objective and rms target error."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "spec.toml"
        path.write_text("\n".join(write_toml(FourbarPathSpec, data, documented=False)) + "\n")
        before = None if resource is None else resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "synthesis.program", "solve", str(path), "--workers", "1",
                               "--out", tmp], capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t0
        cpu = None
        if resource is not None and before is not None:
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
        written = Path(tmp) / data["name"] / "result.json"
        result = json.loads(written.read_text()) if written.exists() else {}
    error = (result.get("facts") or {}).get("path_error") or {}
    return {"whole_solve_s": wall, "whole_solve_cpu_s": cpu, "exit_code": proc.returncode,
            "objective_mm2": (result.get("objective") or {}).get("value"), "rms_mm": error.get("rms_mm")}


def many_targets_row(data: dict, repeats: int = 3, whole: bool = True) -> dict:
    """One set's row of the study: CPU seconds (median of ``repeats``) of the screen and the first STUDY_STARTS
    start points (a fresh screen each time), of the NLP's build (its screen already made), then each of those
    starts solved once as the multistart solves it (median seconds and iterations per start, CPU per iteration
    over them all), and with ``whole`` the whole command (:func:`whole_solve`)."""
    loaded = loaded_spec(data)
    spec = cast(FourbarPathSpec, loaded.model)
    seed = spec.solver.seed
    bounds = np.array(spec.bounds_array(), dtype=float)
    rng = np.random.default_rng([seed, len(spec.targets.points)])
    designs = bounds[:, 0] + rng.random((STUDY_STARTS, len(bounds))) * (bounds[:, 1] - bounds[:, 0])

    def screen_and_starts() -> list:
        forget_screened()
        maker = StartMaker(spec, seed)
        return [maker(k, designs[k]) for k in range(STUDY_STARTS)]

    screen_s, _ = _median_cpu(screen_and_starts, repeats)
    build_s, nlp = _median_cpu(lambda: PathNLP(spec, seed, setting=Setting(spec, seed)), repeats)
    seconds, iterations = [], []
    for k in range(STUDY_STARTS):
        t0 = time.process_time()
        out = nlp.solve(k, designs[k])
        seconds.append(time.process_time() - t0)
        iterations.append(out.iterations)
    row = {"timing": "prescribed" if spec.timed else "free", "targets": len(spec.targets.points),
           "build_cpu_s": build_s, "screen_and_starts_cpu_s": screen_s, "start_cpu_s": float(np.median(seconds)),
           "iterations": float(np.median(iterations)), "per_iteration_ms": 1e3 * sum(seconds) / max(sum(iterations), 1)}
    if whole:
        row.update(whole_solve(data))
    return row


def growth_slopes(rows: list[dict]) -> dict:
    """Per column of GROWTH_COLUMNS the least-squares slope of log(value) against log(target count) over ``rows``
    (1: linear growth, 2: quadratic; None where a value is missing or not positive)."""
    n = np.log([r["targets"] for r in rows])
    out: dict[str, float | None] = {}
    for column in GROWTH_COLUMNS:
        values = [r.get(column) for r in rows]
        ok = all(isinstance(v, (int, float)) and v > 0 for v in values) and len(values) > 1
        out[column] = float(np.polyfit(n, np.log(np.asarray(values, dtype=float)), 1)[0]) if ok else None
    return out


def many_targets_rows(counts: tuple[int, ...] = MANY_TARGET_COUNTS, timings: tuple[str, ...] = tuple(TIMINGS),
                      repeats: int = 3, whole: bool = True, seed: int = 0) -> list[dict]:
    """The many-target study: a row per timing and target count (:func:`many_targets_row`), then per timing a row of
    the slopes (:func:`growth_slopes`, ``targets`` "slope").  Times are CPU seconds of this process (the screen's
    threads included) where the name says cpu, so a shared machine's other load changes them little; the whole
    command's wall seconds too."""
    out: list[dict] = []
    for timing in timings:
        rows = [many_targets_row(many_targets_data(n, TIMINGS[timing], seed), repeats, whole) for n in counts]
        out += rows + [{"timing": timing, "targets": "slope", **growth_slopes(rows)}]
    return out


def many_targets_case(seed: int = 0) -> BenchCase:
    """The largest set of the many-target study (MANY_TARGET_COUNTS[-1] targets, free timing) solved with every start
    on INEXACT_WORKERS workers (no best known: its target is the best any run reached), and the study's table."""
    loaded = loaded_spec(many_targets_data(MANY_TARGET_COUNTS[-1], False, seed))
    return BenchCase(problem=loaded.name, kind="fourbar_path",
                     methods={"ipopt_multistart": ipopt_multistart(loaded, INEXACT_WORKERS, stop_at_target=False)},
                     best_known=None, tolerance=lambda best: LIBRARY_RELATIVE_TOLERANCE * abs(best),
                     note="many targets: a coupler curve digitised with 0.2 mm noise; study many_targets: CPU seconds "
                          "of each part against the target count and their growth (slope of log t against log n)",
                     single_runs={"ipopt_multistart"},
                     studies={"many_targets": lambda: many_targets_rows(seed=seed)})
