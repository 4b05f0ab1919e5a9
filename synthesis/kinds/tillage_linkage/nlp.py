"""The tillage-linkage NLP: a, b, c, theta and the height of C so that the tool tip meets every rule.

Decision variables: the five design variables (fixed ones get lo = hi) and four crank angles, all
exact through structural rows on the AD derivatives of eq 7:

    omega_low, omega_top   y'(omega) = 0, with y(omega_k) >= y(omega_low) and y(omega_k) <= y(omega_top)
                           at every sampled crank angle (so they are the global extremes)
    omega_in, omega_out    y(omega) = ground, y' <= 0 at entry and >= 0 at exit,
                           omega_in < omega_low < omega_out (the in-soil phase around the lowest point)

Depth and lift are then exact; the rearward-motion rule is sampled on soil_samples + 1 crank angles
spread over [omega_in, omega_out] (they move with the design) and backed off to hold between them.

With a ``[dynamics]`` table, its limits are rules on the inverse dynamics at the ``samples`` crank angles of a
turn (backed off like the rearward rule), and ``min_peak_torque`` minimises an epigraph variable t >= |input
torque| at those angles; the soil force is the check's exact one (dynamics.py says why a kink is harmless).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.core.declared import Declared, named
from synthesis.core.kind import Setting
from synthesis.core.problem import (MaxMinMargin, ObjectiveParts, Operating, Problem,
                                    per_rule_backoff)
from synthesis.kinds.tillage_linkage.kinematics import path_function
from synthesis.spec.common import design_box
from synthesis.kinds.tillage_linkage.spec import NAMES, TillageSpec
from synthesis.kinds.tillage_linkage.check import (TWO_PI, crank_rate, dynamics_rules_of, linkage_dynamics, motion,
                                                   params, rules_of)
from synthesis.core.verdict import FINE

DEG = math.pi / 180.0
SAMPLED = ("rearward_in_soil", "peak_input_torque", "peak_shaking_force", "peak_shaking_moment")
#: least crank angle (rad) between the soil entry, the lowest point and the exit
GAP = 0.02
#: rows in mm are divided by this, so that IPOPT sees numbers of order one
MM = 100.0
#: the structural rows a tolerance box holds at their linearised worst case: the entry's and exit's crossing directions
#: (dy <= 0, >= 0) and the order of entry, lowest point and exit (indices into the problem's structural rows)
EXISTENCE_ROWS = (4, 5, 6, 7, 8)


def problem(setting: Setting) -> Declared:
    """The problem of one spec: a start's four crank angles root-found on its own motion (:func:`angles_guess`),
    the crank angles of the returned design in each start's details."""
    spec = setting.spec
    bounds, init = design_box(spec.variables(), NAMES)
    declared = _problem(spec, bounds, setting.operating_symbols)
    shortest = spec.objective.name == "min_bar_length"
    peak = spec.objective.name == "min_peak_torque"

    def start(x0: np.ndarray, elastic: bool) -> tuple[np.ndarray, None]:
        return np.concatenate([x0, angles_guess(spec, {n: float(v) for n, v in zip(NAMES, x0)})]), None

    def crank_deg(out, compiled) -> dict:
        return {"crank_deg": {k: math.degrees(float(v)) for k, v in
                              zip(("lowest", "highest", "soil_entry", "soil_exit"), out.x[5:9])}}

    def reported(out, design: dict, elastic: bool) -> float:
        """The bar length (mm), the design's own peak torque on the check's grid (N m), or the smallest margin."""
        if peak:
            return given_peak_torque(spec, design)
        return design["c"] if shortest else -out.objective

    return Declared(declared, list(NAMES), bounds, init, design=named(list(NAMES)), start=start,
                    objective=reported, details=crank_deg)


def given_peak_torque(spec: TillageSpec, design: dict[str, float], samples: int | None = None) -> float:
    """The peak |input torque| (N m) of a design on ``samples`` crank angles of a turn (default: the check's)."""
    from synthesis.kinds.tillage_linkage.dynamics import peak_torque, turn

    a, b, c, th = params(design)
    n = FINE * spec.solver.samples if samples is None else samples
    return peak_torque(linkage_dynamics(spec, a, b, c, th, design["height_c"]), turn(n))


def _problem(spec: TillageSpec, bounds: np.ndarray, operating_symbols: bool) -> Problem:
    s = spec.solver
    z = ca.SX.sym("z", 9)
    a, b, c, theta_deg, h = (z[i] for i in range(5))
    w_low, w_top, w_in, w_out = z[5], z[6], z[7], z[8]
    p = ca.vertcat(a, b, c, theta_deg * DEG)
    f = path_function()
    ground = -h

    def at(w):
        return f(w, p)

    _, y_low, _, dy_low, _, _ = at(w_low)
    _, y_top, _, dy_top, _, _ = at(w_top)
    _, y_in, _, dy_in, _, _ = at(w_in)
    _, y_out, _, dy_out, _, _ = at(w_out)
    grid = np.linspace(0.0, TWO_PI, s.samples, endpoint=False)
    y_grid = f.map(s.samples)(grid.reshape(1, -1), p)[1].T
    structural = [                                 # EXISTENCE_ROWS index the last five
        (ca.vertcat(dy_low, dy_top) / MM, 0.0, 0.0),
        (ca.vertcat(y_in - ground, y_out - ground) / MM, 0.0, 0.0),
        ((y_grid - y_low) / MM, 0.0, None),
        ((y_top - y_grid) / MM, 0.0, None),
        (dy_in / MM, None, 0.0), (dy_out / MM, 0.0, None),
        (w_low - w_in, GAP, None), (w_out - w_low, GAP, None), (w_out - w_in, None, TWO_PI - GAP),
    ]
    frac = np.linspace(0.0, 1.0, s.soil_samples + 1)
    w_soil = w_in + (w_out - w_in) * ca.DM(frac).T
    dx_soil = f.map(s.soil_samples + 1)(w_soil, p)[2].T
    # the speeds are numbers in a solve; symbols (resolved at their numbers) when the sensitivity analysis asks,
    # so it has every rule's derivative w.r.t. them (they enter only the in-soil velocity, never a structural row)
    operating = ([Operating("crank_speed", ca.SX.sym("crank_speed"), spec.operation.crank_speed, "r/min"),
                  Operating("forward_speed", ca.SX.sym("forward_speed"), spec.operation.forward_speed, "m/s")]
                 if operating_symbols else [])
    rate: ca.SX | float
    forward: ca.SX | float
    if operating:
        rate, forward = operating[0].symbol * TWO_PI / 60.0, operating[1].symbol
    else:
        rate, forward = crank_rate(spec), spec.operation.forward_speed
    vx_soil = rate * dx_soil / 1000.0 + forward
    dynamics = dynamics_rules_of(spec, a, b, c, theta_deg * DEG, h, s.samples, rate, forward)
    rules = rules_of(spec, a, b, c, ground - y_low, y_top - ground, vx_soil, dynamics=dynamics)
    if spec.objective.name == "min_bar_length":
        objective: ObjectiveParts | MaxMinMargin = ObjectiveParts(f=c / MM)
    elif spec.objective.name == "min_peak_torque":
        objective = _peak_objective(spec, a, b, c, theta_deg * DEG, h, rate, forward)
    else:
        objective = MaxMinMargin()
    lbx = np.concatenate([bounds[:, 0], [-TWO_PI] * 4])
    ubx = np.concatenate([bounds[:, 1], [2 * TWO_PI] * 4])
    backoff = s.backoff
    return Problem("tillage_linkage", z, lbx, ubx, structural, rules, objective,
                   backoff=per_rule_backoff(lambda rule: backoff if rule.name in SAMPLED else 1e-7),
                   ipopt="tight", max_iter=s.max_iter,
                   # the shortest-bar optimum is degenerate (b = 2a, height_c at its bound): without any
                   # bound relaxation IPOPT's path from the spec's design is chaotic at the last digit
                   # (the whole start moved by -1e-15 relative ends at 393.27 mm, Error_In_Step_Computation,
                   # instead of 373.06).  Relaxing bounds by 1e-10 (far inside the rules' 1e-7 back-off;
                   # the returned design clipped back into its box by honor_original_bounds) ends the
                   # whole start moved by 0, +-1e-15, +-3e-15 and 1e-14 at 373.0601 mm (Solve_Succeeded,
                   # 478-877 iterations instead of 244), but c alone moved by 1e-15 still ends at
                   # 375.64 mm (max_iter): less sensitive, not insensitive (tests/extreme/test_scale.py)
                   ipopt_options={"ipopt.bound_relax_factor": 1e-10, "ipopt.honor_original_bounds": "yes"},
                   # z: a, b, c (mm), theta (deg), height_c (mm), four crank angles (rad); the rows
                   # in mm divided by the constant MM are still lengths (mm / 100: length power 1),
                   # and so is the objective c / MM -- declared "" once, which left them at mm size
                   # under a length-unit change (tests/extreme/test_scale.py), the angle gaps in rad
                   x_units=["mm", "mm", "mm", "deg", "mm"] + ["rad"] * 4,
                   structural_units=["mm"] * 6 + ["rad"] * 3,
                   objective_unit="N m" if spec.objective.name == "min_peak_torque" else "mm", operating=operating,
                   # in a tolerance box, what makes entry and exit exist -- the crossings' directions and
                   # the order entry < lowest < exit -- is held at its linearised worst case like a rule,
                   # so every design in the box has them (as planting's precision points)
                   robust_structural=EXISTENCE_ROWS)


def _peak_objective(spec: TillageSpec, a, b, c, theta_rad, h, rate, forward) -> ObjectiveParts:
    """Minimise the peak |input torque| over the ``samples`` crank angles of a turn: an epigraph variable t (N m),
    scaled by the given design's peak on the same angles so the objective is about 1 at the start."""
    from synthesis.kinds.tillage_linkage.dynamics import peak_epigraph, turn

    n = spec.solver.samples
    given = given_peak_torque(spec, spec.design_values(), n)
    # a given design that moves no mass against no soil (0) gives no scale: 1 N m then
    typical = given if math.isfinite(given) and given > 0.0 else 1.0
    t, rows = peak_epigraph(linkage_dynamics(spec, a, b, c, theta_rad, h, rate, forward), turn(n))
    return ObjectiveParts(f=t / typical, extra=t, extra_lb=[0.0], extra_ub=[math.inf], extra_init=[typical],
                          rows=rows, extra_units=["N m"], row_units=["N m"] * len(rows))


def angles_guess(spec: TillageSpec, design: dict[str, float]) -> np.ndarray:
    """omega_low, omega_top, omega_in, omega_out of a start: root-found on its own motion; a start whose
    tip never reaches the ground gets an in-soil phase of +-0.8 rad around its lowest point."""
    s = spec.solver
    m = motion(spec, design, s.samples, 2)
    w_low = m.omega_low
    window = next(((w0, w1) for w0, w1 in m.windows
                   if (w_low - w0) % TWO_PI <= (w1 - w0) and w1 - w0 < TWO_PI), None)
    if window is None:
        w_in, w_out = w_low - 0.8, w_low + 0.8
    else:
        w_in = w_low - max(GAP, (w_low - window[0]) % TWO_PI)
        w_out = w_low + max(GAP, (window[1] - w_low) % TWO_PI)
    return np.array([w_low, m.omega_top, w_in, w_out])
