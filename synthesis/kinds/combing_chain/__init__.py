"""Kind combing_chain: the stem-combing chain of seed 002 §四.3 (Shimamoto; eq 12-13, Table 13).

geometry.py  eq 12-13 derived (floats and CasADi symbols) and as printed
check.py, nlp.py, solve.py, plots.py: the kind of the CLI
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
    none of them (synthesis/kinds/combing_chain/parts.py)."""
    from synthesis.kinds.combing_chain import parts

    return parts


class CombingChain(Kind):
    name = "combing_chain"
    summary = "stem-combing chain: chain speed(s) so every plant is combed into a window before the cut (seed 002 §四.3 eq 12-13)"
    objectives = {"max_window_margin": "largest smallest margin of the plant angle before the cut to the window, deg",
                  "min_chain_speed": "slowest chain(s) keeping every plant in the window: sum of gear speeds, m/s"}
    example = "combing_chain/redesign_window_80_100.toml"
    bench_specs = ("combing_chain/redesign_window_80_100.toml", "combing_chain/redesign_two_speed.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.combing_chain.spec import CombingChainSpec

        return CombingChainSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"delta_over_beta.png": _parts().delta_figure,
                "delta_over_beta.svg": _parts().delta_figure}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figure


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE


KIND = CombingChain()

