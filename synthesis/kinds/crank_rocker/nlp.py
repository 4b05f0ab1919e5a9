"""The crank-rocker problem: K, swing and transmission angle as constraints on the simulated mechanism.

Decision variables: the four lengths (fixed ones get lo = hi) and the crank angles phi_a, phi_b of
the rocker's two extreme positions; IPOPT sees the lengths in Grashof coordinates (the crank and the
three Grashof slacks, bounded below by zero), so the crank turns and the kinematics are defined at
every iterate, however far a start lies from a crank-rocker.  Structural rows make them extremes (d beta / d phi = 0, exact
AD); the time-ratio row puts the quick stroke between them (phi_b - phi_a = 2 pi / (1 + K)), the
swing row fixes the angle between the rocker positions, and the transmission angle is sampled over a
turn on a grid that contains the crank along and against the frame, where its extremes are.
"""

from __future__ import annotations

import math
import casadi as ca
import numpy as np

from synthesis.kinematics.grashof import GrashofCoordinates
from synthesis.dynamics.linkage import DYNAMICS_BACKOFF_AT_72, PEAK_OBJECTIVES, peak_backoff, peak_epigraph, peak_of
from synthesis.kinds.crank_rocker.check import check_samples, linkage_dynamics, rules_of
from synthesis.core.declared import Declared
from synthesis.core.kind import Setting
from synthesis.core.problem import DEFAULT_BACKOFF, ObjectiveParts, Problem, scaled_backoff
from synthesis.core.starts import pull_inside
from synthesis.kinematics import fourbar
from synthesis.kinematics.rocker_drive import CrankRocker, quick_return, rocker_function, turn_grid
from synthesis.spec.common import design_box
from synthesis.kinds.crank_rocker.spec import CrankRockerSpec

TWO_PI = 2.0 * math.pi
NAMES = ("l7", "l8", "l9", "l10")
#: starts are moved this far (mm) inside the Grashof crank-rocker region, so the crank turns at the start
START_MARGIN = 1.0


#: design (l7, l8, l9, l10, phi_a, phi_b) <-> coordinates (l7, three Grashof slacks, phi_a, phi_b)
COORDINATES = GrashofCoordinates(l1=3, l2=0, l3=1, l4=2)


def grashof_slacks(lengths: np.ndarray) -> np.ndarray:
    """The three crank-rocker slacks of (l7, l8, l9, l10): affine in the lengths."""
    l7, l8, l9, l10 = lengths
    return np.array(list(fourbar.crank_rotation_slacks(l10, l7, l8, l9).values()), dtype=float)


def problem(setting: Setting) -> Declared:
    """The problem of one spec: a start's lengths moved inside the crank-rocker region, its extremes guessed from
    their simulation; the extremes (phi_a, phi_b, deg) in each start's details."""
    spec = setting.spec
    bounds, init = design_box(spec.variables(), NAMES)
    # decision coordinates z: l7, the three Grashof slacks (>= 0: the crank always turns, so the
    # kinematics are defined at every iterate), phi_a, phi_b; x: the lengths and angles they give
    z = ca.SX.sym("z", 6)
    x = COORDINATES.design(z)
    p, phi_a, phi_b = x[:4], x[4], x[5]
    f = rocker_function(spec.branch)
    _, dbeta_a, _, _, tip_a = f(phi_a, p)
    _, dbeta_b, _, _, tip_b = f(phi_b, p)
    lbx = np.concatenate([bounds[:, 0], [-2 * TWO_PI, -2 * TWO_PI]])
    ubx = np.concatenate([bounds[:, 1], [3 * TWO_PI, 3 * TWO_PI]])
    structural = [(dbeta_a, 0.0, 0.0), (dbeta_b, 0.0, 0.0), *COORDINATES.length_rows(x, lbx, ubx)]
    n = spec.solver.samples_per_turn
    mu = ca.vec(f.map(n)(turn_grid(n).reshape(1, -1), p)[3]) * (180.0 / math.pi)
    a = ca.vertcat(p[3], 0.0)
    # the NLP rows impose K and psi exactly; the records keep the spec's tolerances
    rules = rules_of(spec, [p[i] for i in range(4)], phi_b - phi_a, tip_a - a, tip_b - a, mu)
    total_length = spec.objective.name == "min_total_length"
    peak = PEAK_UNITS.get(spec.objective.name)
    # the crank must turn for the extremes to exist: Grashof stays hard in the elastic diagnosis
    declared = Problem("crank_rocker", z, *COORDINATES.bounds(lbx, ubx), structural, rules, _objective(spec, p, mu),
                       hard_in_elastic=("grashof_crank_rocker",), ipopt="tight",
                       # a sampled peak's limit held inside by its share, so the peak between samples holds too (the
                       # transmission angle's extremes, at 0 and 180 deg, are on the grid: its rows are exact); at
                       # most 2 %: the share grows as (72 / n)^2 and passes the limit itself at 10 samples (the kind
                       # takes 8), where the check's grid tells a peak missed between samples and asks for more
                       backoff=peak_backoff(n, scaled_backoff(DEFAULT_BACKOFF), most=DYNAMICS_BACKOFF_AT_72),
                       # z: l7 and three slacks (mm), the extremes' crank angles (rad); rows: the
                       # extremes' d beta / d phi (a plain number), the three lengths' bounds (mm)
                       x_units=["mm"] * 4 + ["rad"] * 2, structural_units=["", ""] + ["mm"] * 3,
                       objective_unit=peak or ("mm" if total_length else "deg"), max_iter=spec.solver.max_iter)

    def start(lengths: np.ndarray, elastic: bool) -> tuple[np.ndarray, None]:
        lengths = pull_inside(np.asarray(lengths, float), init, grashof_slacks, START_MARGIN)
        return COORDINATES.coordinates(np.concatenate([lengths, extremes_guess(spec, lengths)])), None

    def reported(out, design: dict, elastic: bool) -> float:
        """Total length (mm) of the design itself, the smallest transmission angle (deg) the epigraph
        variable reached, or the peak torque (N m), shaking force (N) or shaking moment (N m) of the design itself on
        the check's grid."""
        if peak:
            return peak_of(linkage_dynamics(spec, [design[n] for n in NAMES]), spec.objective.name, check_samples(spec))
        return sum(design.values()) if total_length else -out.objective * 10.0

    def extremes(out, compiled) -> dict:
        x = COORDINATES.design(out.x[:6])
        return {"extremes_crank_deg": [math.degrees(float(x[4])), math.degrees(float(x[5]))]}

    # the start map pulls a drawn design into the Grashof region: the starts solved are not the uniform draws
    return Declared(declared, list(NAMES), bounds, init, design=_design, start=start, objective=reported,
                    details=extremes, moves_the_design=True)


def _design(z: np.ndarray) -> dict:
    x = COORDINATES.design(z[:6])
    return {n: float(v) for n, v in zip(NAMES, x[:4])}


#: the min-peak objectives and the unit of each
PEAK_UNITS = {name: unit for name, (unit, _) in PEAK_OBJECTIVES.items()}


def _objective(spec, p, mu) -> ObjectiveParts:
    if spec.objective.name == "min_total_length":
        return ObjectiveParts(f=ca.sum1(p) / 100.0)
    if spec.objective.name in PEAK_UNITS:
        return _peak_objective(spec, p)
    t = ca.SX.sym("gamma_min")
    # epigraph: t <= min(mu, 180 - mu) at every sample, maximise t
    rows = [(mu - t, 0.0, None), (180.0 - mu - t, 0.0, None)]
    return ObjectiveParts(f=-t / 10.0, extra=t, extra_lb=[0.0], extra_ub=[90.0],
                          extra_init=[spec.requirements.min_transmission_angle], rows=rows,
                          extra_units=["deg"], row_units=["deg", "deg"])


def _peak_objective(spec, p) -> ObjectiveParts:
    """Minimise the peak torque, shaking force or shaking moment over the solver's samples (an epigraph variable,
    scaled by the given design's peak so the objective is about 1 at the start; the force's epigraph is in N^2)."""
    n = spec.solver.samples_per_turn
    name = spec.objective.name
    given = peak_of(linkage_dynamics(spec, [spec.design_values()[k] for k in NAMES]), name, n)
    t, rows, unit = peak_epigraph(linkage_dynamics(spec, [p[i] for i in range(4)]), name, n)
    # a given design that cannot turn (NaN) or moves no mass (0) gives no scale: 1 in the rule's unit then, so the
    # objective stays finite from every start
    given = float(given) if math.isfinite(float(given)) and float(given) > 0.0 else 1.0
    typical = given * given if name == "min_peak_shaking_force" else given
    return ObjectiveParts(f=t / typical, extra=t, extra_lb=[0.0], extra_ub=[math.inf], extra_init=[typical],
                          rows=rows, extra_units=[unit], row_units=[unit] * len(rows))


def extremes_guess(spec: CrankRockerSpec, lengths: np.ndarray) -> np.ndarray:
    """phi_a, phi_b of a start: its simulated extremes, the quick stroke from a to b."""
    l7, l8, l9, l10 = lengths
    cr = CrankRocker(l7, l8, l9, l10, branch=spec.branch)
    if cr.crank_turns():
        try:
            q = quick_return(cr)
        except ValueError:
            q = None
        if q is not None:
            ex = q.extremes
            if q.stroke_fold_to_ext <= q.stroke_ext_to_fold:
                return np.array([ex.phi_folded, ex.phi_folded + q.stroke_fold_to_ext])
            return np.array([ex.phi_extended, ex.phi_extended + q.stroke_ext_to_fold])
    return np.array([0.0, TWO_PI / (1.0 + spec.requirements.time_ratio)])
