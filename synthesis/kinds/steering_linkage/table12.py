"""Seed 002 Table 12 explained: the kingpin spacing behind the "accurate" column, the row that does not fit
it, the trapezoid behind the "actual" column, and the definition behind the 3.1 m turning radius.

Every fit is a small least-squares NLP solved by the core's one IPOPT call site (exact derivatives);
nothing here is fitted by bending the model: the residual of every row is reported as it comes out.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from synthesis.core.ipopt import CompiledNLP
from synthesis.core.problem import ObjectiveParts, Problem
from synthesis.errors import SolverError
from synthesis.kinds.steering_linkage.kinematics import (ackermann_kingpin_spacing, ackermann_outer, outer_lock,
                                                     turning_radii)

DEG = math.pi / 180.0


@dataclass(frozen=True)
class Row:
    inside: float          # beta, deg
    accurate: float        # alpha ("accurate" outside lock), deg
    actual: float          # alpha0 (actual outside lock), deg
    error: float | None    # printed alpha - alpha0, deg (None: the max-lock row, printed in the text)


def rows_of(published) -> list[Row]:
    """Table 12's four columns plus the maximum-lock row of the text (27 deg -> 21.9 / 22.4 deg)."""
    rows = [Row(b, a, a0, e) for b, a, a0, e in zip(published.inside_lock, published.accurate_outside,
                                                    published.actual_outside, published.error)]
    m = published.max_lock
    rows.append(Row(m.inside, m.accurate, m.actual, None))
    return rows


def _least_squares(name: str, z: ca.SX, residuals: ca.SX, lo: list[float], hi: list[float], init: list[float]):
    """min 1/2 |residuals|^2 over z in [lo, hi], through the core (no rules): (z*, residuals at z*)."""
    problem = Problem(name, z, np.array(lo, float), np.array(hi, float), [], [],
                      ObjectiveParts(f=0.5 * ca.sumsqr(residuals)), ipopt="precise", max_iter=200)
    out = CompiledNLP(problem).solve(0, np.array(init, float))
    if not out.success:
        raise SolverError(f"{name}: the least-squares fit did not converge ({out.return_status})")
    zs = out.x[: z.numel()]
    res = np.asarray(ca.Function("r", [z], [residuals])(zs), float).ravel()
    if not np.all(np.isfinite(res)):
        raise SolverError(f"{name}: the model cannot be evaluated at the fitted point")
    return zs, res


def spacing_interval(row: Row, wheelbase: float, resolution: float) -> tuple[float, float]:
    """The kingpin spacings w for which the Ackermann outside lock at ``row.inside`` rounds to the printed
    ``row.accurate`` (alpha within +-resolution): w decreases as alpha grows."""
    return (ackermann_kingpin_spacing(row.inside, row.accurate + resolution, wheelbase),
            ackermann_kingpin_spacing(row.inside, row.accurate - resolution, wheelbase))


def consistent_rows(intervals: list[tuple[float, float]]) -> list[int]:
    """The largest set of rows whose spacing intervals share a point (the first such set in row order)."""
    n = len(intervals)
    for size in range(n, 0, -1):
        for subset in itertools.combinations(range(n), size):
            if max(intervals[i][0] for i in subset) <= min(intervals[i][1] for i in subset):
                return list(subset)
    return []


def ackermann_fit(rows: list[Row], use: list[int], wheelbase: float) -> tuple[float, np.ndarray]:
    """The kingpin spacing w (mm) minimising sum (alpha_Ackermann(beta_i; w) - alpha_i)^2 (deg^2) over ``use``;
    returns (w, residual alpha_Ackermann - alpha_printed of every row, deg)."""
    w = ca.SX.sym("w")
    beta = np.array([r.inside for r in rows]) * DEG
    alpha = np.array([r.accurate for r in rows])
    model = ackermann_outer(ca.DM(beta), w / wheelbase) / DEG
    residual = model - alpha
    (ws,), _ = _least_squares("kingpin_spacing_fit", w, residual[use], [0.0], [4.0 * wheelbase],
                              [0.5 * wheelbase])
    every = np.asarray(ca.Function("r", [w], [residual])(ws), float).ravel()
    return float(ws), every


def trapezoid_outer_deg(beta_deg, w: float, r: float, gamma_deg: float) -> np.ndarray:
    """The trapezoid's outside lock (deg) at inside locks ``beta_deg`` (floats)."""
    b = np.asarray(beta_deg, float) * DEG
    return np.degrees(np.asarray(outer_lock(ca.DM(b), w, r, gamma_deg * DEG), float).ravel())


def trapezoid_fit(rows: list[Row], w: float, r: float, gamma_bounds=(30.0, 89.9), gamma0: float = 72.0
                  ) -> tuple[float, np.ndarray]:
    """The base angle (deg) of a trapezoid with arm length ``r`` minimising sum (alpha_trap - alpha0_i)^2 over
    every row's actual column; returns (gamma, residual alpha_trap - alpha0 per row, deg)."""
    g = ca.SX.sym("gamma")
    beta = np.array([row.inside for row in rows]) * DEG
    actual = np.array([row.actual for row in rows])
    residual = outer_lock(ca.DM(beta), w, r, g * DEG) / DEG - actual
    (gs,), res = _least_squares("trapezoid_fit", g, residual, [gamma_bounds[0]], [gamma_bounds[1]], [gamma0])
    return float(gs), res


def concavity_gap(rows: list[Row]) -> dict | None:
    """How far the actual column is from any concave alpha0(beta) (a trapezoid's outer lock is concave over
    these locks): the largest drop of a row below the chord of its neighbours (in beta order), and the
    smallest amount by which any concave curve must miss one of the three rows (half that drop)."""
    pts = sorted((r.inside, r.actual) for r in rows)
    worst: dict[str, Any] | None = None
    for (b0, a0), (b1, a1), (b2, a2) in zip(pts, pts[1:], pts[2:]):
        chord = a0 + (b1 - b0) / (b2 - b0) * (a2 - a0)
        drop = chord - a1
        if worst is None or drop > worst["drop_below_chord_deg"]:
            worst = {"rows_inside_deg": [b0, b1, b2], "drop_below_chord_deg": drop,
                     "least_miss_of_a_concave_curve_deg": max(0.0, drop / 2.0)}
    return worst


def turning_radius(published, wheelbase: float, w: float, track: float) -> dict:
    """Every usual definition of the minimum turning radius at the maximum inside lock, and those that round
    to the printed value (3.1 m, printed to 0.1 m)."""
    radii = turning_radii(published.max_lock.inside, wheelbase, w, track)
    printed = published.min_turning_radius
    half = 50.0            # printed to 0.1 m
    matching = [k for k, v in radii.items() if abs(v - printed) <= half]
    return {"inside_lock_deg": published.max_lock.inside, "radii_mm": radii, "printed_mm": printed,
            "definitions_matching_print": matching,
            "named": "inner_front_kingpin",
            "named_formula": "R = L / sin(beta_max): the inner front kingpin's path radius",
            "named_value_mm": wheelbase / math.sin(published.max_lock.inside * DEG)}


def _finite(x) -> float | None:
    """A figure for result.json: None where the trapezoid cannot reach the lock (beyond its dead centre)."""
    x = float(x)
    return x if math.isfinite(x) else None


def explain(spec) -> dict:
    """Table 12 explained (facts of every steering_linkage result whose spec carries the published table)."""
    pub = spec.published
    if pub is None:
        return {}
    v = spec.vehicle
    L = v.wheelbase
    rows = rows_of(pub)
    intervals = [spacing_interval(r, L, pub.resolution) for r in rows]
    use = consistent_rows(intervals)
    inconsistent = [i for i in range(len(rows)) if i not in use]
    w_fit, acc_res = ackermann_fit(rows, use, L)
    lo, hi = max(intervals[i][0] for i in use), min(intervals[i][1] for i in use)
    # the trapezoid behind the actual column, at the spec's kingpin spacing and arm length
    r = spec.design_values()["arm_length"]
    w = v.kingpin_spacing
    try:
        gamma_fit, act_res = trapezoid_fit(rows, w, r)
        fit = {"arm_length_mm": r, "base_angle_deg": gamma_fit, "kingpin_spacing_mm": w,
               "residual_deg": [float(x) for x in act_res], "rms_deg": float(np.sqrt(np.mean(act_res**2))),
               "max_abs_deg": float(np.abs(act_res).max())}
    except SolverError as exc:
        fit = {"arm_length_mm": r, "not_fitted": str(exc)}
    # the arm length is not identified: the fitted rms for other arm lengths
    identification = []
    for rr in (20.0, 50.0, 100.0, 150.0, 200.0, 250.0):
        try:
            g, res = trapezoid_fit(rows, w, rr)
        except SolverError:
            continue
        identification.append({"arm_length_mm": rr, "base_angle_deg": g, "rms_deg": float(np.sqrt(np.mean(res**2))),
                               "max_abs_deg": float(np.abs(res).max())})
    fit["arm_length_identification"] = identification
    ours_acc = np.degrees([float(ackermann_outer(r_.inside * DEG, w / L)) for r_ in rows])
    trap = trapezoid_outer_deg([r_.inside for r_ in rows], w, r, spec.design_values()["base_angle"])
    table: list[dict[str, Any]] = []
    for i, row in enumerate(rows):
        table.append({
            "inside_deg": row.inside, "accurate_printed_deg": row.accurate, "actual_printed_deg": row.actual,
            "error_printed_deg": row.error, "error_of_printed_columns_deg": row.accurate - row.actual,
            "kingpin_spacing_of_row_mm": ackermann_kingpin_spacing(row.inside, row.accurate, L),
            "kingpin_spacing_interval_mm": list(intervals[i]),
            "consistent": i in use,
            "ackermann_at_fit_deg": row.accurate + float(acc_res[i]), "ackermann_residual_deg": float(acc_res[i]),
            "ackermann_at_spec_w_deg": float(ours_acc[i]),
            "trapezoid_deg": _finite(trap[i]), "trapezoid_residual_deg": _finite(trap[i] - row.actual),
            "actual_error_vs_consistent_ackermann_deg": row.actual - float(ours_acc[i]),
            "trapezoid_error_vs_ackermann_deg": _finite(trap[i] - ours_acc[i]),
        })
    return {
        "rows": table,
        "kingpin_spacing": {
            "fit_mm": w_fit, "fit_rows_inside_deg": [rows[i].inside for i in use],
            "common_interval_mm": [lo, hi], "w_over_L": w_fit / L,
            "inconsistent_rows_inside_deg": [rows[i].inside for i in inconsistent],
            "method": "least squares of alpha_Ackermann(beta; w) - alpha_printed (deg) over the rows whose "
                      f"w-intervals (alpha +-{pub.resolution:g} deg) share a point",
        },
        "trapezoid_fit": fit,
        "actual_column_concavity": concavity_gap(rows),
        "turning_radius": turning_radius(pub, L, w, v.track),
        "published_actual_max_error_deg": max(abs(r_.accurate - r_.actual) for r_ in rows),
        "published_actual_max_error_vs_consistent_ackermann_deg":
            max(abs(t["actual_error_vs_consistent_ackermann_deg"]) for t in table),
    }
