"""The path-synthesis problem of a fourbar_path spec, declared for the solve core.

    minimise   sum_i |P(theta2_i; design) - T_i|^2          (mm^2, the field's standard objective)
    over       r1 r2 r3 r4 rcx rcy x0 y0 theta0  (+ theta2_1..theta2_N when the timing is free)
    subject to the spec's rules (rules.path_rules): Grashof class (3 linear rows), loop closure at the
               targets, transmission angle (2 exact rows over a turn), sequence of the angles (linear,
               free timing); grashof = "any": closure and transmission along the motion between targets,
               exactly (two rows per gap at its extreme crank angles, rules.motion_extremes); with a
               [dynamics] table, its limits over a crank turn at [solver] dynamics_samples angles, held
               synthesis.dynamics.linkage.dynamics_backoff of the limit inside (dynamics.py)

The decision vector is in nominal units (nominal_scales): lengths and the coupler point in units of
the targets' size D, the input pivot from the targets' centre in that unit, theta0 in rad; IPOPT sees
the objective divided by D^0.5 (OBJECTIVE_POWER).  The objective a start reports is the path error in mm^2.
grashof = "any" holds its motion rows exactly (rules.motion_extremes; they replaced coarse samples of the motion
re-solved on the spec's samples: INEXACT.md).
Target sets the screen serves (free timing, >= 12 points) are solved to IPOPT tol SCREEN_TOL.  Free timing: every start is watched
(CompiledNLP(watched=True)) and cut at the iterations of CUTS when its path error is far above the
*reference*, the best screened start's path error (StartMaker.reference: a function of the spec and the
seed, the same in every worker, so the cut is the same for any number of workers).  Continuation: a start not placed on
the targets (a Latin-hypercube design with its curve's nearest crank angles; StartPoint.timing_first) is first fitted
with those crank angles held fixed, then solved with free timing from that fit (TIMING_FIRST).  Why each of
these, and what was tried instead, with the numbers: problems/fourbar_path/INEXACT.md.

P is the closed-form coupler point (kinematics.coupler_point, no inverse cosine).  The crank
direction of the sequence rule is an NLP *parameter* (+1 / -1), so one built solver serves starts
that go either way.  The core transcribes it (back-off, elastic form) and runs IPOPT
(synthesis.core.ipopt, preset "exact_fit"); built once per spec (per worker) and reused for every start.
"""

from __future__ import annotations

import functools
import math

import casadi as ca
import numpy as np

from synthesis.kinds.fourbar_path.rules.sequence import sequence_slacks
from synthesis.core.declared import compile_problem
from synthesis.core.kind import KindNLP, Setting
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import ObjectiveParts, Operating, Problem
from synthesis.kinds.fourbar_path.natural import ConfigurationNLP
from synthesis.kinds.fourbar_path.rule_set import EXTREMES, path_backoff, path_rules
from synthesis.kinds.fourbar_path.starts import StartMaker, StartPoint
from synthesis.kinds.fourbar_path.kinematics import BRANCHES, VARIABLES, coupler_point, design_parameters
from synthesis.spec.common import FreeVariable
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

DEG = 180.0 / math.pi
THETA_RANGE = (-4.0 * math.pi, 6.0 * math.pi)    # bounds of the free crank angles (rad): room for one turn
#: rows are kept this far inside their limits, relative to max(1, |limit|), so the exact re-check
#: (margin >= 0) holds at an active rule despite IPOPT's last-digit residuals
BACKOFF = 1e-9


#: IPOPT's objective is the path error in mm^2 / D^OBJECTIVE_POWER (D the targets' size; INEXACT.md)
OBJECTIVE_POWER = 0.5


#: the core's nominal scaling of variables (core/ipopt.py) is off: this NLP is already in nominal units of the
#: targets' size (its x declares plain numbers, which the core's declared-unit rule leaves alone anyway; an
#: earlier box-width rule read widths like 0.5 D as metres and multiplied them by 1000, and picking_arc's
#: one-start solve then ended at max_iter, violating the transmission angle)
OWN_UNITS = "none"


def nominal_scales(targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(offset, scale) of the nominal units of r1 r2 r3 r4 rcx rcy x0 y0 theta0: lengths in units of
    the targets' size (largest extent), the input pivot from the targets' centre, theta0 in rad."""
    lo, hi = targets.min(axis=0), targets.max(axis=0)
    size = float(np.max(hi - lo))
    size = size if size > 0 else 1.0
    centre = 0.5 * (lo + hi)
    offset = np.array([0, 0, 0, 0, 0, 0, centre[0], centre[1], 0.0])
    scale = np.array([size] * 8 + [180.0 / math.pi])
    return offset, scale


def nominal_affine(spec: FourbarPathSpec, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(d0, J) of the first ``n`` decision entries in nominal units: design = offset + scale * z (read from the
    spec's targets as the NLP reads them, so a tolerance box can be sized before the NLP is built)."""
    offset, scale = nominal_scales(np.array(spec.targets.points, dtype=float))
    d0, s = np.zeros(n), np.ones(n)
    d0[:len(offset)], s[:len(scale)] = offset, scale
    return d0, np.diag(s)


#: IPOPT's initial barrier parameter (its default 0.1 pulls a screened start towards the middle of the box)
MU_INIT = 1e-6
#: the deterministic early cut of free-timing starts: at IPOPT iteration k of each (k, factor) a start
#: whose path error is above factor x the best screened start's (StartMaker.reference, the same in every worker)
#: is stopped (User_Requested_Stop); decided by iterations and objectives only, so the same for any worker count.
#: One cut at iteration 30, 400x: chosen on every start's uncut path-error trace of the ten inexact problems (seed 0)
#: and checked on seed 1 (INEXACT.md).  An earlier schedule ((30, 1e4), (200, 1.0), (400, 0.6)) ran most
#: starts to 200 iterations and there stopped starts that end at the uncut run's best (s_curve12, stroke_lift14 on
#: seed 0, triangle18 on seed 1); 300x instead of 400x stops egg16's best start (396x at iteration 30).  The second
#: cut, at iteration 200 above 1x, came with TIMING_FIRST: the starts fitted at their crank angles first
#: pass the cut at iteration 30 within 400x and ran on to convergence or max_iter; replayed on their uncut traces
#: (seeds 0 and 1) it keeps every best start (0.6x loses 2 of 20), and on six seeds it took 32 % fewer iterations and
#: 21 % less CPU, at the best known of the time on 40 of 60 against 41 without it (triangle18 on seed 2 lost)
CUTS = ((30, 400.0), (200, 1.0))
#: a start that reached max_iter with a path error at most this x the reference is resumed once (PathNLP._resumable;
#: its details say how: "resumed"); 0: never
RESUME_WITHIN = 1.0
#: the resumed run's iterations at most (a start that does not converge in them keeps its max_iter answer)
RESUME_ITERATIONS = 150         # in the crank-angle form (the configuration form's: CONFIGURATION_RESUME_ITERATIONS)
#: grashof = "any", free timing: the configuration form (natural.py, regular at the crank's dead positions) solves
#: every start of an open target arc (whose best linkages often rock the crank to a dead position), and polishes a
#: start of a closed loop that the crank-angle form ended otherwise than converged, cut or at max_iter (within
#: RESUME_WITHIN x the reference; a closed loop needs a full turn, so no dead position, but its best linkages may sit
#: on a change point: kidney25); False: off
CONFIGURATION = True
#: a closed loop's polish in the configuration form stops after this many iterations: from where the crank-angle form
#: stopped, a regular point converges in a few dozen, the rest do not converge at all (with the starts' mu_init, 20 of
#: kidney25's 21 polished starts on seed 0 still ran at 150 iterations).  With POLISH_MU_INIT kidney25's converging
#: polishes take 34-57 iterations (seeds 0, 2, 4), so 60 left ~10 % margin: 100 gave the same best objectives and
#: statuses on seeds 0-5 for the four closed "any" loops (INEXACT.md)
POLISH_ITERATIONS = 100
#: IPOPT's initial barrier parameter of a resume or a polish in the configuration form (its own solver,
#: PathNLP.polisher; None: MU_INIT, the starts' solver).  kidney25's best lies on a change point with a target at the
#: links-in-line position; the crank-angle form ends there with a failed step (seeds 2 and 4: starts 35 and 59), and
#: the polish from that point with the starts' 1e-6 left it (path error 9,029 / 285,587 mm^2 when stopped after 60
#: iterations); with 1e-2 it converges, Solve_Succeeded, in 53 / 48 iterations at the best known.  Six seeds with this
#: and CONFIGURATION_RESUME_ITERATIONS: the same hits, best start Solve_Succeeded on 59 of 60 against 56 (INEXACT.md)
POLISH_MU_INIT: float | None = 1e-2
#: the iterations of a resume in the configuration form from max_iter (None: RESUME_ITERATIONS): stroke_lift14's best
#: start on seed 1 (start 43) converges in 173 more (0.259043 -> 0.258968 mm^2, Solve_Succeeded), not in 150; 400 did
#: not catch seed 5's (a study script's start, rounded differently, converged in 367: a crawl, not a margin to count on)
CONFIGURATION_RESUME_ITERATIONS: int | None = 250
#: continuation: an unplaced start of a screened set (StartPoint.timing_first: the Latin-hypercube starts,
#: a random design with its coupler curve's nearest crank angles) is first fitted at those crank angles held fixed
#: (prescribed timing: the design alone, at most this many iterations), then solved with free timing from that fit.
#: Six seeds of the ten inexact problems: at the best known of the time on 41 of 60 against 31 of 60 without (40
#: with the second cut of CUTS; INEXACT.md); the screened and pool starts, already placed on the
#: targets, lose by it, and the open arcs of the configuration form gain nothing (they skip it: PathNLP.solve); 0: off
TIMING_FIRST = 40
#: the smallest step (deg) of the sequence rule a start's fixed crank angles must leave for its fixed phase to run
SEQUENCE_ROOM = 1e-6
#: IPOPT's tolerances for the free-timing target sets of >= SCREEN_MIN_TARGETS points (None: the preset's 1e-12,
#: below the round-off floor of the gradient of an objective of ~1 mm^2: the best starts then ended at IPOPT's
#: acceptable level; 1e-9: 7 of 10 best starts Solve_Succeeded against 5 -- INEXACT.md)
SCREEN_TOL: tuple[float, float] | None = (1e-9, 1e-7)
#: IPOPT's scaling of those sets: the gradient-based scaling divides f by |grad f(x0)|inf / max_gradient when that is
#: above 1, so a start far from the targets (large residuals, large gradient) had its objective scaled down by up to
#: 10^2-10^3 and its tolerance loosened by as much (egg16's best start stopped 4e-6 above the optimum of its own
#: basin).  max_gradient 1000 (IPOPT's default 100): median iterations 79 -> 40.5 (seed 0), 77.25 -> 57.5 (seed 1),
#: at the best known on 6 / 4 of 10 against 5 / 5 (egg16, s_curve12 gained, square24 lost on seed 0; triangle18 lost
#: on seed 1); 300 and 3000 and no scaling measured too (INEXACT.md)
SCREEN_SCALING: dict | None = {"ipopt.nlp_scaling_max_gradient": 1000.0}
#: IPOPT's pivot tolerance of its linear solver MUMPS for sets of more than SPARSE_PIVOTING_ABOVE targets (IPOPT's
#: default 1e-6 up to it; None: the default for every set).  Where many rows that read the design alone are nearly
#: active -- the continuation's first phase (TIMING_FIRST: the crank angles held, 9 variables under 2n closure rows),
#: a prescribed timing's fit -- their pivots fall below 1e-6 of their column, MUMPS delays each into the front of the
#: design, and that front grows dense with them (IPOPT's log: "MUMPS returned INFO(1) = -9 and requires more memory").
#: The first phase's CPU per iteration (30 Latin-hypercube starts of the 0.2 mm noisy curve, INEXACT.md "Many
#: targets"): 1.4, 3.3, 9.3, 50 ms at 100, 250, 500, 1,000 targets, 59 of the 126 CPU seconds of a 1,000-target
#: solve; at 1e-12 (pivots chosen for sparsity) 10.5 ms at 1,000, no front grown.  IPOPT raises the tolerance
#: itself (towards mumps_pivtolmax) when a step comes out inaccurate.  Every set of at most 100 targets (all the tool
#: took before) keeps the default, and its answers
SPARSE_PIVOT_TOLERANCE: float | None = 1e-12
SPARSE_PIVOTING_ABOVE = 100
#: the configuration form (natural.py) of those sets also perturbs every step's constraint block (IPOPT's
#: perturb_always_cd; by default only where it finds the iteration matrix singular).  Its closure rows are
#: equalities, whose zero diagonal MUMPS must pivot on in pairs: at a start far from the targets (IPOPT's Hessian
#: regularisation climbing to 1e16) it delayed them into one dense front, 5-8 s for the 30 iterations of a start cut
#: at 100 targets, 80-90 s at 500 and 1,000; perturbed, 0.6 s at 1,000.  64 starts on a 120 deg arc: 1,338 -> 164
#: CPU s at 1,000 targets, 200 -> 51 at 250, the best 0.1-0.8 % higher (INEXACT.md, "Many targets")
PERTURBED_CONFIGURATION = True


def operating_speed(spec: FourbarPathSpec, setting: Setting) -> list[Operating]:
    """The tolerance analysis's build only: the crank speed a symbol.  Only the [dynamics.limits] read it (elsewhere
    it only scales the trajectory's time), so without them the analysis reports d rule / d crank speed = 0 rather
    than leaving it out."""
    if not setting.operating_symbols:
        return []
    return [Operating("crank_speed", ca.SX.sym("crank_speed"), spec.crank_speed, "r/min")]


def speed_of(operating: list[Operating]):
    """The crank speed (r/min) the rules read: the tolerance analysis's symbol, else None (the spec's number)."""
    return operating[0].symbol if operating else None


class PathNLP(KindNLP):
    """Built once per spec and seed; :meth:`solve` runs one IPOPT solve from a start design."""

    #: solve(index, x) builds the start of most indices itself (screened shapes, the pool) and ignores x there, so
    #: the core cannot solve it from a given design (core.solve.start_from_elastic skips such an NLP)
    builds_its_own_starts = True

    def __init__(self, spec: FourbarPathSpec, seed: int = 0, elastic: bool = False, setting: Setting | None = None):
        setting = setting or Setting(spec, seed)
        self.spec = spec
        self.names = list(VARIABLES)
        self.bounds = np.array(spec.bounds_array(), dtype=float)
        self.init = np.array([spec.design_values()[n] for n in self.names], dtype=float)
        targets = np.array(spec.targets.points, dtype=float)
        self.offset, self.scale = nominal_scales(targets)
        x = ca.SX.sym("x", len(self.names))          # the design in nominal units: (design - offset) / scale
        # a number in the spec enters as that exact number; a free variable stays a decision entry even with
        # bounds [v, v] (the tolerance analysis frees every dimension so: its rules must depend on it)
        given = spec.variables()
        self.fixed = np.array([not isinstance(given[n], FreeVariable) for n in self.names])
        v = {n: float(self.bounds[i, 0]) if self.fixed[i] else self.offset[i] + self.scale[i] * x[i]
             for i, n in enumerate(self.names)}
        thetas: list[float] | list[ca.SX]
        if spec.targets.crank_deg is not None:          # timed: the targets prescribe every crank angle
            theta = ca.SX(0, 1)
            thetas = [math.radians(a) for a in spec.targets.crank_deg]
        else:
            theta = ca.SX.sym("theta2", len(targets))
            thetas = [theta[i] for i in range(len(targets))]
        self.n_theta = theta.numel()
        sign = ca.SX.sym("direction")
        p = design_parameters(v)
        res = []
        for th, (tx, ty) in zip(thetas, targets):
            px, py = coupler_point(th, p, BRANCHES[spec.branch])
            res += [px - tx, py - ty]
        residuals = ca.vertcat(*res)
        f = ca.sumsqr(residuals)
        decision = ca.vertcat(x, theta)
        f_unit = self.scale[0] ** OBJECTIVE_POWER      # the objective in (target size)^k
        lbx = np.concatenate([self.nominal(self.bounds[:, 0]), np.full(self.n_theta, THETA_RANGE[0])])
        ubx = np.concatenate([self.nominal(self.bounds[:, 1]), np.full(self.n_theta, THETA_RANGE[1])])

        operating = operating_speed(spec, setting)

        def problem(samples: int) -> Problem:
            out = Problem(
                "fourbar_path", decision, lbx, ubx,
                structural=(), rules=path_rules(spec, v, thetas, sign, samples, crank_speed_rpm=speed_of(operating)),
                objective=ObjectiveParts(f / f_unit), parameters=sign, backoff=path_backoff(spec, BACKOFF),
                # tol 1e-12: a zero-error fit must come out below 1e-8 mm^2; the monotone barrier reaches the
                # global optimum from more starts on the whole-turn synthetic-truth study (starts.py);
                # "adaptive" is the spec's choice for targets on a short arc (tests/test_bench_fourbar_path.py)
                ipopt="exact_fit", ipopt_options=self._ipopt_options(spec),
                max_iter=spec.solver.max_iter,
                # x in units of the target size (plain numbers under a change of the length unit), crank angles
                x_units=[""] * 9 + ["rad"] * self.n_theta, objective_unit="", operating=operating)
            return out

        self.f_unit = f_unit
        self.starts = StartMaker(spec, seed, auto_order=setting is not None and setting.auto_order)
        # the early cut and the resume: free timing, not elastic; their reference is the best screened start's path
        # error, screened here, when the NLP is built (the main process builds it first: forked workers inherit it)
        self.referenced = not elastic and self.starts.screening
        self.cut = self.referenced and bool(CUTS)
        self.resumes = self.referenced and bool(RESUME_WITHIN)
        self._reference: list = []
        self.continuation = self.referenced and TIMING_FIRST > 0      # its fixed phase is stopped by a watch
        self.watched = self.cut or self.resumes or self.continuation
        if self.referenced:
            _ = self.reference
        self.lbx, self.ubx = lbx, ubx
        # grashof = "any": the motion's rows exact, each gap at its extremes (EXTREMES); else the spec's samples
        # (read only by the rules of "any": the others are evaluated at the targets and in closed form)
        self.samples = EXTREMES if spec.rules.grashof == "any" else spec.solver.samples
        self.compiled = compile_problem(setting, problem(self.samples), elastic, scaling=OWN_UNITS,
                                        watched=self.watched)
        # the path error of a decision vector: the objective of a normal solve, a fact of an elastic one
        self.fit = ca.Function("fit", [decision, sign], [f])
        self.configuration: ConfigurationNLP | None = None
        self._polisher_settings: tuple | None = None
        if (CONFIGURATION and spec.rules.grashof == "any" and self.starts.screening and not elastic
                and setting.tolerance is None and not setting.operating_symbols):
            self._configuration_form(spec, lbx, ubx, f_unit)

    def _configuration_form(self, spec: FourbarPathSpec, lbx: np.ndarray, ubx: np.ndarray, f_unit: float) -> None:
        """grashof = "any" on a screened free-timing target set: the configuration form too (CONFIGURATION; not in a
        tolerance box or the tolerance analysis, whose sensitivities read this crank-angle form)."""
        options = self._ipopt_options(spec)
        if PERTURBED_CONFIGURATION and len(spec.targets.points) > SPARSE_PIVOTING_ABOVE:
            options["ipopt.perturb_always_cd"] = "yes"
        # solved as the crank-angle form is (its setting's method: a bench's finite differences or peer too)
        form = lambda opts: (spec, self.offset, self.scale, self.fixed, lbx, ubx, f_unit, BACKOFF,  # noqa: E731
                             opts, spec.solver.max_iter, self.compiled.method)
        self.configuration = ConfigurationNLP(*form(options))
        if POLISH_MU_INIT is not None:      # the polisher's arguments now, its build on first use
            self._polisher_settings = form({**options, "ipopt.mu_init": POLISH_MU_INIT})

    @property
    def _open_in_configuration(self) -> bool:
        """Whether every start is solved in the configuration form (an open target arc, grashof = "any")."""
        return self.configuration is not None and not self.starts.closed

    @functools.cached_property
    def polisher(self) -> ConfigurationNLP | None:
        """The configuration form that resumes and polishes: the starts' own (``configuration``) but for IPOPT's
        initial barrier parameter POLISH_MU_INIT; built on first use (once per PathNLP: per worker), from the
        settings captured when this NLP was built."""
        if self._polisher_settings is None:
            return self.configuration
        return ConfigurationNLP(*self._polisher_settings)

    def _ipopt_options(self, spec) -> dict:
        out = {"ipopt.mu_strategy": spec.solver.mu_strategy, **({"ipopt.mu_init": MU_INIT} if MU_INIT else {})}
        if SCREEN_TOL is not None and self.starts.screening:
            out.update({"ipopt.tol": SCREEN_TOL[0], "ipopt.acceptable_tol": SCREEN_TOL[1]})
        if SCREEN_SCALING is not None and self.starts.screening:
            out.update(SCREEN_SCALING)
        if SPARSE_PIVOT_TOLERANCE is not None and len(spec.targets.points) > SPARSE_PIVOTING_ABOVE:
            out["ipopt.mumps_pivtol"] = SPARSE_PIVOT_TOLERANCE
        return out

    @property
    def problem(self) -> Problem:
        return self.compiled.problem

    def nominal(self, design: np.ndarray) -> np.ndarray:
        """Design values (spec units) -> the NLP's nominal units."""
        return (np.asarray(design, float) - self.offset) / self.scale

    def design_of(self, z: np.ndarray) -> np.ndarray:
        """The NLP's nominal units -> design values (spec units); a fixed variable is its bound exactly."""
        return np.where(self.fixed, self.bounds[:, 0], self.offset + self.scale * np.asarray(z, float))

    def answer_start(self, design: dict, x0: np.ndarray, p: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        """With free timing, the crank angle of each target and the crank direction are the answer's (result.json
        ``design.crank_deg``, a start's ``direction``), not the start's guesses: its rules are read there."""
        given, direction = design.get("crank_deg"), design.get("direction")
        crank: list = given if isinstance(given, list) else []
        # a check's crank angles are null where the coupler cannot reach a target: no angles to read then
        numbers = isinstance(given, list) and all(
            isinstance(a, (int, float)) and not isinstance(a, bool) and np.isfinite(a) for a in crank)
        if numbers and len(crank) == x0.size - n:
            x0 = x0.copy()
            x0[n:] = np.radians(np.asarray(crank, float))
        if direction not in ("ccw", "cw") and numbers and len(crank) > 1:   # result.json: no direction
            direction = "ccw" if crank[-1] >= crank[0] else "cw"      # the angles run in the crank's turning sense
        if direction in ("ccw", "cw") and p.size == 1:
            p = np.array([1.0 if direction == "ccw" else -1.0])
        return x0, p

    def start(self, index: int, x_design: np.ndarray) -> StartPoint:
        """The repaired start design and crank angles IPOPT starts from (see starts.py)."""
        return self.starts(index, x_design)

    @property
    def reference(self) -> float | None:
        """The early cut's yardstick: the best screened start's path error (mm^2); None: no cut."""
        if not self._reference:
            self._reference.append(self.starts.reference if self.referenced else None)
        return self._reference[0]

    def watch(self):
        """The early cut of one start (None: no cut): stop at iteration k of CUTS when the path error (mm^2) is
        above its factor x the reference."""
        if not self.watched:
            return None
        factors = dict(CUTS) if self.cut else {}

        def rule(iteration: int, f: float) -> bool:
            mm2 = f * self.f_unit
            if iteration not in factors or self.reference is None:
                return False
            return not mm2 <= factors[iteration] * self.reference
        return rule

    def solve(self, index: int, x_design: np.ndarray) -> StartOutcome:
        """One IPOPT run; the crank angle of each target (deg) and the direction in the start's details."""
        sp = self.start(index, x_design)
        z0 = np.clip(self.nominal(sp.design), self.lbx[:9], self.ubx[:9])
        w0 = np.concatenate([z0, sp.theta])
        watch = self.watch()
        first = None
        # not for an open arc in the configuration form: there it found no more best designs on six seeds and cost
        # 150-420 iterations per start (dwell_arc15, stroke_lift14; INEXACT.md)
        in_configuration = self._open_in_configuration
        if (sp.timing_first and self.continuation and not in_configuration
                and self._sequence_can_hold(sp) and not self.compiled.peer_method):
            w0, first = self._fit_at_start_timing(index, w0, sp.sign)
        resumed = None
        if in_configuration:
            assert self.configuration is not None, "_open_in_configuration holds only where that form was built"
            out = self.configuration.solve(index, w0, self.design_of(w0[:9]), sp.sign, watch=watch)
            if self._resumable(out, sp.sign):
                out, resumed = self._resume(index, out, sp.sign, "configuration")
        else:
            out = self.compiled.solve(index, w0, p=sp.sign, watch=watch)
            if self.configuration is not None and self._polishable(out, sp.sign):
                out, resumed = self._resume(index, out, sp.sign, "configuration")
            elif self._resumable(out, sp.sign):
                out, resumed = self._resume(index, out, sp.sign)
        if first is not None:
            out = self._then(first[0], out, "free timing from the fit at the start's crank angles")
        return self._outcome(out, sp, resumed, first[1] if first is not None else None)

    def _sequence_can_hold(self, sp: StartPoint) -> bool:
        """Whether the start's crank angles, held fixed, leave the sequence rule (the spec's [rules] order) room: a
        random start often gives two neighbouring targets the same nearest curve sample, a step of 0 that no design
        can repair (its fixed phase then ends Infeasible_Problem_Detected); such a start is solved as it is."""
        if not self.spec.rules.order:
            return True
        return min(sequence_slacks(list(np.degrees(sp.theta)), sp.sign)) > SEQUENCE_ROOM

    def _fit_at_start_timing(self, index: int, w0: np.ndarray, sign: float):
        """(decision vector, (outcome, its details) or None) of TIMING_FIRST's first phase: IPOPT on the design with
        the crank angles of ``w0`` held fixed, stopped after TIMING_FIRST iterations; the vector its design and those
        angles (w0 itself, with the details, when that run ended on no number; w0 and None, no run, when an angle is
        outside THETA_RANGE)."""
        lo, hi = self.lbx.copy(), self.ubx.copy()
        theta = w0[9:]
        if np.any(theta < lo[9:]) or np.any(theta > hi[9:]):
            return w0, None
        lo[9:], hi[9:] = theta, theta
        cap = lambda iteration, f: iteration >= TIMING_FIRST      # noqa: E731
        out = self.compiled.solve(index, w0, p=sign, watch=cap, x_bounds=(lo, hi))
        x = out.x[: self.compiled.n_x]
        fit = float(self.fit(x, sign)) if np.all(np.isfinite(x)) else math.inf
        details = {"return_status": out.return_status, "iterations": out.iterations,
                   "path_error_mm2": fit if math.isfinite(fit) else None}
        if not math.isfinite(fit):
            return w0, (out, details)
        return np.concatenate([np.clip(x[:9], self.lbx[:9], self.ubx[:9]), theta]), (out, details)

    def _resumable(self, out, sign: float) -> bool:
        """A start that reached max_iter within RESUME_WITHIN x the reference is run once more from where it stopped, by
        a fresh IPOPT (barrier, filter and Hessian regularisation reset).  Few converge so (seed 0: 2 of 49 resumed
        starts; INEXACT.md), but those are starts that crawled along a flat valley to max_iter, as
        stroke_lift14's best did; so a start may run max_iter + RESUME_ITERATIONS (in the configuration form
        CONFIGURATION_RESUME_ITERATIONS) iterations."""
        return out.return_status == "Maximum_Iterations_Exceeded" and self._near_reference(out, sign)

    def _near_reference(self, out, sign: float) -> bool:
        """Whether a start's answer is a number with a path error within RESUME_WITHIN x the reference (resumes on)."""
        if not self.resumes or self.reference is None:
            return False
        x = out.x[: self.compiled.n_x]
        return bool(np.all(np.isfinite(x))) and float(self.fit(x, sign)) <= RESUME_WITHIN * self.reference

    def _resume(self, index: int, first, sign: float, form: str = "angle"):
        """(outcome, what the resume did) for one more IPOPT run from where ``first`` stopped (in the configuration
        form its coupler angles recomputed by the closed form at that design and those crank angles), itself stopped
        after RESUME_ITERATIONS (in the configuration form CONFIGURATION_RESUME_ITERATIONS; a polish of a start that
        did not reach max_iter: POLISH_ITERATIONS), in the
        crank-angle form or (``form`` "configuration") the configuration form: its answer
        when it converged at a path error no higher than ``first``'s (a fresh run need not stay below its start), else
        ``first``'s; the iterations and time of both counted either way."""
        x1 = first.x[: self.compiled.n_x]
        polish = form == "configuration" and first.return_status != "Maximum_Iterations_Exceeded"
        limit = POLISH_ITERATIONS if polish else RESUME_ITERATIONS
        if form == "configuration" and not polish and CONFIGURATION_RESUME_ITERATIONS is not None:
            limit = CONFIGURATION_RESUME_ITERATIONS
        cap = lambda iteration, f: iteration >= limit      # noqa: E731
        if form == "configuration":
            polisher = self.polisher
            assert polisher is not None, "a resume in the configuration form runs only where that form was built"
            second = polisher.solve(index, x1, self.design_of(x1[:9]), sign, watch=cap)
            what = ("polished in the configuration form" if polish
                    else "resumed in the configuration form from where it reached max_iter")
        else:
            second = self.compiled.solve(index, x1, p=sign, watch=cap)
            what = "resumed from where it reached max_iter"
        x2 = second.x[: self.compiled.n_x]
        before, after = float(self.fit(x1, sign)), float(self.fit(x2, sign))
        converged = second.return_status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
        kept = converged and math.isfinite(after) and after <= before
        resumed = {"return_status": second.return_status, "iterations": second.iterations, "kept": kept,
                   "path_error_mm2": after if math.isfinite(after) else None}
        if form == "configuration":
            resumed["form"] = "configuration"
        if kept:
            return self._then(first, second, what), resumed
        first.iterations += second.iterations
        first.wall_s += second.wall_s
        why = "did not converge" if not converged else f"ended higher, {after:.9g} mm^2 against {before:.9g}"
        first.log += f"\n===== {what}: {second.return_status}, not kept ({why})\n" + second.log
        return first, resumed

    def _polishable(self, out, sign: float) -> bool:
        """grashof = "any", a closed loop: a start the crank-angle form ended otherwise than converged, cut or at
        max_iter (which is resumed in the crank-angle form: _resumable) within RESUME_WITHIN x the reference is solved
        again in the configuration form (kidney25's best start ends with a failed step on a change point in the
        crank-angle form, Solve_Succeeded so)."""
        finished = ("Solve_Succeeded", "User_Requested_Stop", "Maximum_Iterations_Exceeded")
        return out.return_status not in finished and self._near_reference(out, sign)

    @staticmethod
    def _then(first, second, why: str):
        """``second`` (a solve started at ``first``'s answer) counting both solves' iterations, time and log."""
        second.iterations += first.iterations
        second.wall_s += first.wall_s
        second.log = first.log + f"\n===== {why}\n" + second.log
        return second

    def _outcome(self, out, sp: StartPoint, resumed: dict | None = None,
                 timing_first: dict | None = None) -> StartOutcome:
        xs = out.x[: len(self.lbx)]
        design = dict(zip(self.names, (float(a) for a in self.design_of(xs[: len(self.names)]))))
        if self.spec.targets.crank_deg is not None:          # timed: the targets prescribe every crank angle
            crank = [float(a) for a in self.spec.targets.crank_deg]
            direction = "given"
        else:
            crank = [float(a) * DEG for a in xs[len(self.names):]]
            shift = 360.0 * math.floor(crank[0] / 360.0)       # first angle in [0, 360), the rest follow it
            crank = [a - shift for a in crank]
            direction = "ccw" if sp.sign > 0 else "cw"
        objective = float(self.fit(xs, sp.sign))          # mm^2, at the returned point
        objective = objective if math.isfinite(objective) else math.inf
        extra = {}
        if resumed is not None:
            extra["resumed"] = resumed
        if timing_first is not None:
            extra["timing_first"] = timing_first
        return StartOutcome.of(out, design, objective, crank_deg=crank, direction=direction, **extra)
