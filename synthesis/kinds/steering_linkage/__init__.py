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


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/steering_linkage/parts.py)."""
    from synthesis.kinds.steering_linkage import parts

    return parts


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
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"steering.png": _parts().steering_figure,
                "steering.svg": _parts().steering_figure,
                "paths.csv": _parts().write_paths_csv,
                "linkage.dxf": _parts().write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figure


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE


KIND = SteeringLinkage()

