"""The solve side of kind guide_tube (:data:`SOLVING`): its NLP, the independent re-check on a finer
row-spacing grid and the result facts."""

from __future__ import annotations

from synthesis.constraints import not_evaluated
from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import Recheck, StartReport
from synthesis.errors import AgrisynthError
from synthesis.kinds.guide_tube.check import FINE, design_of, rules_even_if_stuck, rules_of, scene_facts
from synthesis.kinds.guide_tube.nlp import OBJECTIVE_UNITS, problem
from synthesis.kinds.guide_tube.scene import GuideTubeScene


def prepare(spec) -> GuideTubeScene:
    return GuideTubeScene.from_spec(spec)


def angles_of(design: dict[str, float]) -> dict[str, float]:
    return {k.removeprefix("delta_"): v for k, v in design.items()}


def fine_rules(spec, scene: GuideTubeScene, design: dict[str, float]) -> list:
    """The rules re-evaluated on floats on a 10x finer row-spacing grid, independently of the solver."""
    return rules_of(scene, angles_of(design), scene.spacing_grid(FINE * spec.solver.samples), spec.rules)


def recheck(setting: Setting, outcome) -> Recheck:
    """Raises SeedlingSticks / WallAboveDropPoint (ValueErrors) for a design the drop model cannot evaluate."""
    return Recheck(fine_rules(setting.spec, setting.data, outcome.design))


def unevaluated_rules(spec, why: str) -> list:
    """The rule table of a design the drop model cannot evaluate: every rule, with the reason."""
    r = spec.rules
    where = "row spacings"
    rules = [not_evaluated("landing_time_spread", None, r.max_time_spread, "s", where, why)]
    if r.max_spacing_error is not None:
        rules.append(not_evaluated("spacing_error", None, r.max_spacing_error, "mm", where, why))
    for t in spec.tubes:
        rules.append(not_evaluated(f"wall_exit_speed_{t.name}", r.min_exit_speed, None, "m/s", where, why))
        rules.append(not_evaluated(f"free_fall_height_{t.name}", r.min_free_fall, None, "mm", where, why))
    return rules


def finish(setting: Setting, best: StartReport) -> Finished:
    spec, scene = setting.spec, setting.data
    # no start could be evaluated: the result shows the given design, so no start's objective belongs to it
    objective = {"name": spec.objective.name, "value": None if best.why is not None else best.outcome.objective,
                 "unit": OBJECTIVE_UNITS[spec.objective.name]}
    settings = {"samples": spec.solver.samples}
    given = design_of(spec.given_angles())
    if best.why is not None:
        # no start gives a design the drop model can evaluate (a seedling sticks at every start's
        # angles): the given design's facts, every rule not evaluated, with the reason
        return Finished(design=given, objective=objective, facts={"source": spec.source},
                        solver_settings=settings, baseline_design=given,
                        rules=[r.record().to_json() for r in unevaluated_rules(spec, best.why)])
    design = best.outcome.design
    return Finished(design=design, objective=objective,
                    facts=scene_facts(spec, scene, angles_of(design), FINE * spec.solver.samples),
                    solver_settings=settings, baseline_design=given)


def baseline_rules(setting: Setting) -> list[dict] | None:
    """The rule table of the spec's given angles, for the side-by-side table."""
    spec = setting.spec
    try:       # a given design whose seedling sticks has a table too: its wall rules fail, its landing times do not exist
        rules, _ = rules_even_if_stuck(setting.data, spec.given_angles(),
                                       setting.data.spacing_grid(FINE * spec.solver.samples), spec.rules)
    except AgrisynthError:
        return None
    return [r.record().to_json() for r in rules]


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules, prepare=prepare,
                  samples_hint="[solver] samples or [solver] backoff",
                  relax_hint="Try wider bounds on the wall angles, looser limits on those rules, or more --starts.")
