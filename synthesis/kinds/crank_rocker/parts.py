"""The parts of the kind(s) of synthesis/kinds/crank_rocker/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.crank_rocker.check import headline, run_check
from synthesis.kinds.crank_rocker.coarse import COARSE
from synthesis.kinds.crank_rocker.export import write_linkage_dxf, write_paths_csv
from synthesis.kinds.crank_rocker.nlp import COORDINATES
from synthesis.kinds.crank_rocker.plots import compare_figure, extremes_figure
from synthesis.kinds.crank_rocker.poses import POSES
from synthesis.kinds.crank_rocker.solve import SOLVING
