"""The two grids the studio evaluates on: coarse while a slider moves, the check's own (fine) on release.

Fine is ``agrisynth check`` itself.  Coarse is the same check on fewer samples:

* most kinds' checks evaluate their sampled rules on 10x the ``[solver]`` sample counts (the fine
  re-check grid); coarse runs that check with every ``[solver]`` sample count divided by 10 (not below
  the least the spec model allows), i.e. on the optimiser's own grid;
* planting_fourbar's check has its grid built in (400 samples per phase, 3600 per turn); coarse calls
  the same evaluation on 40 and 360;
* steering_linkage's check also explains the paper's Table 12 (least-squares fits of the published rows,
  about nine tenths of its time); that explanation does not depend on the design, so the coarse grid
  leaves it out of the facts (the rules are the check's, on the [solver] lock samples);
* tillage_linkage's check also measures, at the design, how far the paper's printed equations 3-11 are
  from the constructed geometry (four fifths of its time); that is a fact about the paper, not a rule, so
  the coarse grid leaves it out (the rules are the check's, on the [solver] samples);
* clamp_cam's check also tabulates each motion segment's extremes, refined by scalar searches (half its
  time); the coarse grid draws the profile and follower without that table (the rules are the check's, on the
  [solver] samples per segment);
* crank_rocker's check samples the transmission angle on 3600 crank angles; coarse on the [solver]
  samples_per_turn;
* combing_chain's check samples 181 plant angles x 51 machine speeds per gear and explains the paper's
  published figures; coarse: the [solver] beta_samples x speed_samples, and only the curves the page draws;
* a kind whose check reads no sample count is evaluated on its one grid while dragging too (the page says so):
  fourbar_path unless its grashof is "any" (its rules are at the targets and in closed form), and comb_finger
  while 10x its turn_samples is below the check's least 3600 turn angles.

Each note states the sample counts the coarse and the fine grid actually evaluate.
"""

from __future__ import annotations

from typing import Callable

from synthesis import kinds
from synthesis.core.verdict import FINE
from synthesis.result import Result
from synthesis.spec import LoadedSpec

GRIDS = ("coarse", "fine")
#: sample counts of the check divided by this while dragging (the check's fine grid is 10x the solver's)
COARSENING = 10
#: planting_fourbar: the check's built-in grid and the coarse one (samples per phase, per turn, trajectory)
PLANTING_FINE = (400, 3600, 361)
PLANTING_COARSE = (40, 360, 121)
#: kinds whose check grid is fixed in the kind (no [solver] sample count reaches it)
ONE_GRID = {"guide_tube", "picker", "picker_double_crank"}


def _sample_fields(spec) -> dict[str, tuple[int, int]]:
    """[solver] field -> (value, least allowed) for every sample count of the spec."""
    solver = getattr(spec, "solver", None)
    if solver is None:
        return {}
    out = {}
    for name, info in type(solver).model_fields.items():
        value = getattr(solver, name)
        if "samples" in name and isinstance(value, int) and not isinstance(value, bool):
            least = next((m.ge for m in info.metadata if hasattr(m, "ge")), 1)
            step = next((m.multiple_of for m in info.metadata if hasattr(m, "multiple_of")), 1)
            out[name] = (value, int(least), int(step))
    return out


def _coarser(spec):
    """The spec with every [solver] sample count divided by COARSENING."""
    fields = _sample_fields(spec)
    changes = {}
    for name, (value, least, step) in fields.items():
        coarse = max(least, value // COARSENING)
        changes[name] = max(least, coarse - coarse % step) if step > 1 else coarse
    return spec.model_copy(update={"solver": spec.solver.model_copy(update=changes)})


def _planting(samples: tuple[int, int, int]) -> Callable[[LoadedSpec], Result]:
    def evaluate(loaded: LoadedSpec) -> Result:
        from synthesis.planting.check import evaluate, scene_facts, trajectory
        from synthesis.planting.scene import PlantingScene

        spec = loaded.model
        scene = PlantingScene.from_spec(spec)
        rules, pts = evaluate(scene, spec.rules, samples[0], samples[1])
        design = dict(spec.design_values())
        design["branch"] = spec.arm.branch
        return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                      design=design, rules=[r.record().to_json() for r in rules],
                      trajectory=trajectory(scene, pts, samples[2]), extra=scene_facts(spec, scene, pts))
    return evaluate


def _steering(loaded: LoadedSpec) -> Result:
    from synthesis.steering_linkage.check import evaluate, facts

    spec = _coarser(loaded.model)
    design = spec.design_values()
    rules, trace = evaluate(spec, design, COARSENING * spec.solver.samples)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra=facts(spec, design, trace, {}))


def _tillage(loaded: LoadedSpec) -> Result:
    import math

    from synthesis.tillage_linkage.check import curves, evaluate, joints, params

    spec = loaded.model
    design = spec.design_values()
    rules, motion = evaluate(spec, design, spec.solver.samples, spec.solver.soil_samples)
    machine, trajectory = curves(spec, design, motion)
    a, b, c, th = params(design)
    # the check's curve and its poses 45 deg apart (its facts "curve" and "positions"), nothing else
    poses = [{"crank_deg": k * 45.0, **{n: list(v) for n, v in joints(math.radians(k * 45.0), a, b, c, th).items()}}
             for k in range(8)]
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], trajectory=trajectory,
                  extra={"curve": machine, "positions": poses})


def _clamp_cam(loaded: LoadedSpec) -> Result:
    from synthesis.clamp_cam.check import evaluate, follower_motion, profile
    from synthesis.clamp_cam.scene import CamScene

    spec = loaded.model
    scene = CamScene.from_spec(spec)
    rules, _ = evaluate(scene, spec.solver.samples_per_segment)
    trajectory, follower = follower_motion(scene)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=dict(scene.design), rules=[r.record().to_json() for r in rules], trajectory=trajectory,
                  extra={"follower": follower, "profile": profile(scene)})


def _crank_rocker(loaded: LoadedSpec) -> Result:
    from synthesis.crank_rocker.check import evaluate, facts, mechanism

    spec = loaded.model
    cr = mechanism(spec)
    rules, q = evaluate(spec, cr, samples=spec.solver.samples_per_turn)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=spec.design_values(), rules=[r.record().to_json() for r in rules], extra=facts(spec, cr, q))


def _combing_chain(loaded: LoadedSpec) -> Result:
    from synthesis.combing_chain.check import curves, evaluate

    spec = loaded.model
    design = spec.design_values()
    rules, _ = evaluate(spec, design, spec.solver.beta_samples, spec.solver.speed_samples)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra={"curves": curves(spec, design)})


#: kinds whose coarse grid is their check's rules on the [solver] samples with only what the page draws
TRIMMED = {"planting_fourbar": _planting(PLANTING_COARSE), "steering_linkage": _steering,
           "tillage_linkage": _tillage, "clamp_cam": _clamp_cam, "crank_rocker": _crank_rocker,
           "combing_chain": _combing_chain}


def evaluator(kind: str, grid: str) -> Callable[[LoadedSpec], Result]:
    """loaded spec -> Result, on ``grid``."""
    check = kinds.checker(kind)
    if grid == "fine":
        return check
    if kind in TRIMMED:
        return TRIMMED[kind]
    if kind in ONE_GRID:
        return check

    def coarse(loaded: LoadedSpec) -> Result:
        if not _sample_fields(loaded.model):
            return check(loaded)
        return check(LoadedSpec(_coarser(loaded.model), loaded.path, loaded.sha256))
    return coarse


def note(kind: str, grid: str, spec=None) -> str:
    """What the grid is, in words, for the page."""
    if kind == "planting_fourbar":
        phase, turn, _ = PLANTING_COARSE if grid == "coarse" else PLANTING_FINE
        return f"{phase} samples per phase, {turn} per crank turn"
    if grid == "fine":
        return "agrisynth check's own grid"
    if kind in ONE_GRID or (spec is not None and not _sample_fields(spec)):
        return "the check's one grid (this kind's check has no coarser one)"
    if spec is None:
        return f"the check with [solver] sample counts / {COARSENING}"
    fields = _sample_fields(spec)
    coarse = _coarser(spec).solver
    if kind == "steering_linkage":        # lock_grid: samples + 1 locks, the check's on 10x the [solver] samples
        return (f"the check on {FINE * coarse.samples + 1} inside locks (fine: "
                f"{FINE * spec.solver.samples + 1}), without its Table 12 explanation")
    if kind == "fourbar_path":
        if spec.rules.grashof_class != "any":   # path_rules samples between targets only for grashof "any"
            return (f"the check's one grid (grashof = \"{spec.rules.grashof_class}\": its rules are evaluated at the "
                    f"targets and in closed form, on no sample count)")
        return (f"the check on {FINE * coarse.samples} samples per gap between targets (fine: "
                f"{FINE * spec.solver.samples})")
    if kind == "guide_way":
        return (f"the check on {FINE * coarse.samples_per_segment} samples per segment (fine: "
                f"{FINE * spec.solver.samples_per_segment})")
    if kind == "comb_finger":
        from synthesis.comb_finger.check import fine_samples

        ours, theirs = fine_samples(_coarser(spec)), fine_samples(spec)
        if ours == theirs:                 # the check samples at least CHECK_TURN_SAMPLES, whatever [solver] says
            return (f"the check's one grid ({theirs} finger turn angles: it does not go below that for [solver] "
                    f"turn_samples {spec.solver.turn_samples})")
        return f"the check on {ours} finger turn angles (fine: {theirs})"
    if kind == "tillage_linkage":
        return (f"the check's rules on [solver] samples {spec.solver.samples} and soil_samples "
                f"{spec.solver.soil_samples} (fine: 10x), without the printed-equation residuals")
    if kind == "crank_rocker":
        from synthesis.crank_rocker.check import CHECK_SAMPLES

        return (f"the check with [solver] samples_per_turn {spec.solver.samples_per_turn} crank angles "
                f"(fine: {CHECK_SAMPLES})")
    if kind == "combing_chain":
        from synthesis.combing_chain.check import CHECK_BETA_SAMPLES, CHECK_SPEED_SAMPLES

        return (f"the check's rules on [solver] beta_samples {spec.solver.beta_samples} x speed_samples "
                f"{spec.solver.speed_samples} (fine: {CHECK_BETA_SAMPLES} x {CHECK_SPEED_SAMPLES}), only the curves drawn")
    if kind == "clamp_cam":
        return (f"the check's rules on [solver] samples_per_segment {spec.solver.samples_per_segment} (fine: 10x), "
                f"without the table of segment extremes")
    return "the check with " + ", ".join(f"[solver] {n} {v} -> {getattr(coarse, n)}" for n, (v, _, _) in fields.items())
