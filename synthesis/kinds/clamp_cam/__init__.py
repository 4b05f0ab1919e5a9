"""Kind clamp_cam: the clamp cams of seed 001 §2.2 (motion law, roller-follower profile, pressure angle)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/clamp_cam/parts.py)."""
    from synthesis.kinds.clamp_cam import parts

    return parts


class ClampCam(Kind):
    name = "clamp_cam"
    summary = "clamp cams: motion law, roller-follower profile, pressure angle, undercut (seed 001 §2.2)"
    objectives = {"base_radius": "smallest base-circle radius, mm",
                  "pressure_angle": "smallest peak pressure angle (measured on the fine grid), deg",
                  "nearest": "smallest change from the given cam",
                  "spring_force": "smallest peak spring load on the follower (preload + stiffness x stroke), N "
                                  "(N m for an oscillating follower); needs [dynamics]"}
    example = "clamp_cam/opening_cam_redesign_modified_sine.toml"
    bench_specs = ("clamp_cam/opening_cam_redesign.toml", "clamp_cam/rotating_cam_redesign.toml")
    #: the four segments fill one turn (rise + far_dwell + return + near_dwell = 360 deg, the spec's and the NLP's
    #: identity): in a tolerance box the near dwell takes what the others leave of it
    follows = {"near_dwell": {"rise": -1.0, "far_dwell": -1.0, "return": -1.0}}

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.clamp_cam.spec import ClampCamSpec

        return ClampCamSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"motion.png": _parts().motion_figure,
                "profile.png": _parts().profile_figure,
                "profile.svg": _parts().profile_figure,
                "profile.csv": _parts().write_csv,
                "profile.dxf": _parts().write_dxf}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figure


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE

    def bounds_read(self, spec) -> list[str]:
        # the spring-shaped law is fitted from the stiffness's lower bound and the preload's range
        # (synthesis.kinds.clamp_cam.scene.spring_shaping), whatever their values
        if spec.motion.law != "optimised" or spec.bspline.minimise != "spring_force" or spec.dynamics is None:
            return []
        _, preload, stiffness = spec.dynamics.body_fields(spec.follower.type)
        return [preload, stiffness]

    def poses(self) -> Poses:
        return _parts().POSES


KIND = ClampCam()

