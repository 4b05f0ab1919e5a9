"""Inverse dynamics of the combined picker: the crank-rocker AEFG at constant crank speed driving the double crank ABCD
through the rigid body AE + AB about A (synthesis/kinds/picker/combined_dynamics.py).

* An independent formulation of the whole two-loop mechanism: every joint of both loops written afresh in sympy as a
  function of time (the loop closures by the law of cosines, the drive placed as the kind places it and checked
  against the kind's joints), velocities and accelerations by sympy's exact derivatives, and Newton-Euler for the five
  bodies (GF, FE, the rigid body AE + AB, BC with its clamp arm, CD) solved as one 15 x 15 linear system per instant:
  the input torque, every joint force (at A the frame's force on the rigid body), the shaking force and the shaking
  moment about G.  The input torque also by the energy method, d(T + V)/dt over GF's speed.
* The energy balance from result.json alone over each sample interval, and zero net work over a turn.
* Consistency with the parts' own kinds: the torque AE puts on AB is picker_double_crank's input torque when AB turns
  at the speed and acceleration the rocker gives it; with a massless double crank the input torque is crank_rocker's
  own (the drive mirrored and turned into the machine frame as the kind mounts it).
* The rules on CasADi symbols equal those on floats, and their AD derivatives equal central differences.
* The library spec's stated peaks.
"""

from __future__ import annotations

import json
import math
import re

import casadi as ca
import mpmath
import numpy as np
import pytest
import sympy as sp
from conftest import LIBRARY
from dynamics_support import energy_residuals, mechanical_energy

from synthesis import kinds
from synthesis.dynamics.facts import turn
from synthesis.dynamics.fourbar import over_turn
from synthesis.kinds.picker import check as double_crank_check
from synthesis.kinds.picker import combined
from synthesis.kinds.picker.combined_dynamics import (
    JOINTS,
    PARAMETERS,
    PickerDynamics,
    dynamics_rules,
    parameters,
    picker_dynamics,
)
from synthesis.kinds.picker.dynamics import double_crank_dynamics
from synthesis.kinematics.rocker_drive import CrankRocker
from synthesis.result import result_text
from synthesis.spec import load_spec
from synthesis.spec.dynamics import DynamicsLimits, DynamicsSection, PointMass

SPEC = LIBRARY / "picker" / "cai2020_picker_dynamics.toml"
DENSITY, AREA = 7850.0, 120.0          # kg/m^3, mm^2: the library spec's steel bars
CLAMP, HUB = 0.12, 0.05                 # kg: a clamp at M, a mass on AE at (60, 15) mm in its link frame


def loaded_picker(**installation):
    """The library spec (with the installation changed as given) and its drive, as the kind's check builds it."""
    loaded = load_spec(SPEC)
    spec = loaded.model
    if installation:
        spec = spec.model_copy(update={"installation": spec.installation.model_copy(update=installation)})
    cr_spec = load_spec(spec.part_path(loaded.path, "crank_rocker")).model
    dc_spec = load_spec(spec.part_path(loaded.path, "double_crank")).model
    v = cr_spec.design_values()
    cr = CrankRocker(v["l7"], v["l8"], v["l9"], v["l10"], cr_spec.branch)
    drive = combined.make_drive(spec, cr, double_crank_check.linkage(dc_spec), dc_spec.drive.start)
    return loaded, spec, drive


def loaded_table(spec, gravity=(0.3, -9.81)):
    """The spec's [dynamics] table with a clamp at M, a mass off the line of AE, and gravity with an x part, so every
    term counts."""
    table = spec.dynamics
    drive_part = table.crank_rocker.model_copy(update={"point_masses": [
        PointMass(link="rocker", mass=HUB, at=(60.0, 15.0))]})
    dc_part = table.double_crank.model_copy(update={"point_masses": [PointMass(link="coupler", mass=CLAMP, at="tip")]})
    return type(table).model_validate({**table.model_dump(), "crank_rocker": drive_part.model_dump(),
                                       "double_crank": dc_part.model_dump(), "gravity": gravity})


# ----- the independent formulation ---------------------------------------------------------------------------------

def e(angle):
    return sp.Matrix([sp.cos(angle), sp.sin(angle)])


def cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def third_joint(p, q, lp, lq, side):
    """The point at lp from p and lq from q, on the side ``side`` (+-1) of p -> q (law of cosines)."""
    d = q - p
    dist = sp.sqrt(d[0] ** 2 + d[1] ** 2)
    gamma = sp.acos((lp ** 2 + dist ** 2 - lq ** 2) / (2 * lp * dist))
    return p + lp * e(sp.atan2(d[1], d[0]) + side * gamma)


def mechanism(drive, sides):
    """Every joint of both loops in the machine frame (m) as sympy expressions of the time t: the drive built in its
    own frame (G origin, A on +x), mirrored when mounted so and turned so that A -> G points along theta2, A put on
    the double crank's pivot; AB turned from its picking angle by what AE turns."""
    t = sp.Symbol("t")
    cr, dc = drive.cr, drive.dc
    mm = sp.Rational(1, 1000)
    l7, l8, l9, l10 = (sp.Float(v) * mm for v in (cr.l7, cr.l8, cr.l9, cr.l10))
    phi7 = drive.phi_pick + drive.sense * drive.omega * t
    a_own = sp.Matrix([l10, 0])
    f_own = l7 * e(phi7)
    e_own = third_joint(f_own, a_own, l8, l9, sides[0])
    beta = sp.atan2(e_own[1] - a_own[1], e_own[0] - a_own[0])
    a = sp.Matrix([dc.x_a, dc.y_a]) * mm
    rot = drive.theta2 - math.pi
    turn_ = sp.Matrix([[math.cos(rot), -math.sin(rot)], [math.sin(rot), math.cos(rot)]])
    mirror = sp.diag(1, drive.mount)

    def placed(p):
        return a + turn_ * mirror * (p - a_own)

    phi1 = drive.phi10 + drive.mount * (beta - drive.beta_pick)
    phi3, phi4 = math.radians(dc.phi3), math.radians(dc.phi4)
    b = a + sp.Float(dc.l1) * mm * e(phi1 - phi3)
    d = a + sp.Float(dc.l4) * mm * e(-phi3)
    c = third_joint(b, d, sp.Float(dc.l2) * mm, sp.Float(dc.l3) * mm, sides[1])
    m = c + sp.Float(dc.l5) * mm * e(sp.atan2(c[1] - b[1], c[0] - b[0]) + phi4)
    return t, {"G": placed(sp.Matrix([0, 0])), "F": placed(f_own), "E": placed(e_own), "A": a, "B": b, "C": c,
               "D": d, "M": m}


def bodies(j):
    """The five bodies, each a list of parts (mass kg, centre m, inertia kg m^2 about it, angle rad): steel bars, the
    point mass on AE at (60, 15) mm of its frame, the clamp at M."""
    def bar(p, q):
        d = q - p
        length = sp.sqrt(d[0] ** 2 + d[1] ** 2)
        mass = DENSITY * AREA * 1e-6 * length
        return mass, (p + q) / 2, mass * length ** 2 / 12, sp.atan2(d[1], d[0])

    ae = bar(j["A"], j["E"])
    u = (j["E"] - j["A"]) / sp.sqrt((j["E"] - j["A"]).dot(j["E"] - j["A"]))
    hub = (HUB, j["A"] + 0.060 * u + 0.015 * sp.Matrix([-u[1], u[0]]), 0, ae[3])
    bc = bar(j["B"], j["C"])
    return {"GF": [bar(j["G"], j["F"])], "FE": [bar(j["F"], j["E"])], "AEB": [ae, hub, bar(j["A"], j["B"])],
            "BC": [bc, bar(j["C"], j["M"]), (CLAMP, j["M"], 0, bc[3])], "CD": [bar(j["D"], j["C"])]}


#: each body's joint forces: (joint, sign): +1 the force the joint's reaction names acts on this body, -1 its opposite
LOADS = {"GF": [("G", 1), ("F", -1)], "FE": [("F", 1), ("E", -1)], "AEB": [("E", 1), ("A", 1), ("B", -1)],
         "BC": [("B", 1), ("C", -1)], "CD": [("C", 1), ("D", 1)]}


def derivatives(f, time, angles):
    """The values of f (sympy's expressions of t, lambdified for mpmath), their first and second time derivatives at ``time`` (3 x n floats): central differences
    at 50 digits with a step of 1e-10 s (truncation 1e-20, rounding 1e-30 of the values: far below double precision),
    of sympy's expressions evaluated by mpmath; ``angles`` flags the angles, whose differences are taken modulo a turn.
    (sympy's own second derivatives of both loops run to 10^5 operations an expression.)"""
    with mpmath.workdps(50):
        h, at = mpmath.mpf("1e-10"), mpmath.mpf(time)
        low, mid, high = (np.array(f(at + k * h), dtype=object) for k in (-1, 0, 1))
        turns = np.array([2 * mpmath.pi if a else 0 for a in angles], dtype=object)

        def wrapped(d):
            return np.array([x - w * mpmath.nint(x / w) if w else x for x, w in zip(d, turns)], dtype=object)

        first = wrapped(high - low) / (2 * h)
        second = (wrapped(high - mid) - wrapped(mid - low)) / h ** 2
        return np.array([[float(x) for x in row] for row in (mid, first, second)])


def newton_euler(drive, sides, instants, gravity):
    """(torque (N,), reactions (2, 7, N), shaking force (2, N), shaking moment about G (N,), torque by the energy
    method (N,)) at the given instants (s), from the sympy formulation: per body, the force balance and the moment
    balance about the origin, the joint forces and the motor's torque on GF unknown."""
    t, j = mechanism(drive, sides)
    parts = bodies(j)
    g = np.asarray(gravity, float)
    constant = [(name, float(sp.sympify(m).subs(t, 0)), float(sp.sympify(i).subs(t, 0)))
                for name, body in parts.items() for m, _, i, _ in body]
    scalars = [x for body in parts.values() for _, c, _, a in body for x in (c[0], c[1], a)]
    joints = sp.lambdify(t, [j[n] for n in JOINTS], "numpy")
    coordinates = sp.lambdify(t, scalars, "mpmath", cse=True)
    out = []
    for time in instants:
        at = {n: np.asarray(p, float).ravel() for n, p in zip(JOINTS, joints(time))}
        motion = derivatives(coordinates, time, [k % 3 == 2 for k in range(len(scalars))])
        lhs, rhs, power = np.zeros((15, 15)), np.zeros(15), 0.0
        for k, name in enumerate(parts):
            row = 3 * k
            for joint, sign in LOADS[name]:
                col = 2 * JOINTS.index(joint)
                lhs[row:row + 2, col:col + 2] += sign * np.eye(2)
                lhs[row + 2, col:col + 2] += sign * np.array([-at[joint][1], at[joint][0]])   # r x F
            if name == "GF":
                lhs[row + 2, 14] = 1.0
        for p, (name, mass, inertia) in enumerate(constant):
            row = 3 * list(parts).index(name)
            (cx, cy, _), (vx, vy, spin), (ax, ay, angular_acc) = motion[:, 3 * p:3 * p + 3]
            need = mass * (np.array([ax, ay]) - g)
            rhs[row:row + 2] += need
            rhs[row + 2] += inertia * angular_acc + cx * need[1] - cy * need[0]
            # d(T + V)/dt of this part: m v . (a - g) + I w w'
            power += mass * (vx * (ax - g[0]) + vy * (ay - g[1])) + inertia * spin * angular_acc
        x = np.linalg.solve(lhs, rhs)
        reactions = x[:14].reshape(7, 2).T
        frame = reactions[:, [0, 3, 6]]
        moment = -sum(cross(at[n] - at["G"], frame[:, i]) for i, n in enumerate(("G", "A", "D"))) - x[14]
        out.append((x[14], reactions, -frame.sum(1), moment, power / (drive.mount * drive.sense * drive.omega)))
    return (np.array([o[0] for o in out]), np.stack([o[1] for o in out], -1), np.stack([o[2] for o in out], -1),
            np.array([o[3] for o in out]), np.array([o[4] for o in out]))


def assembly_sides(drive):
    """The sides (+-1) of the drive's and the double crank's third joints that are the kind's assembly: the ones whose
    joints match the kind's own (combined.machine_joints) at a few instants, to 1e-9 mm."""
    for sides in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
        t, j = mechanism(drive, sides)
        f = sp.lambdify(t, [j[n] for n in ("G", "F", "E", "A", "B", "C", "D", "M")], "numpy")
        ok = True
        for time in (0.0, 0.13, 0.47, 0.81):
            s = combined.states(drive, [time])
            kind = combined.machine_joints(drive, float(s["phi1"][0]), float(s["phi7"][0]))
            ours = [np.asarray(p, float).ravel() * 1000 for p in f(time)]
            ok &= all(np.allclose(ours[k], kind[n], rtol=0, atol=1e-9) for k, n in enumerate("GFEABCDM"))
        if ok:
            return sides
    raise AssertionError("no assembly of the sympy mechanism matches the kind's joints")


@pytest.mark.slow         # about 1.5 s each: sympy's expressions of both loops differentiated at 50 digits
@pytest.mark.parametrize("installation", [{}, {"picking_extreme": "extended"}])
def test_the_combined_dynamics_equals_an_independent_two_loop_formulation(installation):
    """The published picker (the drive mirrored, its crank turning with phi7 increasing) and picking at the other
    extreme (not mirrored, phi7 decreasing): at instants over a turn, the input torque, every joint force, the shaking
    force and moment."""
    _, spec, drive = loaded_picker(**installation)
    assert (drive.mount, drive.sense) == ((-1, 1) if not installation else (1, -1))
    gravity = (0.3, -9.81)
    dyn = picker_dynamics(loaded_table(spec, gravity), drive)
    instants = np.array([0.0, 0.07, 0.2, 0.33, 0.44, 0.61, 0.78, 0.93])
    ours = dyn.over_turn(instants * drive.omega)
    torque, reactions, shaking, moment, energy_torque = newton_euler(drive, assembly_sides(drive), instants, gravity)
    scale = np.abs(reactions).max()
    # measured: 7e-15 relative at most
    np.testing.assert_allclose(ours["torque"], torque, rtol=1e-12, atol=1e-13 * scale)
    np.testing.assert_allclose(ours["reactions"], reactions, rtol=1e-12, atol=1e-13 * scale)
    np.testing.assert_allclose(ours["shaking_force"], shaking, rtol=1e-12, atol=1e-13 * scale)
    np.testing.assert_allclose(ours["shaking_moment"], moment, rtol=1e-12, atol=1e-13 * scale)
    # the energy method: the motor's power is the rate of change of kinetic plus potential energy (measured: 6e-16)
    np.testing.assert_allclose(ours["torque"], energy_torque, rtol=1e-12, atol=1e-13 * np.abs(torque).max())
    assert np.abs(torque).max() > 0.3 and scale > 5.0


# ----- result.json -------------------------------------------------------------------------------------------------

def library_result(loaded=None) -> dict:
    return json.loads(result_text(kinds.get("picker").check(loaded or load_spec(SPEC))))


def test_energy_balance_over_every_interval_of_the_library_result():
    """From result.json alone: over each of the 360 sample intervals the motor's work (the periodic power integrated
    exactly) equals the change of the six links' kinetic and potential energy; over the turn it is zero (constant
    speed, no loads)."""
    dyn = library_result()["facts"]["dynamics"]
    assert len(dyn["links"]) == 6 and set(dyn["joints"]) == set(JOINTS)
    work, change, net = energy_residuals(dyn)
    peak = np.abs(work).max()
    assert peak > 1e-3
    assert np.abs(work - change).max() <= 1e-11 * peak         # measured: 8e-14
    assert abs(net) <= 1e-12 * peak                             # measured: 2e-14
    # the file's energies are the links' own
    energy = np.array(dyn["kinetic_energy_J"]) + np.array(dyn["potential_energy_J"])
    np.testing.assert_allclose(energy, mechanical_energy(dyn), rtol=0, atol=1e-12)


def test_the_double_crank_turns_at_the_speed_the_rocker_gives_it():
    """AB's speed in facts.dynamics is the rocker's (the rigid body), zero at picking and at dropping, and its angle
    spans the swing: the facts' AB angle at the dropping instant is the kind's."""
    loaded = load_spec(SPEC)
    data = library_result(loaded)
    dyn = data["facts"]["dynamics"]
    links = {link["role"]: link for link in dyn["links"]}
    np.testing.assert_allclose(links["rocker"]["angular_velocity_radps"], dyn["crank_ab_speed_radps"], rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(links["driven_crank"]["angular_velocity_radps"], dyn["crank_ab_speed_radps"], rtol=0,
                               atol=1e-12)
    speed = np.array(dyn["crank_ab_speed_radps"])
    assert abs(speed[0]) < 1e-12 and abs(speed[160]) < 1e-3 * np.abs(speed).max()   # 160 deg: the dropping instant
    ab = np.array(dyn["crank_ab_deg"])
    swing = next(r["value"] for r in data["rules"] if r["name"] == "drive_swing")
    assert ab[0] == pytest.approx(50.0, abs=1e-12)
    assert ab.max() - ab.min() == pytest.approx(swing, abs=1e-3)       # 1 deg samples: within 1e-3 deg of the top


def test_the_driven_torque_is_the_double_cranks_own_at_the_rockers_speed():
    """picker_double_crank's inverse dynamics (its kind's mapping and masses) with AB at the speed and acceleration
    the rocker gives it, at the angles AB takes, is the torque AE puts on AB in the combined picker."""
    _, spec, drive = loaded_picker()
    table = loaded_table(spec)
    dyn = picker_dynamics(table, drive)
    tau = turn(90)
    out = dyn.over_turn(tau)
    part = table.double_crank
    single = DynamicsSection(crank=part.crank, coupler=part.coupler, rocker=part.rocker,
                             point_masses=part.point_masses, gravity=table.gravity, crank_speed=60.0)
    own = double_crank_dynamics(single, tuple(float(v) for v in drive.dc.parameters()), drive.dc.branch)
    varying = over_turn(own.branch, out["crank_ab"], own.geometry, own.mass, own.loads,
                        out["crank_ab_speed"].reshape(1, -1), own.gravity, alpha=out["crank_ab_acceleration"])
    np.testing.assert_allclose(out["driven_torque"], varying["torque"], rtol=1e-12, atol=1e-13)
    # at picking AB stands still: only gravity and the rocker's acceleration load it
    assert abs(out["crank_ab_speed"][0]) < 1e-12 and abs(out["crank_ab_acceleration"][0]) > 1.0


def test_with_a_massless_double_crank_the_input_torque_is_the_crank_rockers_own():
    """The drive alone (a double crank of no mass), against crank_rocker's inverse dynamics in its own frame: the kind
    mounts it mirrored (a mirror image: torque of opposite sign) and turned by theta2 - 180 deg (gravity turned back
    into its frame), its crank at phi_pick + s tau."""
    loaded, spec, drive = loaded_picker()
    table = spec.dynamics
    zero = {"mass": 0.0, "com": (0.0, 0.0), "inertia": 0.0}
    massless = type(table).model_validate({**table.model_dump(), "double_crank": {
        "crank": zero, "coupler": zero, "rocker": zero}, "gravity": (0.4, -9.81)})
    tau = turn(72)
    ours = picker_dynamics(massless, drive).over_turn(tau)
    assert np.abs(ours["driven_torque"]).max() == 0.0
    cr_loaded = load_spec(spec.part_path(loaded.path, "crank_rocker"))
    from synthesis.kinds.crank_rocker.check import linkage_dynamics

    rot = drive.theta2 - math.pi
    gx, gy = 0.4, -9.81
    g_own = (math.cos(rot) * gx + math.sin(rot) * gy, drive.mount * (-math.sin(rot) * gx + math.cos(rot) * gy))
    part = table.crank_rocker
    cr_table = DynamicsSection(crank=part.crank, coupler=part.coupler, rocker=part.rocker, gravity=g_own,
                               crank_speed=60.0)
    cr_spec = cr_loaded.model.model_copy(update={"dynamics": cr_table})
    own = linkage_dynamics(cr_spec, (drive.cr.l7, drive.cr.l8, drive.cr.l9, drive.cr.l10))
    theirs = over_turn(own.branch, drive.phi_pick + drive.sense * tau, own.geometry, own.mass, own.loads,
                       drive.sense * drive.omega, own.gravity)
    np.testing.assert_allclose(ours["torque"], drive.mount * theirs["torque"], rtol=1e-12, atol=1e-13)
    assert np.abs(ours["torque"]).max() > 0.05


# ----- rules -------------------------------------------------------------------------------------------------------

def limited_table(spec):
    return loaded_table(spec).model_copy(update={"limits": DynamicsLimits(
        peak_input_torque=1.0, peak_shaking_force=20.0, peak_shaking_moment=2.0)})


def symbolic_rules(table, drive, samples: int) -> tuple[list, ca.Function]:
    """The rules on the parameters q as CasADi symbols (the bars' masses following the lengths) and q -> (values, rows,
    d rows / d q)."""
    q = ca.SX.sym("q", len(PARAMETERS))
    rules = dynamics_rules(PickerDynamics.of(table, drive.cr.branch, drive.mount, drive.dc.branch,
                                             [q[i] for i in range(len(PARAMETERS))]), table, samples)
    values = ca.vertcat(*[ca.vec(rule.expr) for rule in rules])
    rows = ca.vertcat(*[ca.vec(row[0]) for rule in rules for row in rule.rows()])
    return rules, ca.Function("rules", [q], [values, rows, ca.jacobian(rows, q)])


def float_rows(table, drive, q, samples: int) -> np.ndarray:
    rules = dynamics_rules(PickerDynamics.of(table, drive.cr.branch, drive.mount, drive.dc.branch, tuple(q)), table,
                           samples)
    return np.concatenate([np.ravel(np.asarray(row[0], float)) for r in rules for row in r.rows()])


def test_rules_are_the_same_on_floats_and_symbols():
    _, spec, drive = loaded_picker()
    table = limited_table(spec)
    symbolic, f = symbolic_rules(table, drive, 24)
    floats = dynamics_rules(picker_dynamics(table, drive), table, 24)
    assert [r.name for r in floats] == [r.name for r in symbolic] == [
        "peak_input_torque", "peak_shaking_force", "peak_shaking_moment"]
    q0 = np.array(parameters(drive))
    values, rows, _ = (np.asarray(v).ravel() for v in f(q0))
    np.testing.assert_allclose(values, np.concatenate([np.ravel(np.asarray(r.expr, float)) for r in floats]),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rows, float_rows(table, drive, q0, 24), rtol=1e-12, atol=1e-12)
    assert all("crank GF" in r.where for r in floats)


def test_rule_derivatives_equal_central_differences():
    """d(rows)/dq by CasADi AD against central differences of the float rows, for every parameter: the lengths of
    both linkages (they move the bars' masses too), the angles, the picking instant, the crank speed."""
    _, spec, drive = loaded_picker()
    table = limited_table(spec)
    _, f = symbolic_rules(table, drive, 24)
    q0 = np.array(parameters(drive))
    jac = np.asarray(f(q0)[2])
    steps = {"sense": None, "omega": 1e-5}
    for i, name in enumerate(PARAMETERS):
        h = steps.get(name, 1e-4 if i < 11 else 1e-6)
        if h is None:                # a sign, not a variable
            continue
        step = np.zeros(q0.size)
        step[i] = h
        central = (float_rows(table, drive, q0 + step, 24) - float_rows(table, drive, q0 - step, 24)) / (2 * h)
        np.testing.assert_allclose(jac[:, i], central, rtol=1e-6, atol=1e-6 * max(np.abs(jac[:, i]).max(), 1e-9),
                                   err_msg=name)
    moved = {name for i, name in enumerate(PARAMETERS) if np.abs(jac[:, i]).max() > 1e-4}
    # x_a, y_a only translate the machine: no dynamics quantity about G moves with them
    assert moved >= set(PARAMETERS) - {"x_a", "y_a", "sense"}


def test_the_check_rules_read_the_facts_peaks():
    """With every limit and the facts sampled on the check's own grid, each rule's value is facts.dynamics' peak."""
    loaded = load_spec(SPEC)
    table = loaded.model.dynamics.model_copy(update={"samples": 3600, "limits": DynamicsLimits(
        peak_input_torque=1.0, peak_shaking_force=20.0, peak_shaking_moment=2.0)})
    result = kinds.get("picker").check(type(loaded)(**{**loaded.__dict__,
                                                       "model": loaded.model.model_copy(update={"dynamics": table})}))
    rules = {r["name"]: r for r in result.rules}
    summary = result.extra["dynamics"]["summary"]
    assert rules["peak_input_torque"]["value"] == pytest.approx(summary["input_torque_Nm"]["peak"], rel=1e-14)
    assert rules["peak_shaking_force"]["value"] == pytest.approx(summary["shaking_force_N"]["peak"], rel=1e-14)
    assert rules["peak_shaking_moment"]["value"] == pytest.approx(summary["shaking_moment_Nm"]["peak"], rel=1e-14)
    assert all(r["satisfied"] for r in result.rules)


def test_a_picker_without_dynamics_has_no_dynamics_rules_or_facts():
    data = json.loads(result_text(kinds.get("picker").check(load_spec(LIBRARY / "picker" / "cai2020_picker.toml"))))
    assert "dynamics" not in data["facts"] and not any(r["name"].startswith("peak_") for r in data["rules"])


def test_a_tip_mass_on_the_drive_is_refused():
    from pydantic import ValidationError

    data = load_spec(SPEC).model.dynamics.model_dump()
    data["crank_rocker"]["point_masses"] = [{"link": "rocker", "mass": 0.1, "at": "tip"}]
    with pytest.raises(ValidationError, match=re.escape("is the clamp point M, on the double crank's coupler")):
        type(load_spec(SPEC).model.dynamics).model_validate(data)


# ----- the library spec --------------------------------------------------------------------------------------------

def test_the_library_specs_stated_peaks():
    """The header of cai2020_picker_dynamics.toml states the peak input torque, driven torque and shaking force and
    moment of its check; they are the result's, to the digits printed."""
    text = SPEC.read_text()
    stated = {key: float(re.search(rf"{key} (\d+\.\d+)", text).group(1)) for key in (
        "peak input torque", "peak torque on AB", "peak shaking force", "peak shaking moment")}
    summary = library_result()["facts"]["dynamics"]["summary"]
    found = {"peak input torque": summary["input_torque_Nm"]["peak"],
             "peak torque on AB": summary["driven_torque_Nm"]["peak"],
             "peak shaking force": summary["shaking_force_N"]["peak"],
             "peak shaking moment": summary["shaking_moment_Nm"]["peak"]}
    for key, value in stated.items():
        assert found[key] == pytest.approx(value, abs=0.0005 + 1e-12), key
