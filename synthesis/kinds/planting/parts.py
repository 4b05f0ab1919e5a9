"""The parts of the kind(s) of synthesis/kinds/planting/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.planting.check import headline, result_tables, run_check
from synthesis.kinds.planting.coarse import COARSE
from synthesis.kinds.planting.compare_plots import animation_of_one, kinematics_of_one, linkage_of_one, overlay_figures
from synthesis.kinds.planting.export import write_linkage_dxf, write_paths_csv
from synthesis.kinds.planting.finite_difference import mean_relative_errors
from synthesis.kinds.planting.plots import trajectory_figure
from synthesis.kinds.planting.poses import POSES
from synthesis.kinds.planting.scene import PlantingScene
from synthesis.kinds.planting.solve import SOLVING
from synthesis.kinds.planting.spec import PlantingFourbarSpec
from synthesis.library import LIBRARY
from synthesis.spec import load_spec

#: seed 000 §5.1: mean errors of its central-difference scheme against the analytic values (speed, acceleration)
PRINTED_DERIVATIVE_ERRORS = {1.0: (1.48, 4.94), 0.2: (0.64, 1.49)}


def derivative_error_rows() -> list[dict]:
    """Seed 000's central-difference scheme (eq. 8-14) against CasADi's exact derivatives, production
    design of example 1 (Table 1), mean over 360 crank angles, at the paper's two steps; both the
    literal tan^-1 directions and quadrant-correct ones (:mod:`synthesis.kinds.planting.finite_difference`)."""
    spec = load_spec(LIBRARY / "planting_arm/taiwan_example1.toml").model
    assert isinstance(spec, PlantingFourbarSpec)
    scene = PlantingScene.from_spec(spec)
    rows = []
    for step, (speed_printed, acc_printed) in PRINTED_DERIVATIVE_ERRORS.items():
        for scheme in ("atan", "atan2"):
            e = mean_relative_errors(scene.design, scene.motion, step, scheme=scheme)
            rows.append({"design": "taiwan_example1", "step_deg": step, "scheme": scheme,
                         "speed_error_pct": 100 * e["speed_magnitude"],
                         "acceleration_magnitude_error_pct": 100 * e["acceleration_magnitude"],
                         "acceleration_vector_error_pct": 100 * e["acceleration_vector"],
                         "printed_speed_pct": speed_printed, "printed_acceleration_pct": acc_printed})
    return rows
