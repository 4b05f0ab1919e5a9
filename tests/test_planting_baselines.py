"""The four published designs of seed 000: Grashof class, the paper's speed findings, library specs."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from conftest import PLANTING, TABLE1, arm, motion
from synthesis.kinematics.fourbar import crank_rotation_slacks
from synthesis.kinds.planting.placement import suggest_seedbed
from synthesis.kinds.planting.scene import PlantingScene, Seedbed, find_precision_points
from synthesis.kinds.planting.kinematics import tip_state
from synthesis.spec import load_spec

TWO_PI = 2 * math.pi


def test_all_published_designs_are_grashof_crank_rockers(example):
    l1, l2, l3, l4 = TABLE1[example][:4]
    lengths = sorted((l1, l2, l3, l4))
    assert l2 == lengths[0]                                   # the crank is the shortest link
    assert lengths[0] + lengths[3] < lengths[1] + lengths[2]  # s + l < p + q
    assert min(crank_rotation_slacks(l1, l2, l3, l4).values()) > 0


def _depth_and_p4p6(example: int, forward_m_s: float) -> tuple[float, float]:
    m = motion(forward_m_s)
    scene = PlantingScene(arm(example), m, Seedbed((0.0, 1e3), 0.0, 22.0, 110.0), None, 25.0)
    pts = find_precision_points(scene)
    t4, t5, t6 = pts.theta["P4"] - TWO_PI, pts.theta["P5"], pts.theta["P6"]
    s4, s5, s6 = (tip_state(scene.design, m, t) for t in (t4, t5, t6))
    x4 = s4.pos[0, 0] + m.forward * t4 / m.omega
    x6 = s6.pos[0, 0] + m.forward * t6 / m.omega
    assert s4.pos[1, 0] == pytest.approx(s6.pos[1, 0], abs=1e-9)   # P4 and P6 on one level
    return s4.pos[1, 0] - s5.pos[1, 0], abs(x6 - x4)


@pytest.mark.parametrize("example, lengthens", [(1, True), (2, False), (3, True), (4, True)])
def test_forward_speed_leaves_depth_and_moves_p4p6_as_the_paper_found(example, lengthens):
    """Seed 000 §5.3(2): depth unchanged; P4P6 longer for backward-tilting 1, 3, 4, shorter for 2."""
    depth_slow, p4p6_slow = _depth_and_p4p6(example, 0.50)
    depth_fast, p4p6_fast = _depth_and_p4p6(example, 0.75)
    assert depth_fast == pytest.approx(depth_slow, abs=1e-9)
    assert depth_slow == pytest.approx(25.0, abs=1e-9)
    # a change of at least 2 mm: the trend is real, not rounding
    assert (p4p6_fast - p4p6_slow > 2.0) if lengthens else (p4p6_slow - p4p6_fast > 2.0)


SPECS = sorted(PLANTING.glob("taiwan_example*.toml"))


@pytest.mark.parametrize("path", SPECS, ids=lambda p: p.stem)
def test_baseline_tray_placement_is_what_the_placement_rule_gives(path):
    spec = load_spec(path).model
    scene = PlantingScene.from_spec(spec)
    placed = suggest_seedbed(scene.design, scene.motion, spec.seedbed.seedling_height, spec.seedbed.thickness,
                             spec.soil.analysis_depth)
    assert spec.seedbed.x == pytest.approx(placed.x, abs=0.05)
    assert spec.seedbed.y == pytest.approx(placed.y, abs=0.05)
    assert spec.seedbed.tilt == pytest.approx(placed.tilt, abs=0.05)


def test_table1_values_are_in_the_library(example):
    spec = load_spec(PLANTING / f"taiwan_example{example}.toml").model
    values = spec.design_values()
    assert tuple(values[k] for k in ("l1", "l2", "l3", "l4", "l5", "zeta", "phi")) == TABLE1[example]
    assert "Table 1" in spec.source


@pytest.mark.slow
def test_planting_check_imports_no_other_mechanism(tmp_path):
    """The whole `agrisynth check` of a planting spec (rules, figures, report) in a fresh interpreter."""
    script = (
        "import sys\n"
        "from synthesis.cli import cli\n"
        "try:\n"
        f"    cli.main(['check', {str(PLANTING / 'taiwan_example1.toml')!r}, '--out', {str(tmp_path)!r}],"
        " standalone_mode=False)\n"
        "except SystemExit:\n"
        "    pass\n"
        "print('\\n'.join(sorted(sys.modules)))\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    modules = proc.stdout.split()
    assert "synthesis.kinds.planting.check" in modules
    foreign = ("synthesis.kinds.clamp_cam", "synthesis.kinds.guide_tube", "synthesis.kinds.picker", "synthesis.kinds.fourbar_path",
               "cvxpy", "distributed")     # ezdxf: the check writes linkage.dxf
    assert not [m for m in modules if m.startswith(foreign)]
