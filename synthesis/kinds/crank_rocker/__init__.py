"""Kind crank_rocker: synthesis of a crank-rocker from K, rocker swing and minimum transmission angle."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    import numpy as np

    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


class CrankRocker(Kind):
    name = "crank_rocker"
    summary = "crank-rocker from time ratio K, swing and minimum transmission angle (seed 001 §2.1.3)"
    objectives = {"min_total_length": "smallest l7 + l8 + l9 + l10, mm",
                  "max_transmission_angle": "largest smallest transmission angle over a turn, deg"}
    example = "picker/cai2020_crank_rocker_synthesis.toml"
    bench_specs = ("picker/cai2020_crank_rocker_synthesis.toml", "picker/crank_rocker_max_transmission.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.crank_rocker.spec import CrankRockerSpec

        return CrankRockerSpec

    def check(self, loaded: LoadedSpec) -> Result:
        from synthesis.kinds.crank_rocker.check import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.crank_rocker.check import headline

        return headline(result)

    def solving(self) -> Solving:
        from synthesis.kinds.crank_rocker.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.crank_rocker.export import write_linkage_dxf, write_paths_csv
        from synthesis.kinds.crank_rocker.plots import extremes_figure

        return {"extremes.png": extremes_figure,
                "extremes.svg": extremes_figure,
                "paths.csv": write_paths_csv,
                "linkage.dxf": write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.crank_rocker.plots import compare_figure

        return compare_figure


    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.crank_rocker.coarse import COARSE

        return COARSE

    def poses(self) -> Poses:
        from synthesis.kinds.crank_rocker.poses import POSES

        return POSES

    def design_affine(self, spec: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The NLP works in Grashof coordinates (three lengths replaced by the slacks of the Grashof rows)."""
        from synthesis.kinds.crank_rocker.nlp import COORDINATES

        return COORDINATES.affine(n)


KIND = CrankRocker()

