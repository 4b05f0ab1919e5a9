"""The guide-tube NLP: free wall angles such that every tube lands at the same time.

Decision variables: the free wall angles (deg) and, for the ``uniform`` objective, the worst
plant-position error tau (mm) over the sampled row spacings (epigraph form); that objective asks
for landing times within rules.max_time_spread at the design row spacing instead of equal ones.  The drop time is the closed form of drop.py on CasADi symbols:
one smooth expression of the angle through near-sticking and decelerating slides, so IPOPT gets
exact derivatives by AD.  Rows are the rules of check.rules_of built on symbols: exactly equal
landing times at the design row spacing, plant-position error over the sampled row spacings,
the seedling's speed squared at every wall end (it must slide off), free fall before the wall.
This is the only module of the kind that calls ``nlpsol``.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
import weakref
from dataclasses import dataclass

import casadi as ca
import numpy as np

from constraints import Rule
from synthesis.errors import SpecError
from synthesis.guide_tube.check import rules_of
from synthesis.guide_tube.drop import DropPhases, Physics, Tube, drop_phases
from synthesis.guide_tube.scene import GuideTubeScene
from synthesis.spec.common import bounds_of, is_free, value_of
from synthesis.spec.guide_tube import GuideTubeSpec


def symbolic_drop(delta_deg, tube: Tube, physics: Physics) -> DropPhases:
    return drop_phases(delta_deg * (math.pi / 180), tube, physics)


@dataclass
class StartOutcome:
    start: int
    design: dict[str, float]       # delta_<tube> -> deg, every tube
    objective: float
    return_status: str
    success: bool
    iterations: int
    wall_s: float
    log: str
    x: np.ndarray


class GuideTubeNLP:
    """Built once (CasADi functions and nlpsol), solved from many starts."""

    def __init__(self, spec: GuideTubeSpec, scene: GuideTubeScene, elastic: bool = False):
        free = [t for t in spec.tubes if is_free(t.angle)]
        if not free:
            raise SpecError("guide_tube.tubes: solve needs at least one free wall angle (angle = {init, bounds}); "
                            "every angle is fixed, so use `agrisynth check`")
        self.spec, self.scene, self.elastic = spec, scene, elastic
        self.names = [t.name for t in free]
        self.tube_names = [t.name for t in spec.tubes]
        n = len(free)
        uniform = spec.objective.name == "uniform"
        delta = ca.SX.sym("delta_deg", n)
        tau = ca.SX.sym("tau_mm") if uniform else ca.SX(0, 1)
        symbols = {t.name: delta[k] for k, t in enumerate(free)}
        angles = {t.name: symbols.get(t.name, value_of(t.angle)) for t in spec.tubes}
        self.grid = scene.spacing_grid(spec.solver.samples)
        self.rules: list[Rule] = rules_of(scene, angles, self.grid, spec.rules, drop=symbolic_drop,
                                          equalise=not uniform)
        design_times = [symbolic_drop(angles[t.name], scene.tube(i, scene.rows.design_spacing), scene.physics)
                        .landing_time for i, t in enumerate(spec.tubes)]

        rows, lbg, ubg = [], [], []
        slack_of_rule: list[tuple[str, ca.SX, float]] = []
        backoff = spec.solver.backoff
        for rule in self.rules:
            sigma = ca.SX.sym(f"slack_{rule.name}") if elastic else None
            if sigma is not None:
                slack_of_rule.append((rule.name, sigma, rule.scale))
            for vector, lo, hi in rule.rows():
                for expr in ca.vertsplit(ca.vec(ca.SX(vector))):
                    self._append(rows, lbg, ubg, expr, lo, hi, sigma, rule.scale, backoff)
        if uniform:                        # -tau <= V (t_i - t_j) <= tau at every sampled row spacing
            for w in self.grid:
                times = [symbolic_drop(angles[t.name], scene.tube(i, w), scene.physics).landing_time
                         for i, t in enumerate(spec.tubes)]
                for i in range(len(times)):
                    for j in range(i + 1, len(times)):
                        diff = scene.forward_mm_per_s * (times[i] - times[j])
                        rows += [tau - diff, tau + diff]
                        lbg += [0.0, 0.0]
                        ubg += [math.inf, math.inf]

        init = np.array([value_of(t.angle) for t in free])
        objective = {
            "nearest": ca.sumsqr(delta - init),
            "fastest": 1000.0 * design_times[0],
            "uniform": tau,
        }[spec.objective.name]
        self._objective_fn = ca.Function("objective", [delta, tau], [objective])
        slacks = ca.vertcat(*[s for _, s, _ in slack_of_rule]) if elastic else ca.SX(0, 1)
        if elastic:   # the conflict measure first; the design objective only breaks ties
            objective = 1e3 * ca.sum1(slacks) + 1e-6 * objective
        x = ca.vertcat(delta, tau, slacks)
        self.n_delta, self.n_tau, self.n_slack = n, tau.numel(), slacks.numel()
        self.slack_names = [name for name, _, _ in slack_of_rule]
        bounds = [bounds_of(t.angle) for t in free]
        self.lbx = np.array([b[0] for b in bounds] + [0.0] * self.n_tau + [0.0] * self.n_slack)
        self.ubx = np.array([b[1] for b in bounds] + [math.inf] * self.n_tau + [math.inf] * self.n_slack)
        self.bounds = np.array(bounds, dtype=float)
        self.init = init
        self.lbg, self.ubg = np.array(lbg), np.array(ubg)
        fd, self._log_path = tempfile.mkstemp(prefix="agrisynth_ipopt_", suffix=".log")
        os.close(fd)
        weakref.finalize(self, _remove, self._log_path)
        opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                "ipopt.output_file": self._log_path, "ipopt.file_print_level": 5,
                "ipopt.max_iter": spec.solver.max_iter, "ipopt.tol": 1e-10, "ipopt.acceptable_tol": 1e-8}
        self.solver = ca.nlpsol("guide_tube", "ipopt", {"x": x, "f": objective, "g": ca.vertcat(*rows)}, opts)
        self._times = ca.Function("design_times", [delta], [ca.vertcat(*design_times)])

    @staticmethod
    def _append(rows: list, lbg: list, ubg: list, expr, lo, hi, sigma, scale: float, backoff: float) -> None:
        """One row lo <= expr <= hi, inequality limits tightened by backoff x scale; with an elastic
        slack sigma (>= 0, in units of the rule's scale) the row is relaxed by sigma x scale."""
        equality = lo is not None and hi is not None and lo == hi
        lo_t = None if lo is None else (lo if equality else lo + backoff * scale)
        hi_t = None if hi is None else (hi if equality else hi - backoff * scale)
        if sigma is None:
            rows.append(expr)
            lbg.append(-math.inf if lo_t is None else lo_t)
            ubg.append(math.inf if hi_t is None else hi_t)
            return
        if lo_t is not None:
            rows.append(expr + sigma * scale)
            lbg.append(lo_t)
            ubg.append(math.inf)
        if hi_t is not None:
            rows.append(expr - sigma * scale)
            lbg.append(-math.inf)
            ubg.append(hi_t)

    def _x0(self, delta0: np.ndarray) -> np.ndarray:
        tau0 = [self._tau_start(delta0)] if self.n_tau else []
        return np.concatenate([delta0, tau0, np.zeros(self.n_slack)])

    def _tau_start(self, delta0: np.ndarray) -> float:
        t = np.array(self._times(delta0)).ravel()
        return float(self.scene.forward_mm_per_s * (t.max() - t.min())) + 1.0

    def design(self, delta: np.ndarray) -> dict[str, float]:
        values = dict(zip(self.names, map(float, delta)))
        return {f"delta_{name}": values.get(name, value_of(t.angle))
                for name, t in zip(self.tube_names, self.spec.tubes)}

    def objective_value(self, x: np.ndarray) -> float:
        delta = x[:self.n_delta]
        tau = x[self.n_delta:self.n_delta + self.n_tau]
        return float(self._objective_fn(delta, tau))

    def slack_values(self, x: np.ndarray) -> dict[str, float]:
        return dict(zip(self.slack_names, map(float, x[self.n_delta + self.n_tau:])))

    def solve(self, index: int, delta0: np.ndarray) -> StartOutcome:
        start = os.path.getsize(self._log_path)
        t0 = time.perf_counter()
        sol = self.solver(x0=self._x0(np.asarray(delta0, dtype=float)), lbx=self.lbx, ubx=self.ubx,
                          lbg=self.lbg, ubg=self.ubg)
        wall = time.perf_counter() - t0
        stats = self.solver.stats()
        with open(self._log_path, "rb") as fh:
            fh.seek(start)
            log = fh.read().decode(errors="replace")
        x = np.array(sol["x"]).ravel()
        return StartOutcome(index, self.design(x[:self.n_delta]), self.objective_value(x),
                            stats["return_status"], bool(stats["success"]), int(stats["iter_count"]), wall, log, x)


def _remove(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
