"""Toggle and Grashof-limit cases of the crank-rocker (the extreme-case matrix).

Change-point crank-rocker: crank 54, coupler 107.6, rocker 86.4, frame 140 mm, so crank + frame =
coupler + rocker (s + l = p + q exactly, "frame" slack 0).  At crank angle pi the coupler and the
rocker lie in one line (the toggle): transmission angle 180 deg (acute 0).  Grashof limit: crank 50,
coupler 100, rocker 80 + eps, frame 70 mm (crank + coupler = rocker + frame at eps = 0; all values
exact in binary).  Each test records its figure for bench.md (``record_property("figure", ...)``).
"""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from synthesis.constraints.grashof import grashof_rule
from synthesis import kinds
from synthesis.kinematics.rocker_drive import CrankRocker, acute, rocker_curve, transmission_angles_deg
from synthesis.spec import load_spec

ROOT = Path(__file__).resolve().parents[2]
SYNTHESIS = ROOT / "problems" / "picker" / "cai2020_crank_rocker_synthesis.toml"
TOGGLE = (54.0, 107.6, 86.4, 140.0)            # l7 crank, l8 coupler, l9 rocker, l10 frame (mm)
PUBLISHED = {"l7": 54.04, "l8": 107.63, "l9": 133.47}   # seed 001 §2.1.3 (the library spec's optimum)


def toggle_spec(tmp_path: Path, l9: float, fixed: bool) -> Path:
    """The library synthesis spec with the links at the change-point lengths (fixed: a check; else inits)."""
    text = SYNTHESIS.read_text()
    for name, old, value in (("l7", "l7 = { init = 50.0, bounds = [5.0, 200.0] }", TOGGLE[0]),
                             ("l8", "l8 = { init = 120.0, bounds = [5.0, 400.0] }", TOGGLE[1]),
                             ("l9", "l9 = { init = 120.0, bounds = [5.0, 400.0] }", l9)):
        assert old in text
        bounds = old.split("bounds = ")[1].rstrip(" }")
        text = text.replace(old, f"{name} = {value!r}" if fixed else f"{name} = {{ init = {value!r}, bounds = {bounds} }}")
    path = tmp_path / "toggle.toml"
    path.write_text(text)
    return path


def test_positions_continuous_through_the_toggle(record_property):
    """Change-point crank-rocker driven through its toggle (crank angle pi): the coupler-rocker joint
    moves continuously (within 1e-3 mm for a 1e-6 rad step either side), the transmission angle on a
    3600-sample turn has no NaN and reaches 0 deg (acute) within 1e-6 deg."""
    cr = CrankRocker(*TOGGLE)
    assert cr.grashof_slacks()["frame"] == 0.0
    at = rocker_curve(cr, np.array([math.pi]))
    step = [float(np.hypot(*(rocker_curve(cr, np.array([math.pi + d]))["tip"][:, 0] - at["tip"][:, 0])))
            for d in (-1e-6, 1e-6)]
    assert np.all(np.isfinite(at["tip"])) and max(step) < 1e-3
    mu = transmission_angles_deg(cr, 3600)
    assert not np.isnan(mu).any()
    assert acute(mu).min() == pytest.approx(0.0, abs=1e-6)
    # the rocker's velocity ratio is infinite exactly at the toggle (the position has a square-root cusp)
    assert math.isinf(float(at["dbeta"][0]))
    record_property("figure", f"joint moves {max(step):.2g} mm for 1e-6 rad; min transmission angle "
                              f"{acute(mu).min():.2g} deg; 0 NaN of 3600")


def test_near_toggle_transmission_angle_reported(tmp_path, record_property):
    """`check` of the change-point design with the rocker 1e-6 mm longer (the crank just turns): the
    minimum transmission angle is reported as a number below 0.2 deg (rule violated, no NaN); at the
    change point itself the Grashof rule holds with margin 0 and the turn rules say why they are not
    evaluated (a change point: at its toggle the linkage can go on either way) instead of a number, not that the
    crank cannot turn, which the rule's margin 0 contradicts."""
    near = kinds.checker("crank_rocker")(load_spec(toggle_spec(tmp_path, TOGGLE[2] + 1e-6, fixed=True)))
    mu = next(r for r in near.rules if r["name"] == "min_transmission_angle")
    assert mu["value"] is not None and math.isfinite(mu["value"]) and 0.0 <= mu["value"] < 0.2
    assert not mu["satisfied"]
    at = kinds.checker("crank_rocker")(load_spec(toggle_spec(tmp_path, TOGGLE[2], fixed=True)))
    rules = {r["name"]: r for r in at.rules}
    assert rules["grashof_crank_rocker"]["satisfied"] and rules["grashof_crank_rocker"]["margin"] == 0.0
    assert rules["min_transmission_angle"]["value"] is None
    assert "at a change point" in rules["min_transmission_angle"]["note"]
    assert "cannot make a full turn" not in rules["min_transmission_angle"]["note"]
    record_property("figure", f"min transmission angle {mu['value']:.3g} deg at 1e-6 mm from the change point; "
                              "at it: Grashof margin 0, turn rules not evaluated (a change point)")


def test_solve_started_at_the_toggle(tmp_path, record_property):
    """A solve whose start is the change-point (toggle) design converges to the library optimum
    (seed 001's published lengths within 0.01 mm)."""
    import sys

    sys.path.insert(0, str(ROOT / "tests"))
    from solving import run_solve

    result, reports, _ = run_solve(load_spec(toggle_spec(tmp_path, TOGGLE[2], fixed=False)), starts=1, workers=1)
    assert result.status == "optimal"
    for name, value in PUBLISHED.items():
        assert result.design[name] == pytest.approx(value, abs=0.01)
    record_property("figure", f"{reports[0].outcome.return_status} in {reports[0].outcome.iterations} iterations "
                              f"from the toggle start; l7 {result.design['l7']:.3f} mm")


@pytest.mark.parametrize("eps", [0.0, 1e-9, -1e-9])
def test_grashof_limit(eps, record_property):
    """s + l = p + q exactly and 1e-9 mm either side: the Grashof rule's value is the slack itself
    (0, +1e-9, -1e-9 within 2e-14 mm, the rounding of 80 + eps; satisfied for eps >= 0: the classification flips only at 0,
    never by rounding), its NLP
    rows are linear (the same Jacobian at all three points), and the kinematics give no NaN on a
    3600-sample turn where the crank turns (eps >= 0)."""
    l7, l8, l9, l10 = 50.0, 100.0, 80.0 + eps, 70.0
    x = ca.SX.sym("x", 4)
    rule = grashof_rule(x[3], x[0], x[1], x[2])
    value = float(ca.Function("v", [x], [rule.expr])([l7, l8, l9, l10]))
    record = grashof_rule(l10, l7, l8, l9).record()           # the numeric rule, as `check` evaluates it
    assert record.satisfied == (eps >= 0) and record.value == pytest.approx(eps, abs=2e-14)
    rows = ca.vertcat(*[r[0] for r in rule.nlp_rows])
    jac = np.asarray(ca.Function("j", [x], [ca.jacobian(rows, x)])([l7, l8, l9, l10]))
    assert value == pytest.approx(eps, abs=2e-14)
    assert np.array_equal(jac, np.asarray(ca.Function("j", [x], [ca.jacobian(rows, x)])([50.0, 100.0, 80.0, 70.0])))
    cr = CrankRocker(l7, l8, l9, l10)
    assert cr.crank_turns() == (eps > 0)
    mu = transmission_angles_deg(cr, 3600)
    nan = int(np.isnan(mu).sum())
    if eps >= 0:
        assert nan == 0
    record_property("figure", f"rule value {value:.3g} mm, crank turns {cr.crank_turns()}, "
                              f"{nan} NaN of 3600 transmission samples"
                              + (" (beyond the limit the loop does not close near the toggle: the check "
                                 "does not evaluate these, see the turn rules' note)" if nan else ""))
