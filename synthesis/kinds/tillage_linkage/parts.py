"""The parts of the kind(s) of synthesis/kinds/tillage_linkage/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.tillage_linkage.check import headline, run_check
from synthesis.kinds.tillage_linkage.coarse import COARSE
from synthesis.kinds.tillage_linkage.export import write_linkage_dxf, write_paths_csv
from synthesis.kinds.tillage_linkage.plots import compare_figure, tillage_figure
from synthesis.kinds.tillage_linkage.solve import SOLVING
