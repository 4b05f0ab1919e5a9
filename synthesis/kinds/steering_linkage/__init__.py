"""Kind steering_linkage: the Ackermann steering trapezoid of seed 002 (Hwang, Model-3 peanut combine, Table 12).

table12.py  the published table explained: kingpin spacing, the inconsistent row, the trapezoid fit, radius
check.py    rules on floats or symbols (one function), the given trapezoid over 0 .. the maximum lock
nlp.py      minimax steering error as a smooth epigraph, outer locks as variables closing the loop
solve.py    the solve side (SOLVING); plots.py the figures (from result data only)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


class SteeringLinkage(Kind):
    name = "steering_linkage"
    summary = "Ackermann steering trapezoid: Table 12 explained, minimax steering error (seed 002 Table 12)"
    objectives = {"min_max_error": "smallest largest |outside lock - Ackermann| over 0 .. the maximum inside lock, deg"}
    example = "steering/steering_redesign_40.toml"
    bench_specs = ("steering/steering_redesign_40.toml", "steering/steering_redesign_27.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.steering_linkage.spec import SteeringSpec

        return SteeringSpec

    def check(self, loaded: LoadedSpec) -> Result:
        from synthesis.kinds.steering_linkage.check import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.steering_linkage.check import headline

        return headline(result)

    def solving(self) -> Solving:
        from synthesis.kinds.steering_linkage.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.steering_linkage.export import write_linkage_dxf, write_paths_csv
        from synthesis.kinds.steering_linkage.plots import steering_figure

        return {"steering.png": steering_figure,
                "steering.svg": steering_figure,
                "paths.csv": write_paths_csv,
                "linkage.dxf": write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.steering_linkage.plots import compare_figure

        return compare_figure


    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.steering_linkage.coarse import COARSE

        return COARSE


KIND = SteeringLinkage()

