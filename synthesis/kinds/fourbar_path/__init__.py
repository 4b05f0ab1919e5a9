"""Kind fourbar_path: any four-bar coupler point through N target points, timing prescribed or free."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    import numpy as np

    from synthesis.core.bench_case import BenchCase
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, ResultTable, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/fourbar_path/parts.py)."""
    from synthesis.kinds.fourbar_path import parts

    return parts


class FourbarPath(Kind):
    name = "fourbar_path"
    summary = "any four-bar coupler point through N target points, timing prescribed or free"
    objectives = {"sum_squared_distance": "sum of squared distances of the coupler point to the targets, mm^2 ([solver] stop_at_objective ends the multistart at the first start, in start order, that reaches it)"}
    example = "fourbar_path/picking_arc.toml"

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

        return FourbarPathSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def result_tables(self, result: Result) -> list[ResultTable]:
        return [_parts().target_error_table(result)]

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"coupler_curve.png": _parts().coupler_curve_figure,
                "coupler_curve.svg": _parts().coupler_curve_figure,
                "linkage.gif": _parts().linkage_animation,
                "paths.csv": _parts().write_paths_csv,
                "linkage.dxf": _parts().write_linkage_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_coupler_curves

    def bench_cases(self, specs: list[LoadedSpec] | None, seed: int = 0) -> list[BenchCase]:
        from synthesis.kinds.fourbar_path.bench import bench_cases

        return bench_cases(specs, seed)

    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE

    def poses(self) -> Poses:
        return _parts().POSES

    def design_affine(self, spec: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The NLP works in nominal units of the targets' size: design = offset + scale * z."""
        return _parts().nominal_affine(spec, n)

    def answer_details(self, result: Result) -> dict:
        """The crank's direction, which result.json keeps in ``facts`` and a start in its details."""
        return {"direction": (result.extra or {}).get("crank_direction")}


KIND = FourbarPath()
