"""Shared factories: the four published arms of seed 000 Table 1 and their spec files."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from synthesis.kinds.planting.kinematics import ArmDesign, Motion

ROOT = Path(__file__).resolve().parent.parent
LIBRARY = ROOT / "problems"
PLANTING = LIBRARY / "planting_arm"

#: seed 000 Table 1: L1..L5 (mm), zeta, phi (deg)
TABLE1 = {
    1: (75, 35, 75, 80, 191, -90, 31),
    2: (130, 40, 90, 88, 200, 41, 35),
    3: (74, 35, 70, 75, 177, -74, 49),
    4: (76, 37, 67, 65, 195, -71, 52),
}


def arm(example: int) -> ArmDesign:
    return ArmDesign(*TABLE1[example])


def motion(forward_m_s: float = 0.6, rpm: float = 250.0) -> Motion:
    return Motion(omega=rpm * 2 * math.pi / 60, forward=forward_m_s * 1000)


@pytest.fixture(params=sorted(TABLE1), ids=lambda k: f"example{k}")
def example(request) -> int:
    return request.param


def pytest_collection_modifyitems(items):
    """The tests marked ``long`` first, then the studies (``benchmark``, ``fuzz``: tens of seconds each), the rest
    after, each in its order: pytest-xdist hands tests out in this order, and a 50 s test begun late keeps one
    worker busy alone at the end of the run -- in ``pytest`` and in ``pytest -m 'slow or fuzz'`` alike."""
    def order(item) -> int:
        if item.get_closest_marker("long"):
            return 0
        return 1 if item.get_closest_marker("benchmark") or item.get_closest_marker("fuzz") else 2

    items.sort(key=order)

