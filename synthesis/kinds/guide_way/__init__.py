"""Kind guide_way: the rotary-arm slide guide way of seed 003 (Liang et al.): claw path -> roller-centre line ->
the two walls of the groove, reproduced from the paper's conics and redesigned as a smooth spline."""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


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
        from synthesis.kinds.guide_way.check import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.guide_way.check import headline

        return headline(result)

    def solving(self) -> Solving:
        from synthesis.kinds.guide_way.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.guide_way.export import write_centre_csv, write_dxf, write_walls_csv
        from synthesis.kinds.guide_way.plots import animation, cycle_figure, guide_figure

        return {"guide_way.png": guide_figure,
                "guide_way.svg": guide_figure,
                "cycle.png": cycle_figure,
                "animation.gif": animation,
                "centre_line.csv": write_centre_csv,
                "walls.csv": write_walls_csv,
                "guide_way.dxf": write_dxf}

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.guide_way.plots import compare_figures

        return compare_figures


    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.guide_way.coarse import COARSE

        return COARSE

    def explicit_design(self, loaded: LoadedSpec, data: dict) -> dict:
        from synthesis.kinds.guide_way.check import explicit_design

        return explicit_design(loaded, data)


KIND = GuideWay()

