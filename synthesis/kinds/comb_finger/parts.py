"""The parts of the kind(s) of synthesis/kinds/comb_finger/ that its Kind class hands out, in one module its
``_parts()`` imports on first use (listing kinds imports none of it; a run imports only its own kind)."""

from __future__ import annotations

from synthesis.kinds.comb_finger.check import headline, run_check
from synthesis.kinds.comb_finger.coarse import COARSE
from synthesis.kinds.comb_finger.plots import compare_figure, finger_figure
from synthesis.kinds.comb_finger.poses import POSES
from synthesis.kinds.comb_finger.solve import SOLVING
