"""The clamp cam's check on the studio's coarse grid.  The check also tabulates each motion segment's extremes,
refined by scalar searches (half its time); the coarse grid draws the profile and the follower without that
table: the rules are the check's, on the [solver] samples per segment (the check's are 10x)."""

from __future__ import annotations

from synthesis.core.kind import CoarseCheck
from synthesis.result import Result


def evaluate(loaded) -> Result:
    from synthesis.kinds.clamp_cam.check import evaluate as rules_at, follower_motion, profile
    from synthesis.kinds.clamp_cam.scene import CamScene

    spec = loaded.model
    scene = CamScene.from_spec(spec)
    rules, _ = rules_at(scene, spec.solver.samples_per_segment)
    trajectory, follower = follower_motion(scene)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=dict(scene.design), rules=[r.record().to_json() for r in rules], trajectory=trajectory,
                  extra={"follower": follower, "profile": profile(scene)})


def note(spec) -> str:
    return (f"the check's rules on [solver] samples_per_segment {spec.solver.samples_per_segment} (fine: 10x), "
            f"without the table of segment extremes")


COARSE = CoarseCheck(evaluate=evaluate, note=note)
