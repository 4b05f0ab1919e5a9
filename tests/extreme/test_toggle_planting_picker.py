"""Toggle cases of the planting arm and the picker's double crank (the extreme-case matrix; the crank-rocker's
are in test_toggle_grashof.py).  Each records its figure for bench.md (``record_property("figure", ...)``).

Planting arm (seed 000's four-bar, synthesis.kinds.planting.kinematics): frame l1 = OO', crank l2 = OA, coupler
l3 = AB, rocker l4 = O'B, crank angle theta from OO'.  The diagonal d = |O'A| has d^2 = l1^2 + l2^2 -
2 l1 l2 cos theta, largest at theta = pi: d = l1 + l2.  With l1 + l2 = l3 + l4 the triangle A-B-O' is flat
there (B on the segment AO', assembly height h2 = 0): coupler and rocker in one line, transmission angle
180 deg (acute 0) -- a change-point crank-rocker (s + l = 30 + 100 = p + q = 70 + 60).  Lengths
l1, l2, l3, l4 = 100, 30, 70, 60 mm (l5 = 150 mm, zeta = 0, phi = 20 deg, the library's branch -1); at its
smallest, d = l1 - l2 = 70 >= |l3 - l4| = 10, so the loop closes over the whole turn.

Picker double crank (seed 001, synthesis.kinds.picker.kinematics.linkage): crank l1 = AB, coupler l2 = BC, follower
l3 = CD, frame l4 = AD (shortest), crank angle phi1 from AD.  |DB|^2 = l4^2 + l1^2 - 2 l4 l1 cos phi1, largest at
phi1 = 180 deg: |DB| = l1 + l4.  With l1 + l4 = l2 + l3 the triangle B-C-D is flat there: transmission angle at
C 180 deg (acute 0), the frame still the shortest link (Grashof's frame slack 0: a change-point double crank).
Lengths l1, l2, l3, l4 = 80, 60, 50, 30 mm (l5 = 40 mm, phi3 = 10, phi4 = 30 deg, branch +1); at its smallest
|DB| = l1 - l4 = 50 >= |l2 - l3| = 10.

"Near" the toggle: the rocker / follower 1e-6 mm longer (l1 + l2 < l3 + l4 by 1e-6): the triangle never
flattens, the least transmission angle is small but positive (of order sqrt(1e-6 / l) rad), still no NaN.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from synthesis.kinematics.rocker_drive import acute
from synthesis.kinds.picker.kinematics.linkage import DoubleCrank, clamp_states, joint_positions as picker_joints
from synthesis.kinds.planting.kinematics import ArmDesign, joint_positions, link_angles
from synthesis.kinds.planting.scene import transmission_angles_deg

PLANTING = dict(l1=100.0, l2=30.0, l3=70.0, l4=60.0, l5=150.0, zeta=0.0, phi=20.0, branch=-1)
PICKER = dict(x_a=0.0, y_a=0.0, l1=80.0, l2=60.0, l3=50.0, l4=30.0, l5=40.0, phi3=10.0, phi4=30.0, branch=1)
STEP = 1e-6          # rad either side of the toggle
#: "continuous on the chosen branch": a joint moves O(step) for a crank step: at most this many mm per rad (the
#: lengths are <= 150 mm; a branch jump would move a joint by the height of the triangle, tens of mm)
MM_PER_RAD = 500.0
SAMPLES = 3600       # a turn in 0.1 deg steps: the toggle angle (pi) is one of them


def _moves(positions: dict[str, np.ndarray]) -> float:
    """Largest distance a joint moves between consecutive columns (mm)."""
    return max(float(np.max(np.hypot(*np.diff(np.asarray(p, float), axis=1)))) for p in positions.values())


def test_planting_arm_through_its_toggle(record_property):
    """Change-point planting arm driven through its toggle (theta = pi, l1 + l2 = l3 + l4): every joint (A, B,
    the claw tip C) moves at most 500 mm/rad x the step (O(step): 1e-6 rad either side, and every 0.1 deg step
    of a turn), no NaN on the turn, the assembly height h2 = 0 and the transmission angle 180 deg at the toggle
    (acute 0 within 1e-6 deg, the value `check`'s transmission rule reads: synthesis.kinds.planting.scene)."""
    d = ArmDesign(**PLANTING)
    at = link_angles(d, math.pi)
    assert abs(float(at["h2"][0])) < 1e-9 and math.degrees(float(at["mu"][0])) == pytest.approx(180.0, abs=1e-6)
    near = joint_positions(d, [math.pi - STEP, math.pi, math.pi + STEP])
    step_move = _moves({k: near[k] for k in ("A", "B", "C")})
    assert all(np.all(np.isfinite(near[k])) for k in near) and step_move <= MM_PER_RAD * STEP
    theta = np.linspace(0.0, 2 * math.pi, SAMPLES, endpoint=False)
    turn = joint_positions(d, theta)
    turn_move = _moves({k: turn[k] for k in ("A", "B", "C")})
    assert all(np.all(np.isfinite(turn[k])) for k in turn)
    assert turn_move <= MM_PER_RAD * (theta[1] - theta[0])
    mu = transmission_angles_deg(d, SAMPLES)
    assert not np.isnan(mu).any() and acute(mu).min() == pytest.approx(0.0, abs=1e-6)
    assert int(np.argmin(acute(mu))) == SAMPLES // 2                  # at theta = pi, where it was derived
    record_property("figure", f"joint moves {step_move:.2g} mm for 1e-6 rad at the toggle (largest on a 0.1 deg "
                              f"turn {turn_move:.3g} mm); min transmission angle {acute(mu).min():.2g} deg at "
                              f"theta = 180 deg; 0 NaN of {SAMPLES}")


def test_picker_double_crank_through_its_toggle(record_property):
    """Change-point picker double crank driven through its toggle (phi1 = 180 deg, l1 + l4 = l2 + l3): B, C and
    the clamp point M move O(step) (at most 500 mm/rad x 1e-6 rad either side, and on every 0.1 deg step of a
    turn), no NaN, the transmission angle at C 180 deg at the toggle (acute 0 within 1e-6 deg: the mu `check`
    reads, synthesis.kinds.picker.kinematics.linkage.clamp_states)."""
    dc = DoubleCrank(**PICKER)
    slacks = dc.grashof_slacks()
    assert slacks[0] == 0.0 and np.all(slacks >= 0.0)                 # frame slack 0: the change point
    near = [picker_joints(dc, 180.0 + math.degrees(s)) for s in (-STEP, 0.0, STEP)]
    step_move = _moves({k: np.array([p[k] for p in near]).T for k in ("B", "C", "M")})
    assert np.all(np.isfinite([p[k] for p in near for k in p])) and step_move <= MM_PER_RAD * STEP
    phi = np.linspace(0.0, 360.0, SAMPLES, endpoint=False)
    states = clamp_states(dc, phi)
    turn_move = _moves({"M": states["M"]})
    assert np.all(np.isfinite(states["M"])) and turn_move <= MM_PER_RAD * math.radians(phi[1] - phi[0])
    mu = states["mu"]
    assert not np.isnan(mu).any() and acute(mu).min() == pytest.approx(0.0, abs=1e-6)
    assert int(np.argmin(acute(mu))) == SAMPLES // 2                  # at phi1 = 180 deg
    record_property("figure", f"joint moves {step_move:.2g} mm for 1e-6 rad at the toggle (clamp point on a "
                              f"0.1 deg turn at most {turn_move:.3g} mm); min transmission angle at C "
                              f"{acute(mu).min():.2g} deg at phi1 = 180 deg; 0 NaN of {SAMPLES}")


@pytest.mark.parametrize("which", ["planting_arm", "picker_double_crank"])
def test_near_the_toggle(which, record_property):
    """The rocker (planting: l4) / follower (picker: l3) 1e-6 mm longer than the change point: the triangle
    never flattens, so the least transmission angle over a turn is a number in (0, 0.5) deg (reported small,
    not 0, not NaN) and every position is finite."""
    if which == "planting_arm":
        d = ArmDesign(**(PLANTING | {"l4": PLANTING["l4"] + 1e-6}))
        mu = transmission_angles_deg(d, SAMPLES)
        positions = joint_positions(d, np.linspace(0.0, 2 * math.pi, SAMPLES, endpoint=False))
        finite = all(np.all(np.isfinite(v)) for v in positions.values())
    else:
        states = clamp_states(DoubleCrank(**(PICKER | {"l3": PICKER["l3"] + 1e-6})),
                              np.linspace(0.0, 360.0, SAMPLES, endpoint=False))
        mu, finite = states["mu"], bool(np.all(np.isfinite(states["M"])))
    least = float(acute(mu).min())
    assert finite and not np.isnan(mu).any() and 0.0 < least < 0.5
    record_property("figure", f"{which}: least transmission angle {least:.3g} deg with the link 1e-6 mm past the "
                              f"change point; 0 NaN of {SAMPLES}")
