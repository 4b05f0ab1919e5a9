"""Kind rotary_planetary: the rotary transplanting mechanism whose planting arms ride on non-circular planetary
gear trains (sun fixed, compound idler, planet carrying the arm; two arms per gearbox)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import FixedBy, Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, ResultTable, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


class RotaryPlanetary(Kind):
    name = "rotary_planetary"
    summary = "rotary transplanting mechanism with non-circular planetary gears: laws, pitch curves, key poses"
    objectives = {"key_pose_miss": "smallest sum of squared key-pose misses, mm^2 + deg^2",
                  "smooth_law": "smoothest laws (mean squared second derivative of F and G, deg^2/rad^4)"}
    example = "rotary_planetary/key_pose_redesign.toml"
    fixed_by = {"plant_spacing": FixedBy("[operation] forward_speed and carrier_speed", "[rules] plant_spacing")}
    bench_specs = ("rotary_planetary/smooth_loop_redesign.toml", "rotary_planetary/key_pose_redesign.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.rotary_planetary.spec import RotaryPlanetarySpec

        return RotaryPlanetarySpec

    def check(self, loaded: LoadedSpec) -> Result:
        from synthesis.kinds.rotary_planetary.check import run_check

        return run_check(loaded)

    def solving(self) -> Solving:
        from synthesis.kinds.rotary_planetary.solve import SOLVING

        return SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        from synthesis.kinds.rotary_planetary.export import write_pitch_curves_csv, write_pitch_curves_dxf
        from synthesis.kinds.rotary_planetary.plots import law_figure, pitch_curves_figure, trajectory_figure

        return {"trajectory.png": trajectory_figure,
                "trajectory.svg": trajectory_figure,
                "law.png": law_figure,
                "pitch_curves.png": pitch_curves_figure,
                "pitch_curves.csv": write_pitch_curves_csv,
                "pitch_curves.dxf": write_pitch_curves_dxf}

    def headline(self, result: Result) -> list[str]:
        """Each key pose's miss (tip, attitude), the loop's height and depth and the hole it leaves."""
        motion = (result.extra or {}).get("motion") or {}
        lines = []
        for name, pose in (motion.get("poses") or {}).items():
            target = pose.get("target") or {}
            att = "" if target.get("attitude") is None else \
                f", attitude {pose['attitude_deg']:.1f} deg (target {target['attitude']:g})"
            lines.append(f"pose {name}: tip {pose['miss_mm']:.3f} mm from target{att}")
        if "trajectory_height_mm" in motion:
            soil = motion.get("soil") or {}
            hole = f", hole {soil['hole_width_mm']:.1f} mm" if soil else ", never in the soil"
            lines.append(f"loop {motion['trajectory_height_mm']:.1f} mm tall, {motion['planting_depth_mm']:.1f} mm "
                         f"deep{hole}")
        return lines

    def result_tables(self, result: Result) -> list[ResultTable]:
        """Each key pose: its target, where the tip is nearest it (carrier angle, position, miss) and the claw's
        attitude there."""
        from synthesis.core.kind import ResultTable

        poses = (((result.extra or {}).get("motion") or {}).get("poses")) or {}
        if not poses:
            return []
        rows = tuple((name, p["target"]["x"], p["target"]["y"], p["target"]["attitude"], p["carrier_deg"], p["x"],
                      p["y"], p["miss_mm"], p["attitude_deg"]) for name, p in poses.items())
        return [ResultTable("Key poses: target and the tip where it is nearest", (
            "pose", "target x, mm", "target y, mm", "target attitude, deg", "carrier angle, deg", "x, mm", "y, mm",
            "miss, mm", "attitude, deg"), rows)]

    def coarse_check(self) -> CoarseCheck:
        from synthesis.kinds.rotary_planetary.coarse import COARSE

        return COARSE

    def compare_figures(self) -> CompareWriter:
        from synthesis.kinds.rotary_planetary.plots import compare_figure

        return compare_figure

    def poses(self) -> Poses:
        from synthesis.kinds.rotary_planetary.poses import POSES

        return POSES


KIND = RotaryPlanetary()
