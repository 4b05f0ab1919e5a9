"""Inverse dynamics of the four-bar kinds (docs/ARCHITECTURE.md "Dynamics").

* An independent multibody formulation (sympy.physics.mechanics: frames, points, accelerations by differentiating
  position vectors in time, the loop's velocity and acceleration from its constraint equations, and the 9 x 9
  Newton-Euler system about each link's centre of mass solved by sympy) gives the same input torque, joint forces and
  shaking force as synthesis.dynamics (closed form about the pivots, CasADi derivatives) to 1e-6 relative, and the
  same shaking moment about the crank pivot from the links' angular momentum alone.
* Energy balance from result.json alone: the input work over each sample interval (the periodic power integrated
  spectrally) equals the change of kinetic plus potential energy of the links; over a turn the net work is zero.
* The rules' AD derivatives equal central differences of the same rules on floats.
"""

from __future__ import annotations

import json
import re
import math

import casadi as ca
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import Point, ReferenceFrame, dynamicsymbols, msubs

from conftest import LIBRARY
from dynamics_support import energy_residuals
from synthesis.dynamics import mass as mass_properties
from synthesis.dynamics.fourbar import over_turn
from synthesis.kinds.crank_rocker.check import linkage_dynamics, rules_of
from synthesis.kinds.planting.check import dynamics_facts_of
from synthesis.kinds.planting.dynamics import arm_dynamics, arm_dynamics_rules
from synthesis.kinds.planting.scene import PlantingScene
from synthesis.kinds.planting.spec import PlantingFourbarSpec
from synthesis import kinds
from synthesis.result import result_text
from synthesis.spec import load_spec
from synthesis.spec.dynamics import Counterweight, DynamicsLimits, ExternalLoad

#: a lumped set of mass properties per link (kg, m, m, kg m^2), centres off the link lines so every term counts
LUMPED = [0.30, 0.021, 0.004, 2.0e-4, 0.65, 0.050, -0.012, 1.4e-3, 0.45, 0.060, 0.008, 9.0e-4]
#: (geometry l1..l4 mm, zeta rad, branch) of the seed-001 crank-rocker and the seed-000 planting arm (example 1)
CASES = {"crank_rocker": ((140.0, 54.0, 107.6, 133.5, 0.0), 1),
         "planting_arm": ((75.0, 35.0, 75.0, 80.0, math.radians(-90.0)), -1)}
OMEGA = 250 * 2 * math.pi / 60
GRAVITY = (0.3, -9.81)


def sympy_newton_euler(geometry, mass, omega, gravity, theta, angles_guess, crank_alpha=0.0, moments=(0.0, 0.0, 0.0),
                       soil=None):
    """Torque, reactions (frame-crank, crank-coupler, coupler-rocker, frame-rocker) and shaking force at crank angle
    theta, by sympy.physics.mechanics: link angles q1 (crank, absolute), q2, q3 with the loop closed numerically.
    ``crank_alpha``: the crank's angular acceleration; ``moments``: a couple on each link; ``soil``: (f0, k,
    surface_y mm, forward speed, at_x, at_y mm on the coupler): the soil law written here from the point's sympy
    position and velocity."""
    l1, l2, l3, l4, zeta = geometry
    q1, q2, q3 = dynamicsymbols("q1 q2 q3")
    t = dynamicsymbols._t
    frame = ReferenceFrame("N")
    links = [frame.orientnew(f"C{k}", "Axis", (q, frame.z)) for k, q in enumerate((q1, q2, q3), 1)]
    o = Point("O")
    o_rocker = o.locatenew("Op", l1 / 1000 * (sp.cos(zeta) * frame.x + sp.sin(zeta) * frame.y))
    a = o.locatenew("A", l2 / 1000 * links[0].x)
    b = a.locatenew("B", l3 / 1000 * links[1].x)
    loop = b.pos_from(o) - o_rocker.pos_from(o) - l4 / 1000 * links[2].x
    closure = [loop.dot(frame.x), loop.dot(frame.y)]
    crank = float(zeta + theta)
    q23 = sp.nsolve([c.subs(q1, crank) for c in closure], [q2, q3], angles_guess, tol=1e-30, prec=30)
    values = {q1: crank, q2: q23[0], q3: q23[1]}
    # the loop's velocity and acceleration: the time derivatives of its closure, q1' = omega, q1'' = 0
    d1 = [sp.diff(c, t) for c in closure]
    d2 = [sp.diff(c, t, 2) for c in closure]
    first = {q1.diff(t): omega}
    u = sp.solve([msubs(e, first, values) for e in d1], [q2.diff(t), q3.diff(t)])
    second = {q1.diff(t, 2): crank_alpha, q2.diff(t, 2): sp.Symbol("a2"), q3.diff(t, 2): sp.Symbol("a3")}
    known = {**first, q2.diff(t): u[q2.diff(t)], q3.diff(t): u[q3.diff(t)]}
    acc = sp.solve([msubs(e, second, known, values) for e in d2], [sp.Symbol("a2"), sp.Symbol("a3")])
    alpha = [crank_alpha, acc[sp.Symbol("a2")], acc[sp.Symbol("a3")]]
    kin = {q1.diff(t, 2): crank_alpha, q2.diff(t, 2): acc[sp.Symbol("a2")], q3.diff(t, 2): acc[sp.Symbol("a3")], **known}
    origins = (o, a, o_rocker)
    coms = [origins[k].locatenew(f"G{k}", mass[4 * k + 1] * links[k].x + mass[4 * k + 2] * links[k].y)
            for k in range(3)]
    f = sp.symbols("fox foy fax fay fbx fby fpx fpy torque")
    fo, fa, fb, fp = (f[0] * frame.x + f[1] * frame.y, f[2] * frame.x + f[3] * frame.y,
                      f[4] * frame.x + f[5] * frame.y, f[6] * frame.x + f[7] * frame.y)
    g = gravity[0] * frame.x + gravity[1] * frame.y
    soil_force, soil_point = 0 * frame.x, a
    if soil is not None:
        f0, k, surface, forward, sx, sy = soil
        soil_point = a.locatenew("C", sx / 1000 * links[1].x + sy / 1000 * links[1].y)
        p = soil_point.pos_from(o)
        depth = surface - 1000 * float(sp.N(msubs(p.dot(frame.y), values)))
        rel = [float(sp.N(msubs(p.dt(frame).dot(e), kin, values))) + v for e, v in ((frame.x, forward), (frame.y, 0))]
        scale = -(f0 + k * depth) / math.sqrt(rel[0] ** 2 + rel[1] ** 2 + 1e-6) if depth > 0 else 0.0
        soil_force = scale * rel[0] * frame.x + scale * rel[1] * frame.y
    # the shaking moment about O from the links' angular momentum alone (no reaction enters): the frame feels minus
    # the moment about O of what it and the motor apply, which is d/dt of the angular momentum about O less gravity's
    # moment, sum_k r_k x m_k (a_k - g) + I_k alpha_k
    spin_rate = sum((coms[k].pos_from(o).cross(mass[4 * k] * (coms[k].pos_from(o).dt(frame).dt(frame) - g))
                     + mass[4 * k + 3] * alpha[k] * frame.z for k in range(3)), 0 * frame.z)
    # less what the agents that are not the frame apply: the couples and the soil force
    spin_rate = spin_rate - sum(moments) * frame.z - soil_point.pos_from(o).cross(soil_force)
    shaking_moment = -float(sp.N(msubs(spin_rate.dot(frame.z), kin, values), 20))
    # (forces at points, torque) on each link: frame on crank at O and the motor, crank on coupler at A, ...
    loads = [([(fo, o), (-fa, a)], f[8] + moments[0]), ([(fa, a), (-fb, b), (soil_force, soil_point)], moments[1]),
             ([(fb, b), (fp, o_rocker)], moments[2])]
    equations = []
    for k, (forces, torque) in enumerate(loads):
        m, inertia = mass[4 * k], mass[4 * k + 3]
        acc_com = coms[k].pos_from(o).dt(frame).dt(frame)
        resultant = sum((force for force, _ in forces), m * g) - m * acc_com
        moment = sum((p.pos_from(coms[k]).cross(force) for force, p in forces), torque * frame.z)
        equations += [resultant.dot(frame.x), resultant.dot(frame.y), moment.dot(frame.z) - inertia * alpha[k]]
    numeric = [sp.N(msubs(e, kin, values), 20) for e in equations]
    solution = sp.solve(numeric, f)
    s = np.array([float(solution[x]) for x in f])
    reactions = s[:8].reshape(4, 2).T
    return s[8], reactions, -(reactions[:, 0] + reactions[:, 3]), shaking_moment


def assert_sample_agrees(ours: dict, i: int, independent: tuple, rel: float, share: float) -> None:
    """Sample i of over_turn's outputs against an independent (torque, reactions, shaking force, shaking moment):
    relative ``rel``, absolute ``share`` of the largest joint force there."""
    torque, reactions, shaking, moment = independent
    scale = np.abs(reactions).max()
    assert ours["torque"][i] == pytest.approx(torque, rel=rel, abs=share * scale)
    np.testing.assert_allclose(ours["reactions"][:, :, i], reactions, rtol=rel, atol=share * scale)
    np.testing.assert_allclose(ours["shaking_force"][:, i], shaking, rtol=rel, atol=share * scale)
    assert ours["shaking_moment"][i] == pytest.approx(moment, rel=rel, abs=share * scale)


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_inverse_dynamics_equals_an_independent_multibody_formulation(case):
    geometry, branch = CASES[case]
    thetas = np.radians([0.0, 47.0, 133.0, 200.0, 291.0])
    ours = over_turn(branch, thetas, geometry, LUMPED, [0.0] * 12, OMEGA, GRAVITY)
    for i, theta in enumerate(thetas):
        independent = sympy_newton_euler(geometry, LUMPED, OMEGA, GRAVITY, theta,
                                         [float(ours["angle"][1, i]), float(ours["angle"][2, i])])
        assert_sample_agrees(ours, i, independent, 1e-6, 1e-9)
    # not a trivial agreement: the torque changes sign over the turn and the forces are tens of newtons
    assert ours["torque"].min() < 0 < ours["torque"].max()
    assert np.abs(ours["reactions"]).max() > 10.0
    assert ours["shaking_moment"].min() < 0 < ours["shaking_moment"].max()


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_fluctuating_crank_with_couples_and_soil_equals_the_independent_formulation():
    """The general four-bar: per-sample crank speed and acceleration, a couple on every link and the soil law on a
    coupler point below the surface, against sympy (the soil force written there from the point's own motion)."""
    geometry, branch = CASES["planting_arm"]
    thetas = np.radians([0.0, 47.0, 133.0, 200.0, 291.0])
    omega = OMEGA * (1.0 + 0.08 * np.sin(thetas))
    alpha = omega * OMEGA * 0.08 * np.cos(thetas)            # omega d(omega)/d(theta)
    moments = np.array([[0.4], [-0.7], [1.1]]) * np.ones((1, thetas.size))
    soil = (6.0, 0.35, -20.0, 0.6, 180.0, -90.0)              # the point 200 mm out on the coupler, below y = -20
    ours = over_turn(branch, thetas, geometry, LUMPED, [0.0] * 12, omega, GRAVITY, alpha=alpha, moments=moments,
                     soil=soil)
    assert (ours["soil_depth"] > 0).sum() >= 2 and (ours["soil_depth"] < 0).sum() >= 1   # in and out of the soil
    for i, theta in enumerate(thetas):
        independent = sympy_newton_euler(
            geometry, LUMPED, float(omega[i]), GRAVITY, theta,
            [float(ours["angle"][1, i]), float(ours["angle"][2, i])], float(alpha[i]), tuple(moments[:, i]), soil)
        assert_sample_agrees(ours, i, independent, 1e-6, 1e-9)
    constant = over_turn(branch, thetas, geometry, LUMPED, [0.0] * 12, OMEGA, GRAVITY)
    assert np.abs(ours["torque"] - constant["torque"]).max() > 0.1      # the extras are not negligible here


def test_power_balance_of_the_general_four_bar_at_every_sample():
    """d(kinetic + potential)/dt = torque omega + the external power (couples and soil), pointwise over a turn at a
    fluctuating speed; the energy's rate by spectral differentiation in theta times omega."""
    geometry, branch = CASES["planting_arm"]
    n = 512
    thetas = 2 * np.pi * np.arange(n) / n
    omega = OMEGA * (1.0 + 0.08 * np.sin(thetas))
    alpha = omega * OMEGA * 0.08 * np.cos(thetas)
    moments = np.vstack([0.4 * np.ones(n), -0.7 * np.cos(thetas), 1.1 * np.ones(n)])
    # f0 = 0: the soil force is continuous in the depth, so the energy stays smooth enough for spectral derivatives
    out = over_turn(branch, thetas, geometry, LUMPED, [0.0] * 12, omega, GRAVITY, alpha=alpha, moments=moments,
                    soil=(0.0, 0.02, -60.0, 0.6, 180.0, -90.0))
    energy = out["kinetic_energy"] + out["potential_energy"]
    wavenumbers = np.fft.rfftfreq(n, 1.0 / n)
    rate = np.fft.irfft(1j * wavenumbers * np.fft.rfft(energy), n) * omega
    power = out["torque"] * omega + out["external_power"]
    assert np.abs(out["soil_force"]).max() > 0.5                   # the soil works on part of the turn
    np.testing.assert_allclose(power, rate, atol=2e-4 * np.abs(power).max())


def test_planting_coupler_bars_combine_by_the_parallel_axis_theorem():
    """The coupler AB with the claw arm AC and a claw mass: against the bars integrated point by point."""
    ab, ac = (75.0, 0.0), (191.0 * math.cos(math.radians(-31)), 191.0 * math.sin(math.radians(-31)))
    m, cx, cy, inertia = mass_properties.combine([mass_properties.bar(7850, 100, (0, 0), ab),
                                                  mass_properties.bar(7850, 100, (0, 0), ac),
                                                  mass_properties.point(0.05, ac)])
    s = (np.arange(200000) + 0.5) / 200000
    pts = [np.outer(s, end) / 1000.0 for end in (ab, ac)]
    dm = [7850 * 100e-6 * np.hypot(*end) / 1000.0 / s.size for end in (ab, ac)]
    total = dm[0] * s.size + dm[1] * s.size + 0.05
    centre = (dm[0] * pts[0].sum(0) + dm[1] * pts[1].sum(0) + 0.05 * np.array(ac) / 1000) / total
    spread = (dm[0] * ((pts[0] - centre) ** 2).sum() + dm[1] * ((pts[1] - centre) ** 2).sum()
              + 0.05 * ((np.array(ac) / 1000 - centre) ** 2).sum())
    assert m == pytest.approx(total, rel=1e-12)
    assert (cx, cy) == pytest.approx(tuple(centre), rel=1e-9)
    assert inertia == pytest.approx(spread, rel=1e-8)


def checked_json(path) -> dict:
    """result.json's data of ``check`` on a library spec, as written (strict JSON) and read back."""
    loaded = load_spec(path)
    return json.loads(result_text(kinds.get(loaded.model.kind).check(loaded)))


def test_energy_balance_of_the_crank_rocker_result():
    dyn = checked_json(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml")["facts"]["dynamics"]
    work, change, net = energy_residuals(dyn)
    peak = np.abs(work).max()
    assert peak > 1e-3
    assert np.abs(work - change).max() <= 1e-6 * peak
    assert abs(net) <= 1e-9 * np.abs(dyn["power_W"]).max() * 2 * math.pi / (250 * 2 * math.pi / 60)


def test_rule_derivatives_equal_central_differences():
    """d(rule rows)/d(lengths) by CasADi AD against central differences of the same rows on floats."""
    loaded = load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml")
    spec = loaded.model.model_copy(update={"dynamics": loaded.model.dynamics.model_copy(
        update={"limits": loaded.model.dynamics.limits.model_copy(update={"peak_input_torque": 1.0,
                                                                          "peak_shaking_force": 20.0,
                                                                          "peak_shaking_moment": 2.0})})})
    x0 = np.array([54.0, 107.6, 133.5, 140.0])
    z = ca.SX.sym("z", 4)
    mu = ca.SX.sym("mu", 72)            # the rows read only the lengths; a stand-in for the transmission samples
    names = ("peak_input_torque", "peak_shaking_force", "peak_shaking_moment")

    def rows(lengths):
        rules = {r.name: r for r in rules_of(spec, [lengths[i] for i in range(4)], 1.0, (1.0, 0.0), (0.0, 1.0), mu)}
        return ca.vertcat(*[rules[n].rows()[0][0] for n in names])

    f = ca.Function("rows", [z, mu], [rows(z), ca.jacobian(rows(z), z)])
    values, jac = (np.asarray(v) for v in f(x0, np.full(72, 60.0)))
    h = 1e-4
    for i in range(4):
        step = np.zeros(4)
        step[i] = h
        central = (np.asarray(f(x0 + step, np.full(72, 60.0))[0]) - np.asarray(f(x0 - step, np.full(72, 60.0))[0])) / (2 * h)
        scale = np.abs(jac[:, i]).max()
        np.testing.assert_allclose(jac[:, i:i + 1], central, rtol=1e-6, atol=1e-6 * scale)
    assert values.shape == (216, 1) and np.abs(jac).max() > 1e-3


def test_energy_balance_of_the_planting_arm_result():
    dyn = checked_json(LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml")["facts"]["dynamics"]
    work, change, net = energy_residuals(dyn)
    peak = np.abs(work).max()
    assert peak > 1e-2 and dyn["external_loads"] is False
    assert np.abs(work - change).max() <= 1e-6 * peak
    assert abs(net) <= 1e-9 * peak


def test_energy_balance_with_an_external_load():
    """A constant force on the rocker: the input and the load's work together change the energy; over a turn the
    input work is what the load takes (not zero)."""
    loaded = load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml")
    table = loaded.model.dynamics.model_copy(update={"external_loads": [
        ExternalLoad(link="rocker", force=(-30.0, 12.0), at=(133.5, 0.0), note="test load")]})
    spec = loaded.model.model_copy(update={"dynamics": table})
    result = kinds.get("crank_rocker").check(type(loaded)(**{**loaded.__dict__, "model": spec}))
    dyn = json.loads(result_text(result))["facts"]["dynamics"]
    work, change, net = energy_residuals(dyn)
    own = checked_json(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml")["facts"]["dynamics"]
    assert np.abs(work - change).max() <= 1e-6 * np.abs(work).max()
    assert dyn["external_loads"]["loads"][0]["force"] == [-30.0, 12.0]
    assert not np.allclose(dyn["input_torque_Nm"], own["input_torque_Nm"], rtol=1e-2)
    # net (input + load) work over a turn is zero; the input's alone equals minus the load's
    omega = 250 * 2 * math.pi / 60
    input_net = np.mean(dyn["power_W"]) * 2 * math.pi / omega
    load_net = np.mean(dyn["external_loads"]["external_power_W"]) * 2 * math.pi / omega
    assert abs(net) <= 1e-9 * np.abs(work).max()
    assert input_net == pytest.approx(-load_net, rel=1e-9, abs=1e-12)


def test_a_spec_without_dynamics_has_no_dynamics_rules_or_facts():
    for path in ("picker/cai2020_crank_rocker.toml", "planting_arm/taiwan_example1.toml"):
        data = checked_json(LIBRARY / path)
        assert "dynamics" not in data["facts"]
        assert not {"peak_input_torque", "peak_shaking_force"} & {r["name"] for r in data["rules"]}


#: seed 000 Table 1's designs at 250 r/min with taiwan_example1_dynamics.toml's arm section (steel 20 x 5 mm bars,
#: a 50 g claw at C, gravity -Y): peak |input torque| N m and its crank angle deg, peak |shaking force| N
#: (problems/planting_arm/DYNAMICS.md)
PUBLISHED = {"taiwan_example1": (2.5242, 340.0, 29.560), "taiwan_example2": (0.5764, 336.0, 15.083),
             "taiwan_example2_zeta_minus41": (0.7026, 338.0, 18.835), "taiwan_example3": (2.4106, 339.0, 26.799),
             "taiwan_example4": (3.1188, 343.0, 30.665)}


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_published_planting_designs_peak_torque_and_shaking_force(name):
    import tomllib
    table = tomllib.loads((LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml").read_text())["dynamics"]
    data = tomllib.loads((LIBRARY / "planting_arm" / f"{name}.toml").read_text())
    spec = PlantingFourbarSpec.model_validate({**data, "dynamics": table})
    summary = dynamics_facts_of(PlantingScene.from_spec(spec), 250.0)["dynamics"]["summary"]
    torque, at, force = PUBLISHED[name]
    assert summary["input_torque_Nm"]["peak"] == pytest.approx(torque, abs=5e-5)
    assert summary["input_torque_Nm"]["peak_at_crank_deg"] == pytest.approx(at)
    assert summary["shaking_force_N"]["peak"] == pytest.approx(force, abs=5e-4)


def test_planting_rule_derivatives_equal_central_differences():
    """The arm's dynamics rows (l5 and phi move the claw arm and the claw's mass) by AD against central differences."""
    loaded = load_spec(LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml")
    table = loaded.model.dynamics.model_copy(update={"limits": DynamicsLimits(peak_input_torque=1.0,
                                                                               peak_shaking_force=20.0)})
    p = ca.SX.sym("p", 7)
    dyn = arm_dynamics(table, p, -1, OMEGA)
    rules = {r.name: r for r in arm_dynamics_rules(dyn, 36)}
    rows = ca.vertcat(*[rules[n].rows()[0][0] for n in ("peak_input_torque", "peak_shaking_force")])
    f = ca.Function("rows", [p], [rows, ca.jacobian(rows, p)])
    p0 = np.array([75.0, 35.0, 75.0, 80.0, 191.0, math.radians(-90.0), math.radians(31.0)])
    jac = np.asarray(f(p0)[1])
    for i, h in enumerate([1e-4] * 5 + [1e-6] * 2):
        step = np.zeros(7)
        step[i] = h
        central = (np.asarray(f(p0 + step)[0]) - np.asarray(f(p0 - step)[0])) / (2 * h)
        np.testing.assert_allclose(jac[:, i:i + 1], central, rtol=1e-6, atol=1e-6 * np.abs(jac[:, i]).max())
    assert np.abs(jac[:, 4]).max() > 1e-3       # the claw arm's length moves the torque


@pytest.mark.parametrize("path, change, message", [
    ("picker/cai2020_crank_rocker.toml", {"objective": {"name": "min_peak_torque"}}, "needs a [dynamics] table"),
    ("planting_arm/taiwan_example1.toml", {"objective": {"name": "min_peak_shaking_force"}},
     "needs a [dynamics] table"),
    ("picker/cai2020_crank_rocker_dynamics.toml", {"dynamics": {"crank_speed": None}}, "has no crank speed"),
    ("planting_arm/taiwan_example1_dynamics.toml", {"dynamics": {"crank_speed": 250.0}}, "[operation] crank_speed"),
    ("picker/cai2020_crank_rocker_dynamics.toml",
     {"dynamics": {"point_masses": [{"link": "rocker", "mass": 0.1, "at": "tip"}]}}, "names a traced point"),
    ("planting_arm/taiwan_example1_dynamics.toml",
     {"dynamics": {"external_loads": [{"link": "coupler", "force": [1.0, 0.0], "at": [0.0, 0.0]},
                                      {"link": "coupler", "force": [0.0, 1.0], "at": [10.0, 0.0]}]}},
     "at most one load per link"),
])
def test_dynamics_tables_that_cannot_hold_are_refused(path, change, message):
    import tomllib
    from pydantic import ValidationError
    data = tomllib.loads((LIBRARY / path).read_text())
    for key, value in change.items():
        data[key] = {**data.get(key, {}), **value}
        data[key] = {k: v for k, v in data[key].items() if v is not None}
    with pytest.raises(ValidationError, match=re.escape(message)):
        kinds.get(data["kind"]).spec_model().model_validate(data)


def test_the_dynamics_figure_is_drawn_from_the_result_alone(tmp_path):
    """A result with facts.dynamics gets dynamics.png among its run's figures (synthesis/report); one without does not."""
    from synthesis.report import run_artifacts
    from synthesis.report.dynamics_plots import dynamics_figure
    loaded = load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml")
    result = kinds.get("crank_rocker").check(loaded)
    dynamics_figure(result, tmp_path / "dynamics.png")
    assert (tmp_path / "dynamics.png").stat().st_size > 10_000
    plain = load_spec(LIBRARY / "picker" / "cai2020_crank_rocker.toml")
    assert "dynamics.png" in run_artifacts(result)
    assert "dynamics.png" not in run_artifacts(kinds.get("crank_rocker").check(plain))
    with pytest.raises(ValueError, match="no facts.dynamics"):
        dynamics_figure(kinds.get("crank_rocker").check(plain), tmp_path / "none.png")


def test_compare_overlays_the_dynamics_of_the_candidates_that_have_them(tmp_path):
    """compare of a result with facts.dynamics and one without: dynamics.png overlays the one (the other named as
    left out) and the page shows it; of two without, no dynamics figure."""
    from matplotlib.image import imread

    from synthesis.report import comparison_figures
    from synthesis.report.tables import candidates

    with_table = kinds.get("crank_rocker").check(load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml"))
    plain = kinds.get("crank_rocker").check(load_spec(LIBRARY / "picker" / "cai2020_crank_rocker.toml"))
    figures, notes = comparison_figures(candidates([with_table, plain]), tmp_path)
    assert "dynamics.png" in [name for name, _ in figures] and not notes
    assert imread(tmp_path / "dynamics.png").shape[0] > 500         # three panels drawn
    (tmp_path / "dynamics.png").unlink()
    figures, _ = comparison_figures(candidates([plain, plain]), tmp_path)
    assert "dynamics.png" not in [name for name, _ in figures] and not (tmp_path / "dynamics.png").exists()


def test_a_counterweight_changes_the_shaking_force_by_its_centrifugal_force_only():
    """Gravity off, constant speed: a counterweight m at radius r opposite the crank pin leaves the input torque as it is
    and adds m r omega^2 to the shaking force, pointing from the crank pivot away from the pin."""
    loaded = load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml")
    plain = loaded.model.dynamics.model_copy(update={"gravity": (0.0, 0.0)})
    weighted = plain.model_copy(update={"counterweight": Counterweight(mass=0.2, radius=40.0)})
    lengths = (54.0, 107.6, 133.5, 140.0)
    crank = np.radians(np.arange(0.0, 360.0, 15.0))
    before, after = (linkage_dynamics(loaded.model.model_copy(update={"dynamics": t}), lengths).over_turn(crank)
                     for t in (plain, weighted))
    np.testing.assert_allclose(after["torque"], before["torque"], rtol=1e-12, atol=1e-12)
    pull = 0.2 * 0.040 * (250 * 2 * math.pi / 60) ** 2                 # 5.48 N
    expected = before["shaking_force"] - pull * np.vstack([np.cos(crank), np.sin(crank)])
    np.testing.assert_allclose(after["shaking_force"], expected, rtol=1e-12, atol=1e-9)
    assert np.abs(after["shaking_force"] - before["shaking_force"]).max() == pytest.approx(pull)


def test_a_crank_rocker_refuses_a_free_counterweight():
    import tomllib
    from pydantic import ValidationError
    data = tomllib.loads((LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml").read_text())
    data["dynamics"]["counterweight"] = {"mass": {"init": 0.1, "bounds": [0.0, 1.0]}, "radius": 30.0}
    with pytest.raises(ValidationError, match="frees only its lengths"):
        kinds.get("crank_rocker").spec_model().model_validate(data)


def test_a_peak_objective_stays_finite_when_the_given_design_cannot_turn(tmp_path):
    """crank_rocker_min_peak_torque with l7 = 150 (no crank-rocker: the given design's peak is NaN): the objective's
    scale falls back to 1 N m, so f = t / scale is finite (before, t / NaN failed every start)."""
    import casadi as ca

    from synthesis.kinds.crank_rocker.nlp import _peak_objective
    from synthesis.spec import load_spec

    text = (LIBRARY / "picker" / "crank_rocker_min_peak_torque.toml").read_text()
    assert "l7 = { init = 50.0," in text
    path = tmp_path / "bad_init.toml"
    path.write_text(text.replace("l7 = { init = 50.0,", "l7 = { init = 150.0,"))
    spec = load_spec(path).model
    parts = _peak_objective(spec, ca.SX.sym("p", 4))
    f = ca.Function("f", [parts.extra], [parts.f])
    assert float(f(2.0)) == pytest.approx(2.0)


@pytest.mark.parametrize("path", ["planting_arm/taiwan_example1_dynamics.toml",
                                  "picker/cai2020_crank_rocker_dynamics.toml"])
def test_a_shaking_moment_limit_is_a_rule_of_the_check(tmp_path, path):
    """[dynamics.limits] peak_shaking_moment: a rule of both four-bar kinds whose value is the peak |shaking moment|
    about the crank pivot; set at half the design's peak it is violated by that much, and the peak agrees with
    result.json's facts.dynamics (360 samples) to 1 % (the rule reads the kind's own grid)."""
    text = (LIBRARY / path).read_text()
    assert "[dynamics.limits]" not in text
    peak = max(abs(m) for m in checked_json(LIBRARY / path)["facts"]["dynamics"]["shaking_moment_Nm"])
    spec = tmp_path / "moment.toml"
    spec.write_text(f"{text}\n[dynamics.limits]\npeak_shaking_moment = {0.5 * peak!r}\n")
    rules = {r["name"]: r for r in checked_json(spec)["rules"]}
    rule = rules["peak_shaking_moment"]
    assert rule["unit"] == "N m" and rule["limit"][0] is None and rule["limit"][1] == pytest.approx(0.5 * peak)
    assert rule["value"] == pytest.approx(peak, rel=1e-2) and rule["satisfied"] is False
    assert peak > 0.1            # a real moment: tenths of a newton metre and more
