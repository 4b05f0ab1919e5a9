"""Kind clamp_cam: the clamp cams of seed 001 §2.2 (motion law, roller-follower profile, pressure angle)."""

from synthesis.core.kind import Kind

KIND = Kind(
    name="clamp_cam",
    summary="clamp cams: motion law, roller-follower profile, pressure angle, undercut (seed 001 §2.2)",
    spec_model="synthesis.kinds.clamp_cam.spec:ClampCamSpec",
    check="synthesis.kinds.clamp_cam.check:run_check",
    figures={"motion.png": "synthesis.kinds.clamp_cam.plots:motion_figure",
             "profile.png": "synthesis.kinds.clamp_cam.plots:profile_figure",
             "profile.svg": "synthesis.kinds.clamp_cam.plots:profile_figure",
             "profile.csv": "synthesis.kinds.clamp_cam.export:write_csv",
             "profile.dxf": "synthesis.kinds.clamp_cam.export:write_dxf"},
    compare="synthesis.kinds.clamp_cam.plots:compare_figure",
    solving="synthesis.kinds.clamp_cam.solve:SOLVING",
    bench="synthesis.kinds.clamp_cam:bench_cases",
    objectives={"base_radius": "smallest base-circle radius, mm",
                "pressure_angle": "smallest peak pressure angle (measured on the fine grid), deg",
                "nearest": "smallest change from the given cam"},
    example="clamp_cam/opening_cam_redesign_modified_sine.toml",
    coarse_check="synthesis.kinds.clamp_cam.coarse:COARSE",
    poses="synthesis.kinds.clamp_cam.poses:POSES",
)


def bench_cases(specs, seed: int = 0) -> list:
    """The bench set (``agrisynth bench``): the generic studies (:mod:`synthesis.bench_generic`) on the
    given specs, by default on these library redesigns (``--quick``: the first)."""
    from synthesis.bench_generic import library_cases

    return library_cases(specs, seed, [
            "clamp_cam/opening_cam_redesign.toml",
            "clamp_cam/rotating_cam_redesign.toml",
    ])
