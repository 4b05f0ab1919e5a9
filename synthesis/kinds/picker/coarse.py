"""The pickers' checks on the studio's coarse grid: their grids are fixed in the kind (no [solver] sample count
reaches them), so they are evaluated as they are."""

from synthesis.core import coarse
from synthesis.kinds.picker.check import run_check
from synthesis.kinds.picker.combined import run_check as combined_run_check

DOUBLE_CRANK = coarse.one_grid(run_check)
PICKER = coarse.one_grid(combined_run_check)
