"""The path-synthesis NLP in configuration form: regular where the crank is at a dead position.

The crank-angle form (nlp.PathNLP) writes each target's coupler point as a closed function of its crank angle
theta2 (law of cosines, one assembly).  Where the crank cannot turn fully (grashof = "any": a linkage whose crank
only rocks) the best fit often puts a target at a *dead position* of the crank -- coupler and rocker in line,
|O'A| = r3 + r4 or |r3 - r4| -- where that closed form has a square-root singularity: the coupler point moves
as sqrt(theta_dead - theta2), its derivative is unbounded, and IPOPT crawls towards it for hundreds of
iterations or stops with a failed step (dwell_arc15: problems/fourbar_path/INEXACT.md).

Here each target has two angles, the crank's theta2 and the coupler's psi (direction A -> B in the linkage's
frame), and the loop's closure is an equality row, |A + r3 e^{i psi} - O'|^2 = r4^2.  The configuration curve
{closure = 0} is smooth and its gradient does not vanish at a dead position of the crank (there d closure /
d psi = 0 but d closure / d theta2 != 0), so the coupler point A + (rcx + i rcy) e^{i psi} is a smooth function on
a regular constraint set: the dead position is an ordinary point (there the assembly's side may change, so the
motion rule between the targets, |O'A| <= r3 + r4 or >= |r3 - r4|, is what holds the crank at it).  The assembly
(branch) is held by a sign row: B on the spec's side of the line O' -> A, the side the crank-angle form's
``branch`` picks (construction.joint_positions).  Only at a change point (all four
links in line) does the closure's gradient in (theta2, psi) vanish; its gradient in the lengths is then parallel to
the active motion row's (kidney25's, crank at 180 deg: both along (1, 1, -1, -1) in r1..r4, r1 + r2 = r3 + r4), so
neither LICQ nor MFCQ holds there (the multipliers are neither unique nor bounded).  kidney25's best designs
sit so; from where the crank-angle form stopped on seeds 2 and 4 IPOPT converged on them only with a larger barrier
parameter (nlp.POLISH_MU_INIT) than the starts'.

Every rule of the spec is the crank-angle form's (rules.path_rules on the same theta2), so a design and crank
angles returned from here are checked exactly as any other; the coupler point of this form equals the closed
form's wherever the closure and sign rows hold.  PathNLP.solve solves every start of an open target arc in it, and
polishes in it a closed loop's start that the crank-angle form ended otherwise than converged, cut or at max_iter
(a failed step, mostly).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.core.ipopt import CompiledNLP, SolveMethod
from synthesis.core.problem import ObjectiveParts, Problem, Row
from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.kinds.fourbar_path.rule_set import EXTREMES, path_backoff, path_rules
from synthesis.kinds.fourbar_path.kinematics import BRANCHES, VARIABLES
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

#: bounds of the coupler angles psi (rad): as wide as the crank angles'
PSI_RANGE = (-4.0 * math.pi, 6.0 * math.pi)


class ConfigurationNLP:
    """The configuration form of one free-timing spec, in the crank-angle form's nominal units; built once."""

    def __init__(self, spec: FourbarPathSpec, offset: np.ndarray, scale: np.ndarray, fixed: np.ndarray,
                 lbx: np.ndarray, ubx: np.ndarray, f_unit: float, backoff: float, ipopt_options: dict,
                 max_iter: int, method: SolveMethod | None = None):
        targets = np.array(spec.targets.points, dtype=float)
        n = len(targets)
        self.n = n
        self.branch = BRANCHES[spec.branch]
        self.bounds = np.array(spec.bounds_array(), dtype=float)
        x = ca.SX.sym("x", 9)
        v = {name: float(self.bounds[i, 0]) if fixed[i] else offset[i] + scale[i] * x[i]
             for i, name in enumerate(VARIABLES)}
        theta = ca.SX.sym("theta2", n)
        psi = ca.SX.sym("psi", n)
        sign = ca.SX.sym("direction")
        size2 = float(scale[0]) ** 2           # rows in units of the targets' size squared
        turn_c, turn_s = ca.cos(v["theta0"] * math.pi / 180.0), ca.sin(v["theta0"] * math.pi / 180.0)
        res: list[ca.SX] = []
        structural: list[Row] = []
        for i in range(n):
            ax, ay = v["r2"] * ca.cos(theta[i]), v["r2"] * ca.sin(theta[i])
            ux, uy = ca.cos(psi[i]), ca.sin(psi[i])
            bx, by = ax + v["r3"] * ux, ay + v["r3"] * uy
            # the loop closes: |O'B| = r4 (O' = (r1, 0) in the linkage's frame)
            structural.append((((bx - v["r1"]) ** 2 + by ** 2 - v["r4"] ** 2) / size2, 0.0, 0.0))
            # the assembly: joint_positions turns O' -> A by -branch gamma (gamma in [0, pi]) to reach O' -> B, so
            # cross(O'A, O'B) has the sign of -branch (zero at a dead position, where the assembly may change)
            cross = (ax - v["r1"]) * by - ay * (bx - v["r1"])
            structural.append((self.branch * cross / size2, None, 0.0))
            px = ax + v["rcx"] * ux - v["rcy"] * uy
            py = ay + v["rcx"] * uy + v["rcy"] * ux
            gx = v["x0"] + turn_c * px - turn_s * py
            gy = v["y0"] + turn_s * px + turn_c * py
            res += [gx - float(targets[i, 0]), gy - float(targets[i, 1])]
        f = ca.sumsqr(ca.vertcat(*res))
        decision = ca.vertcat(x, theta, psi)
        #: (closure rows, assembly sign rows) of a decision vector (x, theta2, psi), in units of the size squared
        self.rows = ca.Function("rows", [decision], [ca.vertcat(*[r[0] for r in structural[0::2]]),
                                                     ca.vertcat(*[r[0] for r in structural[1::2]])])
        #: the path error (mm^2) of a decision vector (x, theta2, psi)
        self.fit = ca.Function("fit", [decision], [f])
        thetas = [theta[i] for i in range(n)]
        self.lbx = np.concatenate([lbx, np.full(n, PSI_RANGE[0])])
        self.ubx = np.concatenate([ubx, np.full(n, PSI_RANGE[1])])
        problem = Problem(
            "fourbar_path_configuration", decision, self.lbx, self.ubx, structural=structural,
            rules=path_rules(spec, v, thetas, sign, EXTREMES), objective=ObjectiveParts(f / f_unit),
            parameters=sign, backoff=path_backoff(spec, backoff), ipopt="exact_fit", ipopt_options=ipopt_options,
            max_iter=max_iter, x_units=[""] * 9 + ["rad"] * (2 * n), structural_units=[""] * (2 * n),
            objective_unit="")
        self.compiled = CompiledNLP(problem, False, scaling="none", watched=True, method=method)
        self.n_x = 9 + n        # the crank-angle form's decision vector: the design and the crank angles

    def psi_of(self, design: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """The coupler angle at each crank angle by the closed form (the spec's assembly); NaN where it does not
        close."""
        local = {name: float(design[i]) for i, name in enumerate(VARIABLES)}
        local.update(x0=0.0, y0=0.0, theta0=0.0)
        joints = joint_positions(local, np.asarray(theta, dtype=float), self.branch)
        return np.angle(joints["B"] - joints["A"])

    def solve(self, index: int, w: np.ndarray, design: np.ndarray, sign: float, watch=None):
        """IPOPT on the configuration form from the crank-angle form's decision vector ``w`` (design in nominal
        units, crank angles) whose design is ``design`` (spec units); the outcome's x is mapped back to the
        crank-angle form's layout (its multipliers are this form's rows', not that form's: left out)."""
        theta = np.asarray(w[9:9 + self.n], dtype=float)
        psi = self.psi_of(design, theta)
        # each coupler angle within half a turn of the previous one (the crank angles are unwrapped so too)
        psi = np.unwrap(psi)
        out = self.compiled.solve(index, np.concatenate([w[:9 + self.n], psi]), p=sign, watch=watch)
        out.x = out.x[: self.n_x]
        out.lam_g = np.zeros(0)
        return out
