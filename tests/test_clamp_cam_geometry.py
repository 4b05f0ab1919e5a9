"""Motion laws and roller-follower geometry: AD against the hand-written derivatives, textbook
coefficients, the pressure angle against the instant-centre construction, curvature against
circles through neighbouring points, the optimised B-spline law's continuity."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from cam_reference import pole_pressure_angle_oscillating, pole_pressure_angle_translating, three_point_radius
from synthesis.kinds.clamp_cam.kinematics import cam_follower as cf
from synthesis.kinds.clamp_cam.kinematics.motion_laws import CLOSED_FORM, cycloidal, law

#: (C_v, C_a) of the normalised laws from the cam literature (e.g. Norton, Cam Design and
#: Manufacturing Handbook, Table 3-2): an independent source for our piece constants
TEXTBOOK = {"cycloidal": (2.0, 6.2832), "poly345": (1.875, 5.7735), "modified_trapezoid": (2.0, 4.8881),
            "modified_sine": (1.7596, 5.5280)}


@pytest.mark.parametrize("name", sorted(CLOSED_FORM))
def test_ad_of_each_law_matches_its_hand_derivatives(name):
    L = law(name)
    u = ca.SX.sym("u")
    f = ca.Function("d", [u], [ca.jacobian(L.s(u), u), ca.jacobian(L.v(u), u), ca.jacobian(L.a(u), u)])
    grid = np.linspace(0.0005, 0.9995, 1999)
    ad = np.array([np.asarray(f(x), dtype=float).ravel() for x in grid])
    assert np.max(np.abs(ad[:, 0] - L.v(grid))) < 1e-12
    assert np.max(np.abs(ad[:, 1] - L.a(grid))) < 1e-11
    assert np.max(np.abs(ad[:, 2] - L.j(grid))) < 1e-10


@pytest.mark.parametrize("name", sorted(CLOSED_FORM))
def test_laws_rise_from_rest_to_rest_with_textbook_coefficients(name):
    L = law(name)
    ends = np.array([0.0, 1.0])
    assert L.s(ends) == pytest.approx([0.0, 1.0], abs=1e-14)
    assert L.v(ends) == pytest.approx([0.0, 0.0], abs=1e-14)
    assert L.a(ends) == pytest.approx([0.0, 0.0], abs=1e-13)
    # continuity of s, v, a across the piece joints
    for p in L.pieces[1:]:
        left, right = p.u0 - 1e-12, p.u0 + 1e-12
        for fn in (L.s, L.v, L.a):
            assert fn(left) == pytest.approx(fn(right), abs=1e-9)
    cv, ca_ = TEXTBOOK[name]
    assert L.peaks["velocity"] == pytest.approx(cv, abs=1e-4)
    assert L.peaks["acceleration"] == pytest.approx(ca_, abs=1e-4)


def test_seed001_eq11_cycloidal_law_as_printed():
    """eq (11) without its r0 term: s = h (phi/Phi - sin(2 pi phi/Phi) / (2 pi)); the return mirrors it."""
    u = np.linspace(0, 1, 101)
    assert cycloidal().s(u) == pytest.approx(u - np.sin(2 * np.pi * u) / (2 * np.pi), abs=1e-15)


def _symbolic_pitch(follower_of_s, s_of_phi):
    """Pitch curve P(phi) = R(-phi) C(s(phi)) on a CasADi symbol, differentiated by AD."""
    phi = ca.SX.sym("phi")
    cx, cy = follower_of_s(s_of_phi(phi))
    px, py = ca.cos(phi) * cx + ca.sin(phi) * cy, -ca.sin(phi) * cx + ca.cos(phi) * cy
    p = ca.vertcat(px, py)
    dp = ca.jacobian(p, phi)
    return ca.Function("P", [phi], [p, dp, ca.jacobian(dp, phi)])


@pytest.mark.parametrize("follower", ["translating", "oscillating"])
def test_curvature_and_envelope_normal_match_ad_of_the_pitch_curve(follower):
    """The closed forms T, A (derivatives of the pitch curve rotated back) against CasADi AD of P(phi)."""
    beta, h = math.radians(50.0), (12.0 if follower == "translating" else math.radians(20.0))
    L = law("modified_sine")
    if follower == "translating":
        f = cf.Translating(40.0, 6.0)
        s0 = math.sqrt(40.0**2 - 36.0)
        geom = lambda s: (s0 + s, -6.0)  # noqa: E731
    else:
        f = cf.Oscillating(40.0, 90.0, 70.0, -1)
        psi0 = math.acos((90.0**2 + 70.0**2 - 40.0**2) / (2 * 90.0 * 70.0))
        geom = lambda s: (90.0 - 70.0 * ca.cos(psi0 + s), -70.0 * ca.sin(psi0 + s))  # noqa: E731
    P = _symbolic_pitch(geom, lambda phi: h * L.s(phi / beta))
    phis = np.linspace(0.01, beta - 0.01, 57)
    u = phis / beta
    c = cf.roller_centre(f, h * L.s(u), h * L.v(u) / beta, h * L.a(u) / beta**2)
    kappa = cf.pitch_curvature(c)
    px, py = cf.pitch_curve(c, phis)
    for k, phi in enumerate(phis):
        p, dp, ddp = (np.asarray(m, dtype=float).ravel() for m in P(phi))
        assert (px[k], py[k]) == pytest.approx(tuple(p), abs=1e-12)
        k_ad = (dp[0] * ddp[1] - dp[1] * ddp[0]) / np.hypot(*dp) ** 3
        assert -k_ad == pytest.approx(kappa[k], rel=1e-10, abs=1e-12)
    # and against circles through neighbouring points (no derivatives at all)
    d = 1e-4
    pts = [np.column_stack(cf.pitch_curve(cf.roller_centre(f, h * L.s(x), 0 * x, 0 * x), x * beta))
           for x in (u - d, u, u + d)]
    assert 1.0 / three_point_radius(*pts) == pytest.approx(kappa, rel=1e-5)


def test_translating_pressure_angle_closed_form_and_pole():
    """tan a = (s' - e) / (s0 + s), and the instant-centre construction, for an offset follower."""
    r0, e, h, beta = 45.0, 8.0, 15.0, math.radians(70.0)
    L = law("poly345")
    u = np.linspace(0, 1, 301)
    s, ds, dds = h * L.s(u), h * L.v(u) / beta, h * L.a(u) / beta**2
    alpha = np.degrees(cf.pressure_angle(cf.roller_centre(cf.Translating(r0, e), s, ds, dds)))
    s0 = math.sqrt(r0**2 - e**2)
    assert alpha == pytest.approx(np.degrees(np.arctan((ds - e) / (s0 + s))), abs=1e-12)
    assert np.abs(alpha) == pytest.approx(pole_pressure_angle_translating(s, ds, r0, e), abs=1e-9)


@pytest.mark.parametrize("side", [1, -1])
def test_oscillating_pressure_angle_closed_form_and_pole(side):
    """tan a = (l psi' - sigma (a cos(psi0 + psi) - l)) / (a sin(psi0 + psi)), and the pole construction."""
    r0, a, l, h, beta = 40.0, 100.0, 75.0, math.radians(18.0), math.radians(80.0)
    L = law("cycloidal")
    u = np.linspace(0, 1, 301)
    psi, dpsi, ddpsi = h * L.s(u), h * L.v(u) / beta, h * L.a(u) / beta**2
    alpha = np.degrees(cf.pressure_angle(cf.roller_centre(cf.Oscillating(r0, a, l, side), psi, dpsi, ddpsi)))
    g = math.acos((a**2 + l**2 - r0**2) / (2 * a * l)) + psi
    textbook = np.degrees(np.arctan((l * dpsi - side * (a * np.cos(g) - l)) / (a * np.sin(g))))
    assert alpha == pytest.approx(textbook, abs=1e-10)
    assert np.abs(alpha) == pytest.approx(pole_pressure_angle_oscillating(psi, dpsi, r0, a, l, side), abs=1e-7)


def test_optimised_law_is_c2_and_beats_cycloidal_acceleration():
    from synthesis.kinds.clamp_cam.bspline_law import fit_optimised_law

    law_ = fit_optimised_law(10.0, {"rise": 40.0, "return": 14.0}, 2 * math.pi, "acceleration")
    for spl in (law_.rise, law_.return_):
        # continuity with the dwells: rest at both ends to the acceleration (exact by construction)
        assert [spl.s(0.0), spl.v(0.0), spl.a(0.0)] == [0.0, 0.0, 0.0]
        assert spl.s(1.0) == pytest.approx(1.0, abs=1e-15)
        assert [spl.v(1.0), spl.a(1.0)] == pytest.approx([0.0, 0.0], abs=1e-12)
        # C2 across every interior knot (degree 5: C4 in fact)
        for knot in sorted(set(spl.knots))[1:-1]:
            for fn in (spl.s, spl.v, spl.a):
                assert fn(knot - 1e-10) == pytest.approx(fn(knot + 1e-10), abs=1e-6)
        u = np.linspace(0, 1, 4001)
        assert np.all(spl.v(u) >= -1e-9) and np.all((spl.s(u) >= -1e-9) & (spl.s(u) <= 1 + 1e-9))
    # lower peak acceleration than eq (11) for the same windows: C_a 4.1408 vs 2 pi (ratio 0.659)
    assert law_.ratio_to_cycloidal["rise"] == pytest.approx(0.65902, abs=2e-4)
    assert law_.rise.peaks["acceleration"] == pytest.approx(4.1408, abs=1e-3)
    # the ideal (discontinuous) minimum is the constant-acceleration law, C_a = 4: C2 costs ~3.5 %
    assert 4.0 < law_.rise.peaks["acceleration"] < 4.2


def test_optimised_jerk_law_beats_cycloidal_jerk():
    from synthesis.kinds.clamp_cam.bspline_law import fit_optimised_law

    law_ = fit_optimised_law(10.0, {"rise": 40.0, "return": 14.0}, 2 * math.pi, "jerk")
    # the ideal minimum-peak-jerk rise has C_j = 32 (constant-jerk law); cycloidal has 4 pi^2 = 39.48
    assert law_.rise.peaks["jerk"] == pytest.approx(32.0, abs=0.2)
    assert law_.ratio_to_cycloidal["rise"] == pytest.approx(32.0 / (4 * math.pi**2), abs=0.01)
