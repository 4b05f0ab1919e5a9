"""The parts of the kind(s) of synthesis/kinds/guide_tube/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.guide_tube.check import headline, run_check
from synthesis.kinds.guide_tube.coarse import COARSE
from synthesis.kinds.guide_tube.plots import compare_figures, drop_profile_figure, drop_times_figure, sensitivity_figure
from synthesis.kinds.guide_tube.solve import SOLVING
