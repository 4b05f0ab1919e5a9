"""Kind guide_way: the rotary-arm slide guide way of seed 003 (Liang et al.): claw path -> roller-centre line ->
the two walls of the groove, reproduced from the paper's conics and redesigned as a smooth spline."""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/guide_way/parts.py)."""
    from synthesis.kinds.guide_way import parts

    return parts


class GuideWay(Kind):
    name = "guide_way"
    summary = "rotary-arm slide guide way: claw path, roller-centre line, groove walls, undercut (seed 003)"
    objectives = {"smoothness": "the claw path's squared third derivative, relative to the convex fit's"}
    example = "guide_way/smooth_redesign.toml"
    bench_specs = ("guide_way/smooth_redesign.toml",)
    design_unit = "mm"          # the path's control points, which the spec lists without a unit
    robust_refusal = ("its NLP works in the spline's 2 x control_points coordinates, held to the key points by "
                      "equality rows on them, not in the spec's design variables")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.guide_way.spec import GuideWaySpec

        return GuideWaySpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"guide_way.png": _parts().guide_figure,
                "guide_way.svg": _parts().guide_figure,
                "cycle.png": _parts().cycle_figure,
                "animation.gif": _parts().animation,
                "centre_line.csv": _parts().write_centre_csv,
                "walls.csv": _parts().write_walls_csv,
                "guide_way.dxf": _parts().write_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figures


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE

    def explicit_design(self, loaded: LoadedSpec, data: dict) -> dict:
        return _parts().explicit_design(loaded, data)


KIND = GuideWay()

