"""The solve side of kind clamp_cam (:data:`SOLVING`): its NLP, the fine-grid re-check without CasADi
and the result facts.  An optimised (B-spline) law is fitted once per run (cvxpy), then held fixed."""

from __future__ import annotations

from synthesis.kinds.clamp_cam.check import FINE, describe
from synthesis.kinds.clamp_cam.nlp import objective_unit, problem
from synthesis.kinds.clamp_cam.scene import CamScene, evaluate, fit_law
from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import Recheck, StartReport


def prepare(spec):
    """The optimised law, fitted once (None for a closed-form law)."""
    return fit_law(spec)


def fine_check(spec, design: dict[str, float], optimised=None) -> list:
    """Evaluate a design independently of the solver (numpy, no CasADi) on a 10x finer grid: the rules."""
    scene = CamScene.from_spec(spec, design, optimised)
    rules, _ = evaluate(scene, FINE * spec.solver.samples_per_segment)
    return rules


def _peak_pressure_angle(report: StartReport) -> float:
    """The pressure_angle objective read from the fine-grid re-check (deg)."""
    return max(r.value for r in report.records if r.name.startswith("pressure_angle_"))


def recheck(setting: Setting, outcome) -> Recheck:
    spec = setting.spec
    measured = _peak_pressure_angle if spec.objective.name == "pressure_angle" else None
    return Recheck(fine_check(spec, outcome.design, setting.data), None, measured)


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    scene = CamScene.from_spec(spec, best.outcome.design, setting.data)
    kind_facts, trajectory = describe(scene)
    return Finished(design=dict(scene.design),
                    objective={"name": spec.objective.name, "value": best.outcome.objective,
                               "unit": objective_unit(spec)},
                    facts=kind_facts, trajectory=trajectory,
                    solver_settings={"samples_per_segment": spec.solver.samples_per_segment})


def baseline_rules(setting: Setting) -> list[dict] | None:
    """The rule table of the spec's given design (start values), for the side-by-side table."""
    spec = setting.spec
    return [r.record().to_json() for r in fine_check(spec, spec.design_values(), setting.data)]


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules, prepare=prepare,
                  samples_hint="[solver] samples_per_segment or [solver] backoff",
                  relax_hint="Try wider bounds on the design variables, looser limits on those rules, "
                             "or another motion law.")
