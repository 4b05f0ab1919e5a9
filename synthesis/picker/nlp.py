"""The picker double-crank NLP: fit the clamp point to the picking arc under the rules of eq 5-7.

Decision variables: the nine linkage variables in spec units (fixed ones get lo = hi).  The crank
angles of the target points are prescribed (evenly over the working swing), so the objective is an
explicit function of the design.  Eq (4), the sum of distances, has a kink wherever a distance is
zero; it is solved as sum sqrt(d^2 + eps^2) (eps from the spec, default 0.01 mm: the smoothed value
exceeds eq 4 by at most n * eps), warm-started from the least-squares fit, which IPOPT solves fast
and reliably; each start keeps whichever of the two designs has the lower exact eq (4).  Reported
objectives are always the exact eq (4) (or sum of squares) of the design.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from constraints.grashof import grashof_double_crank_rule
from constraints.placement import frame_point_rule
from constraints.transmission import acute_transmission_rule
from synthesis.kinematics.picker_linkage import DoubleCrank, clamp_function
from synthesis.picker.check import arc_error, linkage, swing_angles, target_angles, target_points
from synthesis.rule_nlp import ObjectiveParts, RuleNLP, pull_inside
from synthesis.spec.common import bounds_of, value_of
from synthesis.spec.picker import PickerDoubleCrankSpec

NAMES = ("x_a", "y_a", "l1", "l2", "l3", "l4", "l5", "phi3", "phi4")
DEG = math.pi / 180.0
#: starts are moved this far (mm) inside the Grashof double-crank region, so the loop closes at the start
START_MARGIN = 1.0


@dataclass
class StartOutcome:
    start: int
    design: dict[str, float]
    objective: float            # exact eq (4) in mm, or the sum of squares in mm^2
    return_status: str          # of the last stage
    success: bool
    iterations: int             # both stages
    wall_s: float
    log: str


def grashof_slacks(x: np.ndarray) -> np.ndarray:
    """Eq (6) slacks of a design vector (affine in the lengths)."""
    return DoubleCrank(*x[:9]).grashof_slacks()


class PickerNLP:
    """Built once per spec (least-squares stage and, for eq 4, the smoothed stage); reused for every start."""

    def __init__(self, spec: PickerDoubleCrankSpec, elastic: bool = False):
        self.spec = spec
        variables = spec.variables()
        self.bounds = np.array([bounds_of(variables[n]) for n in NAMES], dtype=float)
        self.init = np.array([value_of(variables[n]) for n in NAMES], dtype=float)
        x = ca.SX.sym("x", 9)
        p = ca.vertcat(x[:7], x[7] * DEG, x[8] * DEG)
        f = clamp_function(spec.linkage.branch)
        targets = target_points(spec)
        angles = target_angles(spec) * DEG
        m = f.map(len(angles))(angles.reshape(1, -1), p)[0]              # 2 x n clamp points
        d2 = ca.sum1((m - ca.DM(targets.T)) ** 2)                        # 1 x n squared distances
        samples = swing_angles(spec, spec.solver.samples) * DEG
        mu = ca.vec(f.map(len(samples))(samples.reshape(1, -1), p)[3]) / DEG
        rules = [grashof_double_crank_rule(x[5], x[2], x[3], x[4]),
                 frame_point_rule(x[0], spec.rules.x_a_min),
                 acute_transmission_rule(mu, spec.rules.min_transmission_angle, "at C, over the working swing")]
        common = dict(elastic=elastic, max_iter=spec.solver.max_iter, backoff=spec.solver.backoff,
                      hard_in_elastic=("grashof_double_crank",))
        # the loop must close for the path to exist: Grashof stays hard in the elastic diagnosis
        self.stages = [RuleNLP("picker_lsq", x, self.bounds[:, 0], self.bounds[:, 1], [], rules,
                               ObjectiveParts(f=ca.sum2(d2) / 100.0), **common)]
        if spec.objective.name == "sum_of_distances" and not elastic:
            eps = spec.objective.epsilon
            self.stages.append(RuleNLP("picker_eq4", x, self.bounds[:, 0], self.bounds[:, 1], [], rules,
                                       ObjectiveParts(f=ca.sum2(ca.sqrt(d2 + eps * eps)) / 10.0), **common))

    def exact_objective(self, design: dict[str, float]) -> float:
        err = arc_error(self.spec, linkage(self.spec, design))
        return err["eq4_sum_mm"] if self.spec.objective.name == "sum_of_distances" else err["sum_of_squares_mm2"]

    def prepared_start(self, x0: np.ndarray) -> np.ndarray:
        return pull_inside(np.asarray(x0, float), self.init, grashof_slacks, START_MARGIN)

    def solve(self, start: int, x0: np.ndarray) -> StartOutcome:
        """Least squares, then (eq 4) the smoothed sum of distances from there; the start's answer is
        the stage design with the lower exact objective: the smoothed stage may wander to a worse
        neighbour on this flat landscape, and a least-squares fit is a fine eq (4) design too."""
        x = self.prepared_start(x0)
        iterations, wall, logs = 0, 0.0, []
        candidates = []
        for stage in self.stages:
            out = stage.solve(start, x)
            iterations += out.iterations
            wall += out.wall_s
            logs.append(out.log)
            x = out.x[:9]
            design = {n: float(v) for n, v in zip(NAMES, x)}
            objective = self.exact_objective(design)
            if not math.isfinite(objective):     # the loop breaks somewhere: the re-check rejects it
                objective = math.inf
            candidates.append((objective, len(candidates), design, out))
        objective, _, design, out = min(candidates, key=lambda c: (c[0], -c[1]))
        return StartOutcome(start, design, objective, out.return_status, out.success, iterations, wall,
                            "\n".join(logs))
