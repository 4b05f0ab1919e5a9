"""The parts of the kind(s) of synthesis/kinds/combing_chain/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.combing_chain.check import headline, run_check
from synthesis.kinds.combing_chain.coarse import COARSE
from synthesis.kinds.combing_chain.plots import compare_figure, delta_figure
from synthesis.kinds.combing_chain.solve import SOLVING
