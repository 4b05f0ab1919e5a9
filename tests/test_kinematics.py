"""Kinematics: loop closure, AD derivatives against the seed's complex-number formulas (eq. 4-7)."""

from __future__ import annotations

import cmath
import math

import casadi as ca
import numpy as np

from conftest import arm, motion
from synthesis.kinematics import fourbar
from synthesis.kinds.planting.kinematics import claw_tip, tip_derivatives, tip_state

ANGLES = np.linspace(0.0, 2 * np.pi, 360, endpoint=False)


def test_loop_closure_to_1e9_mm(example):
    d = arm(example)
    p = d.parameters()
    for th in ANGLES:
        (ax, ay), (bx, by) = fourbar.coupler_joint(th, d.l1, d.l2, d.l3, d.l4, p[5], d.branch)
        ox, oy = fourbar.rocker_pivot(d.l1, p[5])
        cx, cy = claw_tip(th, p, d.branch)
        assert abs(math.hypot(ax, ay) - d.l2) < 1e-9
        assert abs(math.hypot(bx - ax, by - ay) - d.l3) < 1e-9
        assert abs(math.hypot(bx - ox, by - oy) - d.l4) < 1e-9
        assert abs(math.hypot(cx - ax, cy - ay) - d.l5) < 1e-9
        # AC is AB turned clockwise by phi
        turn = cmath.phase(complex(cx - ax, cy - ay) / complex(bx - ax, by - ay))
        assert abs(turn + math.radians(d.phi)) < 1e-12


def _complex_number_derivatives(d, m, th):
    """Seed 000 eq. 4 (omega3), its companions for omega4 and alpha3, and eq. 3/7 for the tip.

    Written from the vector loop r2 e^{i t2} + r3 e^{i t3} = r1 e^{i t1} + r4 e^{i t4} with the
    angles read off the assembled positions; nothing here uses AD or the position formulas' form.
    """
    p = d.parameters()
    (ax, ay), (bx, by) = fourbar.coupler_joint(th, d.l1, d.l2, d.l3, d.l4, p[5], d.branch)
    ox, oy = fourbar.rocker_pivot(d.l1, p[5])
    t2 = math.atan2(ay, ax)
    t3 = math.atan2(by - ay, bx - ax)
    t4 = math.atan2(by - oy, bx - ox)
    w2 = m.omega
    r2, r3, r4, r5 = d.l2, d.l3, d.l4, d.l5
    w3 = -(r2 / r3) * w2 * math.sin(t4 - t2) / math.sin(t4 - t3)                    # eq. 4
    w4 = (r2 / r4) * w2 * math.sin(t2 - t3) / math.sin(t4 - t3)
    a3 = (-r2 * w2**2 * math.cos(t2 - t4) - r3 * w3**2 * math.cos(t3 - t4) + r4 * w4**2) / (r3 * math.sin(t3 - t4))
    e5 = cmath.exp(1j * (t3 - math.radians(d.phi)))
    v_a = 1j * w2 * r2 * cmath.exp(1j * t2)
    a_a = -(w2**2) * r2 * cmath.exp(1j * t2)
    v_c = v_a + 1j * w3 * r5 * e5                                                      # eq. 3
    a_c = a_a + (1j * a3 - w3**2) * r5 * e5                                            # eq. 7
    return v_c, a_c


def test_ad_velocity_and_acceleration_match_complex_number_formulas(example):
    d, m = arm(example), motion()
    st = tip_state(d, m, ANGLES)
    for k, th in enumerate(ANGLES):
        v_c, a_c = _complex_number_derivatives(d, m, th)
        v_ad = complex(*st.vel[:, k])
        a_ad = complex(*st.acc[:, k])
        assert abs(v_ad - v_c) <= 1e-9 * abs(v_c)
        assert abs(a_ad - a_c) <= 1e-9 * abs(a_c)


def test_same_function_on_floats_and_symbols():
    d = arm(1)
    p = d.parameters()
    on_floats = claw_tip(1.234, p, d.branch)
    assert all(isinstance(v, float) for v in on_floats)
    theta = ca.SX.sym("theta")
    f = ca.Function("f", [theta], [ca.vertcat(*claw_tip(theta, p, d.branch))])
    assert np.allclose(np.asarray(f(1.234)).ravel(), on_floats, rtol=0, atol=1e-12)
    assert np.allclose(np.asarray(tip_derivatives(d.branch)(1.234, p)[0]).ravel(), on_floats, atol=1e-12)


def test_assembly_height_is_zero_at_toggle_and_positions_stay_finite():
    # l1 + l2 = l3 + l4: the linkage reaches its extended toggle exactly at theta = pi
    l1, l2, l3, l4 = 75.0, 35.0, 50.0, 60.0
    assert abs(fourbar.assembly_height_sq(math.pi, l1, l2, l3, l4)) < 1e-9
    for dt in (1e-3, 1e-6, 1e-9):
        (a, b) = fourbar.coupler_joint(math.pi - dt, l1, l2, l3, l4, 0.0, -1)
        assert all(math.isfinite(v) for v in (*a, *b))
        assert abs(math.hypot(b[0] - a[0], b[1] - a[1]) - l3) < 1e-6
