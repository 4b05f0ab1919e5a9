"""Kind crank_rocker: synthesis of a crank-rocker from K, rocker swing and minimum transmission angle."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    import numpy as np

    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/crank_rocker/parts.py)."""
    from synthesis.kinds.crank_rocker import parts

    return parts


class CrankRocker(Kind):
    name = "crank_rocker"
    summary = "crank-rocker from time ratio K, swing and minimum transmission angle (seed 001 §2.1.3)"
    objectives = {"min_total_length": "smallest l7 + l8 + l9 + l10, mm",
                  "max_transmission_angle": "largest smallest transmission angle over a turn, deg",
                  "min_peak_torque": "smallest peak |input torque| over a turn, N m ([dynamics] needed)",
                  "min_peak_shaking_force": "smallest peak shaking force on the frame over a turn, N ([dynamics] "
                                            "needed)",
                  "min_peak_shaking_moment": "smallest peak |shaking moment| on the frame over a turn, about the "
                                             "crank pivot, N m ([dynamics] needed)"}
    example = "picker/cai2020_crank_rocker_synthesis.toml"
    bench_specs = ("picker/cai2020_crank_rocker_synthesis.toml", "picker/crank_rocker_max_transmission.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.crank_rocker.spec import CrankRockerSpec

        return CrankRockerSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"extremes.png": _parts().extremes_figure,
                "extremes.svg": _parts().extremes_figure,
                "paths.csv": _parts().write_paths_csv,
                "linkage.dxf": _parts().write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figure


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE

    def poses(self) -> Poses:
        return _parts().POSES

    def design_affine(self, spec: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The NLP works in Grashof coordinates (three lengths replaced by the slacks of the Grashof rows)."""
        return _parts().COORDINATES.affine(n)


KIND = CrankRocker()

