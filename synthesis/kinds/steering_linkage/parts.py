"""The parts of the kind(s) of synthesis/kinds/steering_linkage/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.steering_linkage.check import headline, run_check
from synthesis.kinds.steering_linkage.coarse import COARSE
from synthesis.kinds.steering_linkage.export import write_linkage_dxf, write_paths_csv
from synthesis.kinds.steering_linkage.plots import compare_figure, steering_figure
from synthesis.kinds.steering_linkage.solve import SOLVING
