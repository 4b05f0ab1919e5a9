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
        from synthesis.kinds.combing_chain.check import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.combing_chain.check import headline

        return headline(result)

    def solving(self) -> Solving:
        from synthesis.kinds.combing_chain.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.combing_chain.plots import delta_figure

        return {"delta_over_beta.png": delta_figure,
                "delta_over_beta.svg": delta_figure}

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.combing_chain.plots import compare_figure

        return compare_figure


    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.combing_chain.coarse import COARSE

        return COARSE


KIND = CombingChain()

