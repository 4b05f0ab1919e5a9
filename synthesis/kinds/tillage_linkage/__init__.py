"""Kind tillage_linkage: the distorted rotary tillage linkage of seed 002 (Hwang, §四.2, eq 3-11, Figs. 18-20).

printed.py  eq 3-11 as printed (our reading of the OCR), held against the geometry and against AD
check.py    rules on floats or symbols (one function), the given linkage over a crank turn
nlp.py      extremes and soil entry/exit as NLP variables with exact structural rows
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
    none of them (synthesis/kinds/tillage_linkage/parts.py)."""
    from synthesis.kinds.tillage_linkage import parts

    return parts


class TillageLinkage(Kind):
    name = "tillage_linkage"
    summary = "distorted rotary tillage linkage: crank, bar through a roller pair, tool path (seed 002 eq 3-11)"
    objectives = {"min_bar_length": "shortest tillage bar c meeting every rule, mm",
                  "max_margin": "largest smallest normalised rule margin (the design deepest inside every rule)",
                  "min_peak_torque": "smallest peak |input torque| on the flywheel over a turn, N m ([dynamics] "
                                     "needed)"}
    example = "tillage/tillage_redesign.toml"
    bench_specs = ("tillage/tillage_redesign.toml",)

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.tillage_linkage.spec import TillageSpec

        return TillageSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"tillage.png": _parts().tillage_figure,
                "tillage.svg": _parts().tillage_figure,
                "paths.csv": _parts().write_paths_csv,
                "linkage.dxf": _parts().write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figure


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE


KIND = TillageLinkage()

