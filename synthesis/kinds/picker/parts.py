"""The parts of the kind(s) of synthesis/kinds/picker/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.picker.check import combined_headline, headline, run_check
from synthesis.kinds.picker.coarse import DOUBLE_CRANK, PICKER
from synthesis.kinds.picker.combined import run_check as combined_run_check
from synthesis.kinds.picker.export import write_double_crank_csv, write_double_crank_dxf, write_picker_csv, write_picker_dxf
from synthesis.kinds.picker.nlp import COORDINATES
from synthesis.kinds.picker.plots import compare_figure, path_figure, picker_animation, picker_figure
from synthesis.kinds.picker.solve import SOLVING
from synthesis.report.trajectory_overlay import trajectory_overlay
