"""Kind clamp_cam: the clamp cams of seed 001 §2.2 (motion law, roller-follower profile, pressure angle)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


class ClampCam(Kind):
    name = "clamp_cam"
    summary = "clamp cams: motion law, roller-follower profile, pressure angle, undercut (seed 001 §2.2)"
    objectives = {"base_radius": "smallest base-circle radius, mm",
                  "pressure_angle": "smallest peak pressure angle (measured on the fine grid), deg",
                  "nearest": "smallest change from the given cam"}
    example = "clamp_cam/opening_cam_redesign_modified_sine.toml"
    bench_specs = ("clamp_cam/opening_cam_redesign.toml", "clamp_cam/rotating_cam_redesign.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.clamp_cam.spec import ClampCamSpec

        return ClampCamSpec

    def check(self, loaded: LoadedSpec) -> Result:
        from synthesis.kinds.clamp_cam.check import run_check

        return run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        from synthesis.kinds.clamp_cam.check import headline

        return headline(result)

    def solving(self) -> Solving:
        from synthesis.kinds.clamp_cam.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.clamp_cam.export import write_csv, write_dxf
        from synthesis.kinds.clamp_cam.plots import motion_figure, profile_figure

        return {"motion.png": motion_figure,
                "profile.png": profile_figure,
                "profile.svg": profile_figure,
                "profile.csv": write_csv,
                "profile.dxf": write_dxf}

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.clamp_cam.plots import compare_figure

        return compare_figure


    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.clamp_cam.coarse import COARSE

        return COARSE

    def poses(self) -> Poses:
        from synthesis.kinds.clamp_cam.poses import POSES

        return POSES


KIND = ClampCam()

