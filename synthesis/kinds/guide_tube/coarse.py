"""The guide tube's check on the studio's coarse grid: its grid is fixed in the kind (no [solver] sample count
reaches it), so it is evaluated as it is."""

from synthesis.core import coarse
from synthesis.kinds.guide_tube.check import run_check

COARSE = coarse.one_grid(run_check)
