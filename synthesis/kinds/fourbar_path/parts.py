"""The parts of the kind(s) of synthesis/kinds/fourbar_path/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.fourbar_path.check import headline, run_check, target_error_table
from synthesis.kinds.fourbar_path.coarse import COARSE
from synthesis.kinds.fourbar_path.export import write_linkage_dxf, write_paths_csv
from synthesis.kinds.fourbar_path.nlp import nominal_affine
from synthesis.kinds.fourbar_path.plots import compare_coupler_curves, coupler_curve_figure, linkage_animation
from synthesis.kinds.fourbar_path.poses import POSES
from synthesis.kinds.fourbar_path.solve import SOLVING
