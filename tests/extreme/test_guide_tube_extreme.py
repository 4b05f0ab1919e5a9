"""guide_tube at the edges of its physics: near-sticking walls (A -> 0), decelerating slides,
sticking, steep drag (v_L down to 0.5 m/s), the closed form against the ODE over v_L in [0.5, 1e4] m/s and
A in [1e-10, 0.8] (one bench row per v_L), very long falls, and the drag-free limit."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import brentq

from synthesis.kinds.guide_tube import drag
from synthesis.kinds.guide_tube.drag import Q_LONG, Q_SERIES, stopping_distance, traverse
from synthesis.kinds.guide_tube.drop import Physics, SeedlingSticks, Tube, drop_phases, landing
from synthesis.kinds.guide_tube.ode import simulate
from synthesis.kinds.guide_tube.slope import landing_time_slope
from solving import agrisynth

ROOT = Path(__file__).resolve().parents[2]
BASELINE = ROOT / "problems" / "guide_tube" / "cai2020_tubes.toml"
TUBE_I = Tube("I", 0.105, 0.040, 0.210)
TUBE_II = Tube("II", 0.035, 0.040, 0.210)
G = 9.8


@pytest.fixture(autouse=True)
def no_floating_point_warnings():
    """No overflow, invalid operation or division by zero anywhere (numpy raises; warnings are errors)."""
    with np.errstate(over="raise", invalid="raise", divide="raise"), warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def physics_with_a_sq(delta_deg: float, a_sq: float, terminal_speed: float = 17.5) -> Physics:
    """The friction coefficient that leaves sin d - mu cos d = a_sq."""
    d = math.radians(delta_deg)
    return Physics(0.6, G, terminal_speed, (math.sin(d) - a_sq) / math.cos(d))


# --- near sticking: tan d -> mu+, A = sqrt(sin d - mu cos d) -> 0 -------------------------------------------

@pytest.mark.parametrize("A", [1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8])
@pytest.mark.parametrize("tube", [TUBE_I, TUBE_II], ids=["I", "II"])
def test_near_sticking_closed_form_matches_the_ode(tube, A, record_property):
    """v_L = 17.5 m/s, 40 deg wall, A -> 0: landing time within 1e-6 s and slide time within 1e-9 s of the ODE."""
    physics = physics_with_a_sq(40.0, A * A)
    closed = landing(40.0, tube, physics)
    ode = simulate(40.0, tube, physics)
    assert math.isfinite(closed.landing_time)
    assert abs(closed.landing_time - ode.landing_time) < 1e-6
    assert abs(closed.t_slide - ode.t_slide) < 1e-9          # what we measure (DOP853 at 1e-12)
    record_property("figure", f"tube {tube.name}, A = {A:g}: slide {closed.t_slide:.5f} s, |closed form - ODE| = "
                              f"{abs(closed.landing_time - ode.landing_time):.1e} s")


def test_slide_time_is_continuous_through_a_zero_driving_acceleration():
    """a = g A^2 crosses zero: the slide time is one smooth function of a (no 1/A)."""
    kappa, v0, s = G / 17.5 ** 2, 1.5, 0.15
    times = [traverse(v0, a, kappa, s)[0] for a in (-1e-12, -1e-15, 0.0, 1e-15, 1e-12)]
    assert max(times) - min(times) < 1e-12
    # a = 0 exactly is pure drag: v = v0 / (1 + kappa v0 t), so t = (exp(kappa s) - 1) / (kappa v0)
    assert times[2] == pytest.approx(math.expm1(kappa * s) / (kappa * v0), rel=1e-14)
    # and its slope in a is finite and the same from both sides (CasADi AD through the series)
    a = ca.SX.sym("a")
    slope = ca.Function("slope", [a], [ca.jacobian(traverse(v0, a, kappa, s)[0], a)])
    left, right = float(slope(-1e-12)), float(slope(1e-12))
    assert math.isfinite(left) and left == pytest.approx(right, rel=1e-9)


@pytest.mark.parametrize("threshold", [Q_SERIES, -Q_SERIES, Q_LONG])
def test_branch_switches_of_the_closed_form_are_seamless(threshold):
    """The series / atanh / atan / long-distance forms meet without a jump in value or slope."""
    kappa, v0, s = G / 2.0 ** 2, 0.8, 0.3

    def q_of(a):
        E = math.exp(-2 * kappa * s)
        W = (1 - E) / kappa
        v = math.sqrt(v0 * v0 * E + a * W)
        return a * kappa * W * W / (v + v0 * E) ** 2

    E = math.exp(-2 * kappa * s)
    a_stops = -v0 * v0 * E * kappa / (1 - E)       # below it the motion stops before s
    a_star = brentq(lambda a: q_of(a) - threshold, a_stops * (1 - 1e-9), 1e6, xtol=1e-15)
    a = ca.SX.sym("a")
    t = traverse(v0, a, kappa, s)[0]
    f = ca.Function("f", [a], [t, ca.jacobian(t, a)])
    below, above = f(a_star * (1 - 1e-9)), f(a_star * (1 + 1e-9))
    assert float(above[0]) == pytest.approx(float(below[0]), rel=1e-9)
    assert float(above[1]) == pytest.approx(float(below[1]), rel=1e-6)


# --- decelerating slide: tan d < mu ---------------------------------------------------------------------

@pytest.mark.parametrize("delta, mu", [(30.0, 0.8), (20.0, 0.6), (35.0, 1.2)])
def test_decelerating_slide_is_real_and_matches_the_ode(delta, mu, record_property):
    """tan d < mu: the slide slows down, landing time within 1e-9 s of the ODE, value and AD slope of the
    symbolic form equal the float form (1e-14 s) and the independent slope (1e-9 relative)."""
    physics = Physics(0.6, G, 17.5, mu)
    assert math.tan(math.radians(delta)) < mu
    closed = landing(delta, TUBE_II, physics)
    ode = simulate(delta, TUBE_II, physics)
    assert closed.slide_accel < 0 and closed.v_exit < closed.v_wall        # it slows down ...
    assert abs(closed.landing_time - ode.landing_time) < 1e-9              # ... as the ODE says
    d = ca.SX.sym("d")
    t_z = drop_phases(d, TUBE_II, physics).landing_time
    value, slope = ca.Function("f", [d], [t_z, ca.jacobian(t_z, d)])(math.radians(delta))
    assert float(value) == pytest.approx(closed.landing_time, abs=1e-14)    # no NaN, no complex
    assert float(slope) == pytest.approx(landing_time_slope(delta, TUBE_II, physics), rel=1e-9)
    record_property("figure", f"{delta:g} deg, mu = {mu:g}: slide acceleration {closed.slide_accel:.3f} m/s^2, "
                              f"|closed form - ODE| = {abs(closed.landing_time - ode.landing_time):.1e} s")


def test_sticking_is_found_by_both_implementations_at_the_same_distance(record_property):
    """mu = 1.5 at 15 deg: closed form and ODE both report sticking, stopping distances within 1e-6 mm."""
    physics = Physics(0.6, G, 17.5, 1.5)
    with pytest.raises(SeedlingSticks) as closed:
        landing(15.0, TUBE_I, physics)
    with pytest.raises(SeedlingSticks) as ode:
        simulate(15.0, TUBE_I, physics)
    assert closed.value.stops_after_mm == pytest.approx(ode.value.stops_after_mm, abs=1e-6)
    assert closed.value.stops_after_mm < closed.value.wall_mm
    # drag-free check of the stopping distance: v0^2 / (2 |a|)
    assert stopping_distance(2.0, -3.0, 0.0) == pytest.approx(4.0 / 6.0, rel=1e-15)
    record_property("figure", f"stops after {closed.value.stops_after_mm:.4f} mm of a {closed.value.wall_mm:.1f} mm "
                              f"wall (ODE: {ode.value.stops_after_mm:.4f} mm)")


def _exit_speed_sq(delta_deg: float, tube: Tube, physics: Physics) -> float:
    """v3a^2 in closed form, written out here apart from drag.py: free fall from rest over h1 with drag,
    v1^2 = (g / k)(1 - exp(-2 k h1)); the impact keeps v1 sin d; on the wall d(v^2)/ds = 2a - 2k v^2, so
    v3^2 = a / k + (v2^2 - a / k) exp(-2 k s1) with a = g (sin d - mu cos d), s1 = L3 / cos d."""
    d, g, k = math.radians(delta_deg), physics.gravity, physics.kappa
    h1 = physics.height - tube.below_wall - tube.l3 * math.tan(d)
    v2_sq = (g / k) * -math.expm1(-2 * k * h1) * math.sin(d) ** 2
    a, s1 = g * (math.sin(d) - physics.mu * math.cos(d)), tube.l3 / math.cos(d)
    return a / k + (v2_sq - a / k) * math.exp(-2 * k * s1)


def test_check_of_a_sticking_wall_fails_its_rules_and_writes_the_result(tmp_path):
    """mu = 1.5, tube I at 15 deg (tan 15 deg < mu): the seedling stops on the wall.  `check` evaluates and fails the
    design (exit 1, check's contract: it exited 3 and wrote nothing): tube I never reaches its wall end, the landing
    time spread does not exist, both say where the seedling sticks, and tube II's rules (41 deg: a decelerating slide
    that still ends on the wall's end) are evaluated, matching the closed form written out here."""
    from synthesis.kinds.guide_tube.check import FINE
    from synthesis.kinds.guide_tube.scene import GuideTubeScene
    from synthesis.spec import load_spec

    path = _sticking_spec(tmp_path)
    proc = agrisynth("check", str(path), "--out", str(tmp_path), cwd=tmp_path, timeout=120)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    assert "violated: landing_time_spread, wall_exit_speed_I" in " ".join(proc.stdout.split())
    data = json.loads((tmp_path / "cai2020_tubes-check" / "result.json").read_text(),
                      parse_constant=lambda c: pytest.fail(f"{c} in result.json"))
    rules = {r["name"]: r for r in data["rules"]}
    assert list(rules) == ["landing_time_spread", "wall_exit_speed_I", "free_fall_height_I", "wall_exit_speed_II",
                           "free_fall_height_II"]
    spread = rules["landing_time_spread"]
    assert spread["value"] is None and not spread["satisfied"]
    assert ("at row spacing 230 mm the seedling sticks on the wall of tube I: at wall angle 15 deg with friction "
            "coefficient mu = 1.5") in spread["note"]
    assert data["facts"]["sticks"] == spread["note"] and "tubes" not in data["facts"]
    wall = rules["wall_exit_speed_I"]          # it never reaches the wall end: failed, whatever the limit
    assert wall["value"] is None and not wall["satisfied"] and "(it never reaches the wall end)" in wall["note"]
    # the evaluated rules against the closed form above, over the design spacing and the 10x finer row-spacing grid
    spec = load_spec(path).model
    scene = GuideTubeScene.from_spec(spec)
    spacings = [scene.rows.design_spacing] + scene.spacing_grid(FINE * spec.solver.samples)
    tubes = [[scene.tube(k, w) for w in spacings] for k in range(2)]
    assert min(_exit_speed_sq(15.0, t, scene.physics) for t in tubes[0]) < 0            # it sticks, at every spacing
    v_exit = min(math.sqrt(_exit_speed_sq(41.0, t, scene.physics)) for t in tubes[1])
    assert rules["wall_exit_speed_II"]["value"] == pytest.approx(v_exit, rel=1e-9)
    assert rules["wall_exit_speed_II"]["satisfied"]
    for k, delta in ((0, 15.0), (1, 41.0)):
        h1 = min(600 - 1000 * (t.below_wall + t.l3 * math.tan(math.radians(delta))) for t in tubes[k])
        assert rules[f"free_fall_height_{('I', 'II')[k]}"]["value"] == pytest.approx(h1, rel=1e-12)
    assert (tmp_path / "cai2020_tubes-check" / "report.html").exists()


def _sticking_spec(tmp_path: Path) -> Path:
    """The baseline with mu = 1.5 and tube I at 15 deg: its seedling stops on the wall at every row spacing."""
    text = BASELINE.read_text()
    i, j = text.index("[friction.calibrate]"), text.index("[rows]")
    text = (text[:i] + "[friction]\nmu = 1.5\n\n" + text[j:]).replace("\nangle = 45\n", "\nangle = 15\n", 1)
    path = tmp_path / "sticks.toml"
    path.write_text(text)
    return path


def test_tolerance_of_a_sticking_wall_fails_the_design_and_writes_the_result(tmp_path):
    """`agrisynth tolerance` of the sticking design exited 3 ("solver failure") with nothing written: the NLP has no
    sticking, so the derivatives existed, but the nominal float re-check raised.  Now it is a design that fails
    its rules (exit 1): the nominal table is check's, the rules that cannot be evaluated have no stack-up (their
    NLP numbers, a NaN among them, describe a motion the design does not make), and the evaluated ones do: the free
    fall of tube I, h1 = 600 - 1000 (below_wall + l3 tan delta), loses 1000 l3 sec^2(delta) * 0.5 deg at its worst."""
    from synthesis.kinds.guide_tube.check import FINE, rules_even_if_stuck
    from synthesis.kinds.guide_tube.scene import GuideTubeScene
    from synthesis.spec import load_spec

    path = _sticking_spec(tmp_path)
    proc = agrisynth("tolerance", str(path), "--length", "0.1", "--angle", "0.5", "--samples", "20", "--out",
                     str(tmp_path), cwd=tmp_path, timeout=120)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    data = json.loads((tmp_path / "cai2020_tubes-tolerance" / "result.json").read_text(),
                      parse_constant=lambda c: pytest.fail(f"{c} in result.json"))
    assert "not_finite" not in data
    spec = load_spec(path).model
    scene = GuideTubeScene.from_spec(spec)
    grid = scene.spacing_grid(FINE * spec.solver.samples)
    expected, _ = rules_even_if_stuck(scene, spec.given_angles(), grid, spec.rules)
    nominal = {r["name"]: r for r in data["rules"] if "@" not in r["name"] and r["name"] != "monte_carlo_evaluable"}
    assert [(r.name, r.value) for r in (q.record() for q in expected)] == [(n, r["value"]) for n, r in nominal.items()]
    assert not nominal["landing_time_spread"]["satisfied"] and not nominal["wall_exit_speed_I"]["satisfied"]
    rows = {r["name"]: r for r in data["facts"]["tolerance"]["stack_up"]}
    for name in ("landing_time_spread", "wall_exit_speed_I"):
        assert rows[name]["linear_worst_margin"] is None and rows[name]["drivers"] == []
        assert rows[name]["gap_explanation"].startswith("not compared: the rule is not evaluated at the design (at row "
                                                        "spacing 230 mm the seedling sticks on the wall of tube I")
    spacings = [scene.rows.design_spacing] + grid
    tubes = [scene.tube(0, w) for w in spacings]
    delta = math.radians(15.0)
    h1 = [600 - 1000 * (t.below_wall + t.l3 * math.tan(delta)) for t in tubes]
    worst = int(np.argmin(h1))
    loss = 1000 * tubes[worst].l3 / math.cos(delta) ** 2 * math.radians(0.5)
    assert rows["free_fall_height_I"]["linear_worst_margin"] == pytest.approx(h1[worst] - loss, rel=1e-9)


def test_a_seedling_stuck_off_the_design_spacing_fails_the_check_whatever_the_exit_speed_limit(tmp_path):
    """An independent review's case: mu = 0.3, tube I at 15 deg, designed at 290 mm, min_exit_speed = 0 and a loose
    time spread.  The seedling sticks at 230-250 mm and lands at 270-290 mm: the landing-time spread (at 290 mm) is
    evaluated and holds, and the wall-exit rule read 0 m/s >= 0, so `check` said every rule satisfied (exit 0)."""
    text = BASELINE.read_text()
    i, j = text.index("[friction.calibrate]"), text.index("[rows]")
    text = text[:i] + "[friction]\nmu = 0.3\n\n" + text[j:]
    for old, new in (("\nangle = 45\n", "\nangle = 15\n"), ("design_spacing = 230 ", "design_spacing = 290 "),
                     ("max_time_spread = 0.001 ", "max_time_spread = 1 "), ("min_exit_speed = 0.05 ", "min_exit_speed = 0 ")):
        assert old in text
        text = text.replace(old, new, 1)
    path = tmp_path / "stuck_off_design.toml"
    path.write_text(text)
    proc = agrisynth("check", str(path), "--out", str(tmp_path), cwd=tmp_path, timeout=120)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    rules = {r["name"]: r for r in json.loads((tmp_path / "cai2020_tubes-check" / "result.json").read_text())["rules"]}
    assert rules["landing_time_spread"]["satisfied"]                  # at 290 mm both seedlings land
    wall = rules["wall_exit_speed_I"]
    assert not wall["satisfied"] and wall["value"] is None
    assert wall["note"].startswith("at row spacing 230 mm the seedling sticks on the wall of tube I")
    assert rules["wall_exit_speed_II"]["satisfied"] and rules["wall_exit_speed_II"]["value"] > 0


# --- steep drag and long falls -----------------------------------------------------------------------------

@pytest.mark.parametrize("terminal_speed", [0.5, 1.0, 2.0, 5.0])
@pytest.mark.parametrize("tube, delta", [(TUBE_I, 45.0), (TUBE_II, 30.0)], ids=["I", "II"])
def test_steep_drag_closed_form_matches_the_ode(tube, delta, terminal_speed, record_property):
    """mu = 0.3, steep drag: landing time within 1e-9 s of the ODE (DOP853 at 1e-12)."""
    physics = Physics(0.6, G, terminal_speed, 0.3)
    closed = landing(delta, tube, physics)
    ode = simulate(delta, tube, physics)
    assert abs(closed.landing_time - ode.landing_time) < 1e-6
    assert abs(closed.landing_time - ode.landing_time) < 1e-9             # what DOP853 at 1e-12 gives
    record_property("figure", f"tube {tube.name} at {delta:g} deg, v_L = {terminal_speed:g} m/s: landing "
                              f"{closed.landing_time:.5f} s, |closed form - ODE| = "
                              f"{abs(closed.landing_time - ode.landing_time):.1e} s")


#: the extreme-case table: terminal speeds v_L (m/s, 0.5 = steep drag .. 1e4 = almost none) against slide
#: coefficients A = sqrt(sin d - mu cos d) at d = 40 deg, from near sticking to mu = 0 (A = sqrt(sin 40 deg)
#: = 0.80, the largest a wall at 40 deg allows; A = 1 is the free fall of eq 19 and 21, part of every landing)
TABLE_SPEEDS = [0.5, 2.0, 17.5, 1e2, 1e3, 1e4]
TABLE_A = [1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1e-1, 0.5, math.sqrt(math.sin(math.radians(40.0)))]


@pytest.mark.parametrize("terminal_speed", TABLE_SPEEDS)
def test_closed_form_against_the_ode_over_drag_and_slide(terminal_speed, record_property):
    """Landing time of tubes I and II at 40 deg, closed form (drag.py) against the ODE (DOP853 at 1e-12),
    for A from 1e-10 to 0.80 at this v_L: |difference| < 1e-9 s everywhere (below A ~ 1e-8, A^2 is under
    the rounding of sin d - mu cos d: those rows are the a -> 0 limit, where the closed form has no 1/A)."""
    worst, times = 0.0, []
    for tube in (TUBE_I, TUBE_II):
        for A in TABLE_A:
            physics = physics_with_a_sq(40.0, A * A, terminal_speed)
            closed, ode = landing(40.0, tube, physics), simulate(40.0, tube, physics)
            assert math.isfinite(closed.landing_time)
            gap = abs(closed.landing_time - ode.landing_time)
            assert gap < 1e-9, (tube.name, A)
            worst = max(worst, gap)
            times.append(closed.landing_time)
    record_property("figure", f"v_L = {terminal_speed:g} m/s, A = 1e-10 .. 0.80, tubes I and II: landing "
                              f"{min(times):.4f} .. {max(times):.4f} s, max |closed form - ODE| = {worst:.1e} s")


@pytest.mark.parametrize("height", [0.6, 10.0, 1e3, 1e5])
def test_long_fall_at_terminal_speed_has_no_overflow(height, record_property):
    """From rest, h = (v_L^2/g) ln cosh(g t / v_L): t = (v_L/g) [g h / v_L^2 + ln(1 + sqrt(1 - exp(-2 g h / v_L^2)))],
    written without exp(+...); at v_L = 0.5 m/s the exponent 2 g h / v_L^2 reaches 7.8e6."""
    vl = 0.5
    kappa = G / vl ** 2
    t, v = traverse(0.0, G, kappa, height)
    x = G * height / vl ** 2
    expected = vl / G * (x + math.log1p(math.sqrt(-math.expm1(-2 * x))))
    assert t == pytest.approx(expected, rel=1e-13)
    assert v == pytest.approx(vl * math.sqrt(-math.expm1(-2 * x)), rel=1e-15)
    record_property("figure", f"h = {height:g} m at v_L = 0.5 m/s (exponent {2 * x:.1e}): t = {t:.6g} s, "
                              f"v = {v:.6g} m/s, within 1e-13 of the closed form")


# --- zero drag: v_L -> infinity -------------------------------------------------------------------------------

def textbook(delta_deg: float, tube: Tube, mu: float, height: float = 0.6) -> float:
    """Drag-free kinematics: s = v0 t + a t^2 / 2 for each phase."""
    d = math.radians(delta_deg)
    h1 = height - tube.below_wall - tube.l3 * math.tan(d)
    t1 = math.sqrt(2 * h1 / G)
    v2 = G * t1 * math.sin(d)
    a = G * (math.sin(d) - mu * math.cos(d))
    s1 = tube.l3 / math.cos(d)
    t2 = (math.sqrt(v2 * v2 + 2 * a * s1) - v2) / a
    u = (v2 + a * t2) * math.sin(d)
    t3 = (math.sqrt(u * u + 2 * G * tube.below_wall) - u) / G
    return t1 + t2 + t3


@pytest.mark.parametrize("tube, delta, mu", [(TUBE_I, 45.0, 0.6), (TUBE_II, 41.0, 0.6), (TUBE_II, 25.0, 0.6)])
def test_zero_drag_limit_is_the_textbook_kinematics(tube, delta, mu, record_property):
    """v_L = inf: the textbook kinematics within 1e-13 s (closed form) and 1e-10 s (ODE); the drag effect
    falls as 1 / v_L^2 (2 % on the ratio) from 1e2 to 1e4 m/s."""
    exact = textbook(delta, tube, mu)
    assert landing(delta, tube, Physics(0.6, G, math.inf, mu)).landing_time == pytest.approx(exact, abs=1e-13)
    assert simulate(delta, tube, Physics(0.6, G, math.inf, mu)).landing_time == pytest.approx(exact, abs=1e-10)
    # approaching the limit continuously (drag effect ~ 1 / v_L^2)
    gaps = [abs(landing(delta, tube, Physics(0.6, G, vl, mu)).landing_time - exact) for vl in (1e2, 1e3, 1e4)]
    assert gaps[1] == pytest.approx(gaps[0] / 100, rel=0.02) and gaps[2] == pytest.approx(gaps[1] / 100, rel=0.02)
    record_property("figure", f"tube {tube.name} at {delta:g} deg: {exact:.6f} s; drag effect at v_L = 1e2, 1e3, 1e4 "
                              f"m/s: {gaps[0]:.1e}, {gaps[1]:.1e}, {gaps[2]:.1e} s")


def test_relaxation_length_series_meets_the_closed_form():
    x_star = drag.X_SERIES / 2       # kappa s at the switch
    below = float(drag.relaxation_length(x_star * (1 - 1e-9), 1.0))
    above = float(drag.relaxation_length(x_star * (1 + 1e-9), 1.0))
    assert above == pytest.approx(below, rel=1e-12)
    assert float(drag.relaxation_length(0.0, 0.25)) == 0.5


def test_solve_whose_angle_range_only_sticks_exits_3_naming_tube_angle_and_mu(tmp_path):
    source = (ROOT / "problems" / "guide_tube" / "cai2020_delta2.toml").read_text()
    i, j = source.index("[friction.calibrate]"), source.index("[rows]")
    text = source[:i] + "[friction]\nmu = 1.5\n\n" + source[j:]
    text = text.replace("angle = { init = 41, bounds = [25, 70] }", "angle = { init = 12, bounds = [10, 15] }")
    path = tmp_path / "sticks.toml"
    path.write_text(text)
    proc = agrisynth("solve", str(path), "--out", str(tmp_path), "--workers", "1", cwd=tmp_path, timeout=120)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    message = " ".join(proc.stderr.split())
    assert "the seedling sticks on the wall of tube II: at wall angle" in message
    assert "with friction coefficient mu = 1.5" in message
    assert "Traceback" not in proc.stderr
