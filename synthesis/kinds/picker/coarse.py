"""The pickers' checks on the studio's coarse grid: their grids are fixed in the kind (no [solver] sample count
reaches them), so they are evaluated as they are."""

from synthesis.core import coarse

DOUBLE_CRANK = coarse.one_grid("synthesis.kinds.picker.check:run_check")
PICKER = coarse.one_grid("synthesis.kinds.picker.combined:run_check")
