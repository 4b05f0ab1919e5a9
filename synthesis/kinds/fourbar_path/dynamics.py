"""The path four-bar's inverse dynamics on the shared four-bar (docs/ARCHITECTURE.md "Dynamics").

The kind's linkage is :mod:`synthesis.dynamics.fourbar`'s with the crank pivot O moved to (x0, y0): frame r1 at
angle theta0, crank r2, coupler r3, rocker r4, the assembly ``[linkage] branch`` (both call
``synthesis.kinematics.fourbar.coupler_joint`` with the same arguments), and the crank angle theta2 measured from
O -> O' as the shared one's.  The coupler carries the arm AP to the traced point P = (rcx, rcy) in its frame
(origin A, x towards B), so a coupler given as a bar is two bars of one section, AB and AP, rigid together, and a
point mass ``at = "tip"`` sits at P.  The crank turns at the spec's ``crank_speed``; the dynamics are over a whole
turn, so a design whose crank cannot make one (grashof = "any" may only rock it) has them not evaluated.

One model on floats (check, the re-check, result.json) and on the NLP's symbols (the limits' rows).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from synthesis.constraints import Rule
from synthesis.dynamics.linkage import FourbarDynamics, dynamics_facts, dynamics_rules
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

#: the joints and links by the kind's names, in synthesis.dynamics.fourbar's order
JOINTS = ("O", "A", "B", "O'")
LINKS = ("crank OA", "coupler AB with the arm AP", "rocker O'B")
TWO_PI = 2.0 * math.pi


def radians_per_second(crank_speed_rpm):
    """The crank speed in rad/s of one in r/min (a number or the tolerance analysis's symbol)."""
    return crank_speed_rpm * TWO_PI / 60.0


def linkage_dynamics(spec: FourbarPathSpec, v: dict, omega) -> FourbarDynamics:
    """The inverse dynamics' inputs of the design ``v`` (r1..theta0, theta0 in deg; numbers or the NLP's symbols) at
    the crank speed ``omega`` (rad/s).  Called only with a [dynamics] table."""
    table = spec.dynamics
    assert table is not None, "the dynamics of a spec without a [dynamics] table"
    r1, r2, r3, r4, rcx, rcy = (v[n] for n in ("r1", "r2", "r3", "r4", "rcx", "rcy"))
    tip = (rcx, rcy)            # the traced point P in the coupler's frame
    bars = {"crank": [((0.0, 0.0), (r2, 0.0))], "coupler": [((0.0, 0.0), (r3, 0.0)), ((0.0, 0.0), tip)],
            "rocker": [((0.0, 0.0), (r4, 0.0))]}
    counterweight = None if table.counterweight is None else table.counterweight.values()
    return FourbarDynamics.of(table, spec.linkage.branch, (r1, r2, r3, r4, v["theta0"] * (math.pi / 180.0)), bars,
                              omega, tips={"coupler": tip}, counterweight=counterweight)


def turn_slacks(r1: float, r2: float, r3: float, r4: float) -> dict[str, float]:
    """The two slacks (mm) whose both being >= 0 is the loop closing at every crank angle, the crank turning fully:
    the longest diagonal |O'A| = r1 + r2 within reach, r3 + r4 - (r1 + r2), and the shortest, |r1 - r2|, not
    inside the coupler and rocker's folded reach, |r1 - r2| - |r3 - r4|."""
    return {"r3 + r4 - r1 - r2": r3 + r4 - r1 - r2, "|r1 - r2| - |r3 - r4|": abs(r1 - r2) - abs(r3 - r4)}


def why_no_turn(v: dict) -> str | None:
    """Why a design (numbers) has no dynamics over a turn, or None when its crank turns fully."""
    slacks = turn_slacks(*(float(v[n]) for n in ("r1", "r2", "r3", "r4")))
    listed = ", ".join(f"{k} {s:.3g} mm" for k, s in slacks.items())
    if not all(math.isfinite(s) for s in slacks.values()):
        return f"the link lengths are not numbers (slacks {listed})"
    if min(slacks.values()) < 0.0:
        return f"the crank cannot make a full turn (slacks {listed}): no turn at constant speed"
    if min(slacks.values()) == 0.0:
        return (f"the linkage is at a change point (slacks {listed}): at its toggle it can go on either way, so a "
                f"turn of it is not defined")
    return None


def path_dynamics_rules(spec: FourbarPathSpec, v: dict, samples: int, crank_speed_rpm=None) -> list[Rule]:
    """The ``[dynamics.limits]`` rules over ``samples`` crank angles of a turn (none without a table or a limit); on
    numbers not evaluated, and why, when the crank cannot turn fully.  ``crank_speed_rpm``: the spec's when None
    (the tolerance analysis passes its symbol)."""
    table = spec.dynamics
    if table is None or not table.has_rules():
        return []
    speed = spec.crank_speed if crank_speed_rpm is None else crank_speed_rpm
    symbolic = any(isinstance(x, (ca.SX, ca.MX)) for x in (*v.values(), speed))
    why = None if symbolic else why_no_turn(v)
    if why is not None:
        return dynamics_rules(None, table.limits, 0, missing=why)
    return dynamics_rules(linkage_dynamics(spec, v, radians_per_second(speed)), table.limits, samples)


def dynamics_facts_of(spec: FourbarPathSpec, design: dict, sign: float) -> dict:
    """``{"dynamics": ...}`` of result.json for a design (numbers) whose crank turns fully, turning
    counter-clockwise (``sign`` +1) or clockwise (-1); else nothing.  The shared keys with the centres of mass in the
    machine frame (the crank pivot at (x0, y0)); ``crank_speed_rpm`` is negative for a clockwise crank, so power =
    torque x omega holds with its sign (the torque and forces at a crank angle are the same either way: the inertia
    forces go with omega^2)."""
    table = spec.dynamics
    if table is None or why_no_turn(design) is not None:
        return {}
    speed = sign * spec.crank_speed
    out = dynamics_facts(linkage_dynamics(spec, design, radians_per_second(speed)), table.samples, JOINTS, LINKS,
                         speed, table)
    pivot = np.array([float(design["x0"]), float(design["y0"])])
    for link in out["links"]:
        link["com_mm"] = (np.asarray(link["com_mm"], float) + pivot).tolist()
    out["crank_turns"] = "counter_clockwise" if sign > 0 else "clockwise"
    return {"dynamics": out}
