"""The parts of the kind(s) of synthesis/kinds/clamp_cam/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.clamp_cam.check import headline, run_check
from synthesis.kinds.clamp_cam.coarse import COARSE
from synthesis.kinds.clamp_cam.export import write_csv, write_dxf
from synthesis.kinds.clamp_cam.plots import compare_figure, motion_figure, profile_figure
from synthesis.kinds.clamp_cam.poses import POSES
from synthesis.kinds.clamp_cam.solve import SOLVING
