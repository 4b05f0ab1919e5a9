"""The parts of the kind(s) of synthesis/kinds/guide_way/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.guide_way.check import explicit_design, headline, run_check
from synthesis.kinds.guide_way.coarse import COARSE
from synthesis.kinds.guide_way.export import write_centre_csv, write_dxf, write_walls_csv
from synthesis.kinds.guide_way.plots import animation, compare_figures, cycle_figure, guide_figure
from synthesis.kinds.guide_way.solve import SOLVING
