"""``agrisynth check`` for kind steering_linkage: the given trapezoid over 0 .. the maximum inside lock.

Rules (one function, :func:`rules_of`, on floats or CasADi symbols): the tie rod's transmission angle to
both steering arms at every sampled lock, and the arm length.  Beyond a dead centre (the outer arm and
the tie rod aligned) the trapezoid cannot follow the inner wheel: the transmission rule is then not
evaluated and says at which lock the dead centre lies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

import casadi as ca
import numpy as np
from scipy.optimize import brentq

from synthesis.constraints import Rule
from synthesis.kinds.steering_linkage.rules import arm_length_rule, tie_rod_transmission_rule
from synthesis.core.verdict import FINE
from synthesis.kinds.steering_linkage.kinematics import (ackermann_outer, dead_centre_cosine, inner_tip, kingpins,
                                                     outer_lock, outer_tip, tie_rod_length, transmission_angles)
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.steering_linkage.spec import SteeringSpec

DEG = math.pi / 180.0
#: locks at which the figure draws the linkage (deg; those beyond the maximum lock are left out)
DRAWN_LOCKS = (0.0, 10.0, 20.0, 27.0, 30.0, 40.0)


def lock_grid(max_lock_deg: float, samples: int) -> np.ndarray:
    """samples + 1 inside locks (rad) from 0 to the maximum lock, both included."""
    return np.linspace(0.0, max_lock_deg * DEG, samples + 1)


def rules_of(spec: SteeringSpec, r, mu_deg_samples, missing: str | None = None) -> list[Rule]:
    """Every rule of the spec on a trace (floats or symbols): the arm length r and the transmission angles
    (deg) of both arms at the sampled locks.  Used by check, the NLP and the re-check."""
    req = spec.requirements
    return [tie_rod_transmission_rule(mu_deg_samples, req.min_transmission_angle, req.max_inside_lock, missing),
            arm_length_rule(r, req.arm_length)]


@dataclass(frozen=True)
class Trace:
    """The trapezoid over a grid of inside locks (floats): locks, outside locks, Ackermann locks (deg),
    transmission angles (deg), or the dead centre that stops it."""

    beta_deg: np.ndarray
    alpha_deg: np.ndarray | None
    ackermann_deg: np.ndarray
    mu_outer_deg: np.ndarray | None
    mu_inner_deg: np.ndarray | None
    dead_centre_deg: float | None

    @property
    def error_deg(self) -> np.ndarray | None:
        return None if self.alpha_deg is None else self.alpha_deg - self.ackermann_deg

    @property
    def max_error_deg(self) -> float | None:
        return None if self.alpha_deg is None else float(np.abs(self.alpha_deg - self.ackermann_deg).max())


def dead_centre(spec: SteeringSpec, r: float, gamma: float, upto_deg: float) -> float | None:
    """The first inside lock (deg) in [0, upto] where the trapezoid reaches its dead centre, or None."""
    w = spec.vehicle.kingpin_spacing
    grid = np.linspace(0.0, upto_deg * DEG, 4001)
    kappa = np.asarray(dead_centre_cosine(ca.DM(grid), w, r, gamma), float).ravel()
    bad = np.flatnonzero(np.abs(kappa) >= 1.0)
    if bad.size == 0:
        return None
    k = int(bad[0])
    if k == 0:
        return 0.0
    edge = 1.0 if kappa[k] >= 1.0 else -1.0
    f = lambda b: float(dead_centre_cosine(b, w, r, gamma)) - edge    # noqa: E731
    return math.degrees(brentq(f, grid[k - 1], grid[k], xtol=1e-14))


def trace(spec: SteeringSpec, design: dict[str, float], beta: np.ndarray) -> Trace:
    """The trapezoid ``design`` (arm_length mm, base_angle deg) at the inside locks ``beta`` (rad), floats."""
    v = spec.vehicle
    w, r, gamma = v.kingpin_spacing, design["arm_length"], design["base_angle"] * DEG
    ack = np.degrees(np.asarray(ackermann_outer(ca.DM(beta), w / v.wheelbase), float).ravel())
    dc = dead_centre(spec, r, gamma, math.degrees(beta[-1]))
    if dc is not None:
        return Trace(np.degrees(beta), None, ack, None, None, dc)
    b = ca.DM(beta)
    alpha = outer_lock(b, w, r, gamma)
    mu_o, mu_i = transmission_angles(b, alpha, w, r, gamma)
    as_deg = lambda e: np.degrees(np.asarray(e, float).ravel())      # noqa: E731
    # the signed angles live in (-180, 180]: an arm whose angle to the tie rod grows through 180 deg would jump to
    # -180 and read as the other assembly; followed continuously from lock 0 it reads 180.2, past the line
    along = lambda e: np.unwrap(as_deg(e), period=360.0)             # noqa: E731
    return Trace(np.degrees(beta), as_deg(alpha), ack, along(mu_o), along(mu_i), None)


def dead_centre_why(spec: SteeringSpec, design: dict[str, float], at_deg: float) -> str:
    return (f"the trapezoid passes its dead centre at inside lock {at_deg:.2f} deg, before the maximum lock "
            f"{spec.requirements.max_inside_lock:g} deg (the outer arm and the tie rod align; arm_length "
            f"{design['arm_length']:g} mm, base_angle {design['base_angle']:g} deg, kingpin_spacing "
            f"{spec.vehicle.kingpin_spacing:g} mm)")


def evaluate(spec: SteeringSpec, design: dict[str, float], samples: int) -> tuple[list[Rule], Trace]:
    """The rules of ``design`` on ``samples`` + 1 locks over 0 .. the maximum inside lock, floats."""
    tr = trace(spec, design, lock_grid(spec.requirements.max_inside_lock, samples))
    if tr.dead_centre_deg is not None:
        return rules_of(spec, design["arm_length"], None, dead_centre_why(spec, design, tr.dead_centre_deg)), tr
    return rules_of(spec, design["arm_length"], np.concatenate([tr.mu_outer_deg, tr.mu_inner_deg])), tr


def joints(spec: SteeringSpec, design: dict[str, float], beta_deg: float) -> dict | None:
    """K_L, T_L, T_R, K_R (mm) at inside lock beta (left turn), or None beyond the dead centre."""
    w, r, gamma = spec.vehicle.kingpin_spacing, design["arm_length"], design["base_angle"] * DEG
    b = beta_deg * DEG
    alpha = float(outer_lock(b, w, r, gamma))
    if not math.isfinite(alpha):
        return None
    (klx, kly), (krx, kry) = kingpins(w)
    tl, tr = inner_tip(b, w, r, gamma), outer_tip(alpha, w, r, gamma)
    return {"inside_deg": beta_deg, "outside_deg": math.degrees(alpha),
            "K_L": [klx, kly], "T_L": [float(tl[0]), float(tl[1])], "T_R": [float(tr[0]), float(tr[1])],
            "K_R": [krx, kry]}


def facts(spec: SteeringSpec, design: dict[str, float], tr: Trace, table12: dict | None = None) -> dict:
    """The result's kind facts: the trapezoid, its steering error over the range, the drawn positions, the
    turning radius and (when the spec carries Table 12) the table explained."""
    v, req = spec.vehicle, spec.requirements
    w, r, gamma = v.kingpin_spacing, design["arm_length"], design["base_angle"] * DEG
    out: dict = {
        "source": spec.source,
        "frame": "plan view: origin mid-way between the kingpins, x to the right kingpin, y forward; left turn "
                 "(inner = left wheel), the right turn is its mirror image",
        "vehicle": {"wheelbase_mm": v.wheelbase, "track_mm": v.track, "kingpin_spacing_mm": w},
        "tie_rod_length_mm": float(tie_rod_length(w, r, gamma)),
        "max_inside_lock_deg": req.max_inside_lock,
        "dead_centre_inside_deg": tr.dead_centre_deg,
    }
    if tr.alpha_deg is not None:
        error, mu_outer, mu_inner = tr.error_deg, tr.mu_outer_deg, tr.mu_inner_deg
        assert error is not None and mu_outer is not None and mu_inner is not None, "evaluated with the outside angle"
        k = int(np.argmax(np.abs(error)))
        mu = np.minimum(np.concatenate([mu_outer, mu_inner]), 180.0 - np.concatenate([mu_outer, mu_inner]))
        out.update({
            "max_steering_error_deg": tr.max_error_deg, "max_error_at_inside_deg": float(tr.beta_deg[k]),
            "outside_at_max_lock_deg": float(tr.alpha_deg[-1]),
            "ackermann_at_max_lock_deg": float(tr.ackermann_deg[-1]),
            "min_transmission_angle_deg": float(mu.min()),
            "curve": {"inside_deg": tr.beta_deg.tolist(), "outside_deg": tr.alpha_deg.tolist(),
                      "ackermann_deg": tr.ackermann_deg.tolist(), "error_deg": error.tolist(),
                      "mu_outer_deg": mu_outer.tolist(), "mu_inner_deg": mu_inner.tolist()},
        })
    out["positions"] = [j for j in (joints(spec, design, b) for b in DRAWN_LOCKS if b <= req.max_inside_lock + 1e-9)
                        if j is not None]
    radius = spec.vehicle.wheelbase / math.sin(req.max_inside_lock * DEG)
    out["turning_radius"] = {"definition": f"inner front kingpin path at the maximum inside lock ({req.max_inside_lock:g} "
                                           "deg), R = L / sin(beta_max) (the definition that gives the printed 3.1 m "
                                           "at 27 deg: see STEERING.md)",
                             "inside_lock_deg": req.max_inside_lock, "value_mm": radius}
    if table12:
        out["table12"] = table12
    return out


def run_check(loaded: LoadedSpec) -> Result:
    from synthesis.kinds.steering_linkage.table12 import explain

    spec = cast(SteeringSpec, loaded.model)         # load_spec validated it with this kind's model
    design = spec.design_values()
    rules, tr = evaluate(spec, design, FINE * spec.solver.samples)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra=facts(spec, design, tr, explain(spec)))


def headline(result: Result) -> list[str]:
    """The Ackermann error (largest, where), the outside wheel at full lock against Ackermann's, the smallest
    transmission angle and the turning radius, from result.json facts."""
    facts = result.extra or {}
    if "max_steering_error_deg" not in facts:
        return []
    turning = facts.get("turning_radius")
    radius = turning.get("value_mm") if isinstance(turning, dict) else None
    return [f"Ackermann error max {figure_text(facts.get('max_steering_error_deg'), 'deg')} at inside "
            f"{figure_text(facts.get('max_error_at_inside_deg'), 'deg')}",
            f"at full lock ({figure_text(facts.get('max_inside_lock_deg'), 'deg')} inside): outside "
            f"{figure_text(facts.get('outside_at_max_lock_deg'), 'deg', 4)}, Ackermann "
            f"{figure_text(facts.get('ackermann_at_max_lock_deg'), 'deg', 4)}; turning radius "
            f"{figure_text(radius, 'mm', 4)}",
            f"transmission angle min {figure_text(facts.get('min_transmission_angle_deg'), 'deg')}"]
