"""The picker double-crank NLP: fit the clamp point to the picking arc under the rules of eq 5-7.

Decision variables: the nine linkage variables in spec units (fixed ones get lo = hi), seen by IPOPT
in Grashof coordinates (l1, l2, l3 replaced by the slacks of eq 6, bounded below by zero), so the loop
closes and the kinematics are defined at every iterate, however far a start lies.  The crank
angles of the target points are prescribed (evenly over the working swing), so the objective is an
explicit function of the design.  Eq (4), the sum of distances sum |r_i| (r_i = M(phi_i) - P_i), has
a kink wherever a distance is zero, and at its optimum some distances *are* zero.  It is solved
exactly, as the epigraph  min sum t_i  s.t.  r_i = t_i u_i, |u_i|^2 <= 1, t_i >= 0  (the pairs (t_i,
r_i) allowed are exactly t_i >= |r_i|; the polar factor u_i keeps the rows' gradients regular at
r_i = 0, where the plain cone t_i^2 >= |r_i|^2 has none and IPOPT stalls).  That stage is
warm-started from the least-squares fit, which IPOPT solves fast and reliably.  A start is
"converged" only if the stage of the spec's objective converged; both stages' statuses are kept.
Reported objectives are always the exact eq (4) (or sum of squares) of the design.  The min-peak objectives
(``min_peak_torque``, ``min_peak_shaking_force``, ``min_peak_shaking_moment``) are a second stage like eq (4)'s, from the least-squares fit: an
epigraph over the working swing's samples (synthesis/kinds/picker/dynamics.py), reported as the design's own peak on
the check's grid, with the arc held by ``[rules] max_arc_error``.  With a ``[key_poses]`` table each free pose adds
its crank angle AB (rad, within the working swing) after the nine coordinates, held where the clamp point comes
nearest its target by a structural row (synthesis/kinds/picker/poses.py); every stage carries them.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from synthesis.kinematics.grashof import GrashofCoordinates
from synthesis.core.coordinates import fixed_as_given
from synthesis.core.declared import compile_problem
from synthesis.core.kind import KindNLP, Setting
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import ObjectiveParts, Problem, scaled_backoff
from synthesis.core.starts import pull_inside
from synthesis.kinds.picker.dynamics import PEAK_UNITS, double_crank_dynamics, peak_epigraph, peak_of, peak_sampled
from synthesis.kinds.picker.kinematics.linkage import DoubleCrank, clamp_function
from synthesis.kinds.picker.poses import free_poses, start_angles, symbolic_poses
from synthesis.kinds.picker.check import (CHECK_SAMPLES, arc_error, linkage, rules_of, swing_angles, target_angles,
                                          target_points)
from synthesis.spec.common import design_box
from synthesis.kinds.picker.spec import PickerDoubleCrankSpec

NAMES = ("x_a", "y_a", "l1", "l2", "l3", "l4", "l5", "phi3", "phi4")
DEG = math.pi / 180.0
#: starts are moved this far (mm) inside the Grashof double-crank region, so the loop closes at the start
START_MARGIN = 1.0


#: design (x_a, y_a, l1, l2, l3, l4, ...) <-> coordinates with l1, l2, l3 replaced by the slacks of
#: eq (6) (frame AD = l4 turns fully relative to the others)
COORDINATES = GrashofCoordinates(l1=2, l2=5, l3=3, l4=4)


def grashof_slacks(x: np.ndarray) -> np.ndarray:
    """Eq (6) slacks of a design vector (affine in the lengths)."""
    return DoubleCrank(*x[:9]).grashof_slacks()


class PickerNLP(KindNLP):
    """Built once per spec (least-squares stage and, for eq 4 or a min-peak objective, its epigraph stage); reused for
    every start."""
    maps_its_starts = True      # a start is moved before it is solved (see its start map)

    def __init__(self, spec: PickerDoubleCrankSpec, elastic: bool = False, setting: Setting | None = None):
        setting = setting or Setting(spec)
        self.spec = spec
        variables = spec.variables()
        self.names = list(NAMES)
        self.bounds, self.init = design_box(variables, NAMES)
        # decision coordinates z: the design with l1, l2, l3 replaced by the three Grashof slacks (>= 0:
        # the loop closes at every crank angle and iterate); x: the design they give
        z = ca.SX.sym("z", 9)
        x = COORDINATES.design(z)
        p = ca.vertcat(x[:7], x[7] * DEG, x[8] * DEG)
        f = clamp_function(spec.linkage.branch)
        targets = target_points(spec)
        angles = target_angles(spec) * DEG
        m = f.map(len(angles))(angles.reshape(1, -1), p)[0]              # 2 x n clamp points
        r = m - ca.DM(targets.T)                                         # 2 x n residuals, mm
        self.residuals = ca.Function("residuals", [z], [r])
        samples = swing_angles(spec, spec.solver.samples) * DEG
        mu = ca.vec(f.map(len(samples))(samples.reshape(1, -1), p)[3]) / DEG
        x_a, l1, l2, l3, l4 = (x[NAMES.index(n)] for n in ("x_a", "l1", "l2", "l3", "l4"))
        # each free key pose's crank angle AB (rad), after the coordinates z: w = (z, angles)
        self.free_poses = free_poses(spec)
        angles_of_poses = ca.SX.sym("phi_pose", len(self.free_poses))
        poses, nearest = symbolic_poses(spec, p, {n: angles_of_poses[i] for i, n in enumerate(self.free_poses)})
        rules = rules_of(spec, x_a, l1, l2, l3, l4, mu, p, r, poses)
        lb, ub = self.bounds[:, 0], self.bounds[:, 1]
        lbw, ubw = COORDINATES.bounds(lb, ub)
        w = z
        if self.free_poses:
            w = ca.vertcat(z, angles_of_poses)
            swing = np.radians([spec.drive.start, spec.drive.start + spec.drive.swing])
            lbw = np.concatenate([lbw, np.full(len(self.free_poses), swing[0])])
            ubw = np.concatenate([ubw, np.full(len(self.free_poses), swing[1])])
        self.n_w = w.numel()
        # Problem's keyword arguments both stages share
        common: dict[str, Any] = dict(
            max_iter=spec.solver.max_iter, backoff=scaled_backoff(spec.solver.backoff), ipopt="tight",
            hard_in_elastic=("grashof_double_crank",),
            # z: x_a, y_a, l2 and the slacks, l5 (mm), phi3, phi4 (deg), the free poses' crank angles (rad); rows:
            # three lengths' bounds, the free poses' nearest-point rows
            x_units=["mm"] * 7 + ["deg"] * 2 + ["rad"] * len(self.free_poses),
            structural_units=["mm"] * 3 + ["mm^2/rad"] * len(self.free_poses))
        # the loop must close for the path to exist: Grashof stays hard in the elastic diagnosis
        shape = (w, lbw, ubw, COORDINATES.length_rows(x, lb, ub) + nearest, rules)
        self.stages = [compile_problem(setting, Problem("picker_lsq", *shape, ObjectiveParts(f=ca.sumsqr(r) / 100.0),
                                                        objective_unit="mm^2", **common),
                                       elastic)]
        self.stage_names = ["least_squares"]
        if spec.objective.name == "sum_of_distances" and not elastic:
            self.stages.append(compile_problem(setting, Problem("picker_eq4", *shape, _sum_of_distances(r),
                                                                objective_unit="mm", **common)))
            self.stage_names.append("sum_of_distances")
        if spec.objective.name in PEAK_UNITS and not elastic:
            objective, self.peak_start = _peak_objective(spec, p, z)
            self.stages.append(compile_problem(setting, Problem(f"picker_{spec.objective.name}", *shape, objective,
                                                                objective_unit=PEAK_UNITS[spec.objective.name],
                                                                **common)))
            self.stage_names.append(spec.objective.name)
        # the elastic diagnosis reads the least-squares stage (the only one in elastic mode)
        self.compiled = self.stages[0]

    def exact_objective(self, design: dict[str, float]) -> float:
        """The spec's objective of a design: eq (4) or the sum of squares (mm, mm^2), or a min-peak objective's peak
        (N m, N) on the check's grid over the working swing."""
        name = self.spec.objective.name
        if name in PEAK_UNITS:
            dc = linkage(self.spec, design)
            assert self.spec.dynamics is not None        # the spec's validator requires it with a min-peak objective
            dyn = double_crank_dynamics(self.spec.dynamics, tuple(float(v) for v in dc.parameters()), dc.branch)
            return peak_of(dyn, name, np.radians(swing_angles(self.spec, CHECK_SAMPLES)))
        err = arc_error(self.spec, linkage(self.spec, design))
        return err["eq4_sum_mm"] if name == "sum_of_distances" else err["sum_of_squares_mm2"]

    def start_coordinates(self, x0: np.ndarray) -> np.ndarray:
        """The coordinates z of a start design, moved into the Grashof region along the way to the given
        design when that one is inside (IPOPT moves any start inside its bounds anyway)."""
        return COORDINATES.coordinates(pull_inside(np.asarray(x0, float), self.init, grashof_slacks, START_MARGIN))

    def start_vector(self, x0: np.ndarray) -> np.ndarray:
        """The decision vector w of a start design: its coordinates z (:meth:`start_coordinates`) and, with free key
        poses, each one's crank angle where that design's clamp point comes nearest its target."""
        z = self.start_coordinates(x0)
        if not self.free_poses:
            return z
        dc = linkage(self.spec, {n: float(v) for n, v in zip(NAMES, COORDINATES.design(z))})
        return np.concatenate([z, start_angles(self.spec, dc)])

    def epigraph_start(self, z: np.ndarray) -> np.ndarray:
        """(t, u) of the eq (4) stage at coordinates z: t_i a little above |r_i|, u_i = r_i / t_i (inside)."""
        r = np.asarray(self.residuals(z), dtype=float)
        t = 1.01 * np.hypot(r[0], r[1]) + 1e-3
        return np.concatenate([t, (r / t).T.ravel()])

    def extra_start(self, stage: str, z: np.ndarray) -> np.ndarray | None:
        """The start of a stage's epigraph variables at coordinates z (None: the least-squares stage has none)."""
        if stage == "sum_of_distances":
            return self.epigraph_start(z)
        if stage in PEAK_UNITS:
            return np.atleast_1d(np.asarray(self.peak_start(z), dtype=float)).ravel()
        return None

    def solve(self, start: int, x0: np.ndarray) -> StartOutcome:
        """Least squares, then (eq 4) the exact sum of distances from there.  The start's design is the
        last stage's unless the least-squares design has the lower exact objective (the last stage may
        stop early on this flat landscape); the start counts as converged only if the last stage did
        and its design is the one kept."""
        w = self.start_vector(x0)
        stages, logs, candidates, raws, pose_angles = [], [], [], [], []
        for k, (name, stage) in enumerate(zip(self.stage_names, self.stages)):
            out = stage.solve(start, w, self.extra_start(name, w[:9]))
            logs.append(f"----- stage {name}\n{out.log}")
            w = out.x[:self.n_w]
            z = w[:9]
            design = fixed_as_given(NAMES, self.bounds, {n: float(v) for n, v in zip(NAMES, COORDINATES.design(z))})
            objective = self.exact_objective(design)
            if not math.isfinite(objective):     # the loop breaks somewhere: the re-check rejects it
                objective = math.inf
            stages.append({"name": name, "return_status": out.return_status, "iterations": out.iterations,
                           "wall_s": out.wall_s, "objective": objective if math.isfinite(objective) else None})
            candidates.append((objective, -k, design, out.success and k == len(self.stages) - 1))
            raws.append(out)
            pose_angles.append(w[9:])
        # the last stage's design unless an earlier one is better by more than rounding
        objective, kept, design, success = min(candidates, key=lambda c: (_rounded(c[0]), c[1]))
        last = stages[-1]
        details: dict[str, Any] = {"stages": stages}
        if self.free_poses:     # the crank angles of the free poses where the kept design's stage left them
            details["key_pose_crank_deg"] = {n: math.degrees(float(a))
                                             for n, a in zip(self.free_poses, pose_angles[-kept])}
        return StartOutcome(start, design, objective, last["return_status"], success,
                            sum(s["iterations"] for s in stages), sum(s["wall_s"] for s in stages), "\n".join(logs),
                            raws[-1], details)


def _peak_objective(spec: PickerDoubleCrankSpec, p, z) -> tuple[ObjectiveParts, ca.Function]:
    """Minimise the peak torque, shaking force or moment over the solver's samples of the working swing (an epigraph
    variable t, scaled by the given design's peak so the objective is about 1 at the start); and t's start at
    coordinates z: 1 % above the peak there, so every epigraph row starts inside."""
    assert spec.dynamics is not None                 # the spec's validator requires it with a min-peak objective
    name = spec.objective.name
    crank = np.radians(swing_angles(spec, spec.solver.samples))
    dc = linkage(spec)
    given = peak_of(double_crank_dynamics(spec.dynamics, tuple(float(v) for v in dc.parameters()), dc.branch), name,
                    crank)
    dyn = double_crank_dynamics(spec.dynamics, [p[i] for i in range(9)], spec.linkage.branch)
    t, rows, unit = peak_epigraph(dyn, name, crank)
    # a given design that moves no mass (0) or whose loop breaks (NaN) gives no scale: 1 in the rule's unit then
    given = given if math.isfinite(given) and given > 0.0 else 1.0
    typical = given * given if name == "min_peak_shaking_force" else given        # t is N^2 for the force
    start = ca.Function("peak_start", [z], [1.01 * ca.mmax(ca.fabs(peak_sampled(dyn, name, crank)))])
    return ObjectiveParts(f=t / typical, extra=t, extra_lb=[0.0], extra_ub=[math.inf], extra_init=[typical],
                          rows=rows, extra_units=[unit], row_units=[unit] * len(rows)), start


def _rounded(objective: float) -> float:
    """The objective to 1e-9 relative: stage designs closer than that count as ties."""
    return float(f"{objective:.9e}") if math.isfinite(objective) else objective


def _sum_of_distances(r) -> ObjectiveParts:
    """Eq (4) exactly: min sum t_i with r_i = t_i u_i, |u_i|^2 <= 1, t_i >= 0 (r: 2 x n residuals)."""
    n = r.shape[1]
    t = ca.SX.sym("t", n)
    u = ca.SX.sym("u", 2, n)
    rows = [(r - u * ca.repmat(t.T, 2, 1), 0.0, 0.0), (ca.sum1(u * u).T, None, 1.0)]
    return ObjectiveParts(f=ca.sum1(t) / 10.0, extra=ca.vertcat(t, ca.vec(u)),
                          extra_lb=[0.0] * n + [-1.0] * (2 * n), extra_ub=[np.inf] * n + [1.0] * (2 * n),
                          extra_init=[1.0] * n + [0.0] * (2 * n), rows=rows,
                          extra_units=["mm"] * n + [""] * (2 * n), row_units=["mm", ""])
