"""The planting arm's check on the studio's coarse grid: its built-in grid (400 samples per phase, 3600 per crank
turn) evaluated on a tenth of the samples (40 and 360), by the check's own evaluation."""

from __future__ import annotations

from synthesis.core.kind import CoarseCheck
from synthesis.result import Result

#: the check's built-in grid and the coarse one (samples per phase, per turn, trajectory samples)
FINE = (400, 3600, 361)
COARSE_SAMPLES = (40, 360, 121)


def evaluate(loaded) -> Result:
    from synthesis.kinds.planting.check import evaluate as rules_at, scene_facts, trajectory
    from synthesis.kinds.planting.scene import PlantingScene

    phase, turn, traced = COARSE_SAMPLES
    spec = loaded.model
    scene = PlantingScene.from_spec(spec)
    rules, pts = rules_at(scene, spec.rules, phase, turn)
    design = dict(spec.design_values())
    design["branch"] = spec.arm.branch
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=design, rules=[r.record().to_json() for r in rules],
                  trajectory=trajectory(scene, pts, traced), extra=scene_facts(spec, scene, pts))


def _note(samples: tuple[int, int, int]):
    return lambda spec: f"{samples[0]} samples per phase, {samples[1]} per crank turn"


COARSE = CoarseCheck(evaluate=evaluate, note=_note(COARSE_SAMPLES), fine_note=_note(FINE))
