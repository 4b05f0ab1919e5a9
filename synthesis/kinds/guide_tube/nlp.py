"""The guide-tube problem: free wall angles such that every tube lands at the same time.

Decision variables: the free wall angles (deg) and, for the ``uniform`` objective, the worst
plant-position error tau (mm) over the sampled row spacings (epigraph form); that objective asks
for landing times within rules.max_time_spread at the design row spacing instead of equal ones.  The drop time is the closed form of drop.py on CasADi symbols:
one smooth expression of the angle through near-sticking and decelerating slides, so IPOPT gets
exact derivatives by AD.  Rows are the rules of check.rules_of built on symbols: exactly equal
landing times at the design row spacing, plant-position error over the sampled row spacings,
the seedling's speed squared at every wall end (it must slide off), free fall before the wall.
The NLP itself (rows, backoff, elastic slacks, IPOPT and its log) is the core's
:class:`synthesis.core.problem.Problem`, transcribed by the core; this module only declares the kind's variables and objective.
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np

from synthesis.errors import SpecError
from synthesis.kinds.guide_tube.check import rules_of
from synthesis.kinds.guide_tube.drop import DropPhases, Physics, Tube, drop_phases
from synthesis.core.declared import Declared
from synthesis.core.kind import Setting
from synthesis.core.problem import (Envelope, ObjectiveParts, Operating, Problem,
                                    scaled_backoff)
from synthesis.spec.common import bounds_of, is_free, value_of
from synthesis.spec.operating import ranges_of

#: unit of each objective's value: squared change of the free angles, tube 1's landing time, position error
OBJECTIVE_UNITS = {"nearest": "deg^2", "fastest": "ms", "uniform": "mm"}


def symbolic_drop(delta_deg, tube: Tube, physics: Physics) -> DropPhases:
    return drop_phases(delta_deg * (math.pi / 180), tube, physics)


def problem(setting: Setting) -> Declared:
    """The problem of one spec (its scene: ``setting.data``): the free wall angles, the objective's tau started at
    the spread of a start's landing times (the uniform objective), the result design every tube's delta_<tube>."""
    spec, scene = setting.spec, setting.data
    free = [t for t in spec.tubes if is_free(t.angle)]
    if not free:
        raise SpecError("guide_tube.tubes: solve needs at least one free wall angle (angle = {init, bounds}); "
                        "every angle is fixed, so use `agrisynth check`")
    # (every kind's nothing-free error is the core's; this one comes first because a guide-tube NLP
    # has no variables at all when every angle is fixed)
    # mu given as a range (friction.mu = {range, samples}) is a symbol: the core holds every rule reading it
    # once per sampled mu (an envelope).  When the sensitivity analysis asks, mu and the forward speed are symbols
    # resolved at their numbers where not sampled (every rule's derivative w.r.t. both); otherwise, as a solve
    # sees them, numbers (but a mu range)
    ranges = ranges_of(spec)
    wanted = setting.operating_symbols
    symbolic = bool(ranges) or wanted
    nominal_mu, nominal_speed = scene.physics.mu, spec.rows.forward_speed
    mu = ca.SX.sym("mu") if symbolic else nominal_mu
    forward = ca.SX.sym("forward_speed") if wanted else None
    scene = dataclasses.replace(scene, physics=scene.physics.with_(mu=mu), forward_speed=forward)
    operating = ([Operating("mu", mu, nominal_mu, "-")] if symbolic else []) + (
        [Operating("forward_speed", forward, nominal_speed, "m/s")] if forward is not None else [])
    names = [t.name for t in free]
    uniform = spec.objective.name == "uniform"
    delta = ca.SX.sym("delta_deg", len(free))
    symbols = {t.name: delta[k] for k, t in enumerate(free)}
    angles = {t.name: symbols.get(t.name, value_of(t.angle)) for t in spec.tubes}
    grid = scene.spacing_grid(spec.solver.samples)
    rules = rules_of(scene, angles, grid, spec.rules, drop=symbolic_drop, equalise=not uniform)
    design_times = [symbolic_drop(angles[t.name], scene.tube(i, scene.rows.design_spacing), scene.physics)
                    .landing_time for i, t in enumerate(spec.tubes)]
    bounds = np.array([bounds_of(t.angle) for t in free], dtype=float)
    init = np.array([value_of(t.angle) for t in free])
    declared = Problem("guide_tube", delta, bounds[:, 0], bounds[:, 1], [], rules,
                       _objective(spec, scene, grid, init, delta, angles, design_times),
                       max_iter=spec.solver.max_iter, backoff=scaled_backoff(spec.solver.backoff), ipopt="precise",
                       x_units=["deg"] * len(free), objective_unit=OBJECTIVE_UNITS[spec.objective.name],
                       operating=operating,
                       envelope=Envelope({n: r.solver_values() for n, (_, r) in ranges.items()}) if ranges else None)
    times = ca.vertcat(*design_times)
    landing = ca.Function("design_times", [delta], [ca.substitute(times, mu, ca.SX(nominal_mu))
                                                     if symbolic else times])

    def start(delta0: np.ndarray, elastic: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """tau at a start: the spread of the design landing times there, plus 1 mm (strictly feasible)."""
        delta0 = np.asarray(delta0, dtype=float)
        if elastic or not uniform:
            return delta0, None
        t = np.array(landing(delta0)).ravel()
        return delta0, np.array([spec.rows.forward_speed * 1000.0 * (t.max() - t.min()) + 1.0])

    def design(x: np.ndarray) -> dict[str, float]:
        values = dict(zip(names, map(float, x[:len(names)])))
        return {f"delta_{t.name}": values.get(t.name, value_of(t.angle)) for t in spec.tubes}

    # the free angles' keys in a result design: delta_<tube> (core.solve.at_bounds reads a design by them)
    return Declared(declared, names, bounds, init, design=design, start=start,
                    design_names=[f"delta_{name}" for name in names])


def _objective(spec, scene, grid, init, delta, angles: dict, design_times: list) -> ObjectiveParts:
    """nearest: squared change of the free angles (deg^2); fastest: tube 1's landing time (ms);
    uniform: the worst plant-position error tau (mm) over the sampled row spacings (epigraph)."""
    name = spec.objective.name
    if name == "nearest":
        return ObjectiveParts(f=ca.sumsqr(delta - init))
    if name == "fastest":
        return ObjectiveParts(f=1000.0 * design_times[0])
    tau = ca.SX.sym("tau_mm")
    rows = []
    tubes = spec.tubes
    for w in grid:               # -tau <= V (t_i - t_j) <= tau at every sampled row spacing
        times = [symbolic_drop(angles[t.name], scene.tube(i, w), scene.physics).landing_time
                 for i, t in enumerate(tubes)]
        for i in range(len(times)):
            for j in range(i + 1, len(times)):
                diff = scene.forward_mm_per_s * (times[i] - times[j])
                rows += [(tau - diff, 0.0, None), (tau + diff, 0.0, None)]
    return ObjectiveParts(f=tau, extra=tau, extra_lb=[0.0], extra_ub=[math.inf], extra_init=[0.0], rows=rows,
                          extra_units=["mm"], row_units=["mm"] * len(rows))
