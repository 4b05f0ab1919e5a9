"""Seed 000's finite-difference scheme against exact AD values (the paper's §5.1 error study)."""

from __future__ import annotations

import pytest

from conftest import arm, motion
from synthesis.kinds.planting.finite_difference import mean_relative_errors


def test_chord_scheme_is_second_order_and_underestimates_speed():
    d, m = arm(1), motion()
    coarse = mean_relative_errors(d, m, 1.0, scheme="atan2")
    fine = mean_relative_errors(d, m, 0.2, scheme="atan2")
    # measured: 0.155 % and 0.0062 % (speed); halving-by-5 of the step divides the error by ~25
    assert coarse["speed_magnitude"] == pytest.approx(1.552e-3, rel=0.01)
    assert fine["speed_magnitude"] == pytest.approx(6.21e-5, rel=0.02)
    assert coarse["speed_magnitude"] / fine["speed_magnitude"] == pytest.approx(25.0, rel=0.05)
    # acceleration differentiates estimated velocities: measured ratio 18, still about second order
    assert 15.0 < coarse["acceleration_vector"] / fine["acceleration_vector"] < 30.0


def test_literal_arctan_directions_break_near_vertical_motion():
    # tan^-1 of a slope cannot tell up from down: the acceleration direction is wrong where the
    # claw moves near vertically, which no step size cures
    d, m = arm(1), motion()
    assert mean_relative_errors(d, m, 0.2, scheme="atan")["acceleration_vector"] > 0.3
