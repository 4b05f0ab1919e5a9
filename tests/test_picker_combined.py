"""picker (seed 001 §2.1.3 + §2.3): the crank-rocker driving the double crank at 60 r/min.

The paper reports picking, dropping and picking again at 0, 0.44 and 1.0 s with zero clamp speed
there (Fig. 8b); here they come from the rocker's extreme positions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import LIBRARY
from synthesis.kinds.picker.kinematics.linkage import clamp_states
from synthesis.kinds.picker.combined import run_check
from synthesis.spec import load_spec

PICKER = LIBRARY / "picker"


@pytest.fixture(scope="module")
def result():
    return run_check(load_spec(PICKER / "cai2020_picker.toml"))


def test_instants_from_the_rocker_extremes(result):
    inst = result.extra["instants"]
    # quick stroke = (180 - theta) / 360 of a 1 s turn, theta = 20.004 deg for the printed lengths
    assert inst["picking"]["t"] == 0.0
    assert inst["dropping"]["t"] == pytest.approx(160.0 / 360.0, abs=1e-4)
    assert inst["dropping"]["t"] == pytest.approx(0.44, abs=0.005)          # printed to 0.01 s
    assert inst["picking_again"]["t"] == pytest.approx(1.0, abs=1e-12)
    for name in ("picking", "dropping", "picking_again"):
        assert inst[name]["speed_m_s"] < 1e-9
    # and the clamp does move in between: about 1 m/s at its fastest, during the holding stroke
    assert result.extra["peak_speed_m_s"] == pytest.approx(0.998, abs=0.002)
    assert 0.0 < result.extra["peak_speed_t"] < inst["dropping"]["t"]


def test_clamp_at_the_instants_is_the_double_crank_at_its_swing_ends(result):
    inst = result.extra["instants"]
    dc_spec = load_spec(PICKER / "cai2020_double_crank.toml").model
    from synthesis.kinds.picker.check import linkage
    dc = linkage(dc_spec)
    ends = clamp_states(dc, [50.0, 50.0 + 49.95063727523979])["M"]
    assert [inst["picking"]["x"], inst["picking"]["y"]] == pytest.approx(ends[:, 0], abs=1e-9)
    assert [inst["dropping"]["x"], inst["dropping"]["y"]] == pytest.approx(ends[:, 1], abs=1e-7)
    assert inst["picking"]["crank_ab_deg"] == pytest.approx(50.0, abs=1e-12)
    assert result.extra["crank_ab_range_deg"] == pytest.approx([50.0, 99.9506], abs=1e-3)


def test_trajectory_contract_and_velocity_by_ad(result):
    tr = result.trajectory
    assert tr["frame"] == "machine"
    assert {len(tr[k]) for k in ("t", "crank_deg", "x", "y", "vx", "vy", "ax", "ay")} == {361}
    t, x, y = (np.array(tr[k]) for k in ("t", "x", "y"))
    assert t[-1] == pytest.approx(1.0) and tr["crank_deg"][-1] == pytest.approx(360.0)
    assert (x[0], y[0]) == pytest.approx((x[-1], y[-1]), abs=1e-9)           # one full cycle
    # central differences of the sampled positions agree with the AD velocity and acceleration
    dt = t[1] - t[0]
    vx = (x[2:] - x[:-2]) / (2 * dt)
    vy = (y[2:] - y[:-2]) / (2 * dt)
    assert vx == pytest.approx(np.array(tr["vx"][1:-1]), abs=2.0)         # mm/s, O(dt^2) of ~1000 mm/s
    assert vy == pytest.approx(np.array(tr["vy"][1:-1]), abs=2.0)
    ax = (np.array(tr["vx"][2:]) - np.array(tr["vx"][:-2])) / (2 * dt)
    assert ax == pytest.approx(np.array(tr["ax"][1:-1]), abs=0.01 * np.abs(tr["ax"]).max())


def test_installation_angles(result):
    inst = result.extra["installation"]
    assert inst["theta1_computed_deg"] == pytest.approx(22.44, abs=0.01)      # printed theta1 = 22 deg
    assert inst["joint_angle_ab_minus_ae_deg"] == pytest.approx(6.06, abs=0.01)
    assert result.extra["holding"]["time_s"] < result.extra["holding"]["return_time_s"]
    assert result.all_satisfied
    frame0 = result.extra["frames"][0]["joints"]
    ag = math.degrees(math.atan2(frame0["G"][1] - frame0["A"][1], frame0["G"][0] - frame0["A"][0]))
    assert ag == pytest.approx(8.5, abs=1e-9)
    assert math.hypot(frame0["G"][0] - frame0["A"][0], frame0["G"][1] - frame0["A"][1]) == pytest.approx(140.0)
    assert math.hypot(frame0["E"][0] - frame0["A"][0], frame0["E"][1] - frame0["A"][1]) == pytest.approx(133.5)
    assert math.hypot(frame0["E"][0] - frame0["F"][0], frame0["E"][1] - frame0["F"][1]) == pytest.approx(107.6)


def test_instants_do_not_depend_on_which_extreme_is_picking(tmp_path):
    for part in ("cai2020_crank_rocker.toml", "cai2020_double_crank.toml"):
        (tmp_path / part).write_text((PICKER / part).read_text())
    text = (PICKER / "cai2020_picker.toml").read_text()
    text = text.replace('picking_extreme = "folded"', 'picking_extreme = "extended"').replace(
        "theta1 = 22.0 ", "theta1 = 72.4 ")          # G-A-E at the extended extreme: theta1 + psi of eq (9)
    (tmp_path / "extended.toml").write_text(text)
    other = run_check(load_spec(tmp_path / "extended.toml"))
    inst = other.extra["instants"]
    assert [inst[k]["t"] for k in ("picking", "dropping", "picking_again")] == pytest.approx([0.0, 160 / 360, 1.0],
                                                                                            abs=1e-4)
    assert max(inst[k]["speed_m_s"] for k in inst) < 1e-9
    assert other.extra["installation"]["theta1_computed_deg"] == pytest.approx(72.39, abs=0.01)
    assert other.all_satisfied


def test_published_instants_out_of_order_are_refused_at_load(tmp_path):
    """[published] instants = [0, 1.44, 1.0]: a drop after the next pick, past the 1 s period, was printed as the
    paper's number beside ours.  The part files are named by absolute path in the copy."""
    from synthesis.errors import SpecError

    text = (PICKER / "cai2020_picker.toml").read_text()
    for part in ("cai2020_crank_rocker.toml", "cai2020_double_crank.toml"):
        text = text.replace(f'"{part}"', f'"{PICKER / part}"', 1)
    spec = tmp_path / "late_drop.toml"
    spec.write_text(text.replace("instants = [0.0, 0.44, 1.0]", "instants = [0.0, 1.44, 1.0]", 1))
    with pytest.raises(SpecError, match=r"instants: \[0, 1.44, 1\] s must be picking, dropping, picking again in "
                                        r"that order"):
        load_spec(spec)
