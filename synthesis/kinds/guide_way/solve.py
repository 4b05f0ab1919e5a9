"""The solve side of kind guide_way (:data:`SOLVING`): the convex spline fit once per run (prepare), the
IPOPT stage on its control points, the fine-grid re-check without CasADi's NLP and the result facts."""

from __future__ import annotations

from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import Recheck, StartReport
from synthesis.errors import SpecError
from synthesis.kinds.guide_way.check import (FINE, control_design, describe, dynamics_samples, given_control, scene_for,
                                             whose_path)
from synthesis.kinds.guide_way.nlp import FixedGuide, GuideNLP, control_of, names_of


def prepare(spec):
    """The convex fit of a spline path (None for the paper's conics: nothing to optimise)."""
    if spec.spline is None:
        return None
    from synthesis.kinds.guide_way.fit import fit_path     # cvxpy: imported by a spline path's solve only

    try:
        return fit_path(spec)
    except SpecError as exc:          # said as check says it: which part of the spec the fit could not use
        raise SpecError(f"{whose_path(spec)}: {exc}") from None


def build(setting: Setting, elastic: bool = False):
    if setting.data is None:
        return FixedGuide(setting.spec)
    return GuideNLP(setting.spec, setting.data, elastic, setting)


def _control(spec, design: dict):
    n = spec.spline.control_points
    return control_of([design[k] for k in names_of(n)], n)


def recheck(setting: Setting, outcome) -> Recheck:
    spec = setting.spec
    scene = scene_for(spec, _control(spec, outcome.design), FINE * spec.solver.samples_per_segment)
    # the dynamics rules on the check's grid (check.dynamics_samples)
    return Recheck(scene.rules + _dynamics_rules(scene, dynamics_samples(spec, scene)), scene)


def _dynamics_rules(scene, samples: int | None = None) -> list:
    """The ``[dynamics.limits]`` rules of a numeric scene at ``samples`` over its path (default the table's; none
    without a limit: nothing of the dynamics imported)."""
    table = scene.spec.dynamics
    if table is None or not table.has_rules():
        return []
    from synthesis.kinds.guide_way.dynamics import dynamics_rules

    return dynamics_rules(scene, samples)


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    scene = best.context if best.context is not None else scene_for(spec, _control(spec, best.outcome.design))
    facts = describe(scene)
    facts["convex_fit"] = {"energy": setting.data.energy, "status": setting.data.status,
                           "tangent_speeds": setting.data.speeds}
    # every design variable: the arm the path is solved for (fixed) as well as the control points
    return Finished(design={**spec.design_values(), **best.outcome.design},
                    objective={"name": "smoothness", "value": best.outcome.objective, "unit": "-"},
                    facts=facts, solver_settings={"samples_per_segment": spec.solver.samples_per_segment},
                    baseline_design=_baseline_design(spec, setting.data))


def _baseline_design(spec, fit) -> dict:
    """The given design: the arm and the spec's control points, else the convex fit's."""
    design = dict(spec.design_values())
    for name, value in control_design(fit.control).items():
        design.setdefault(name, value)
    return design


def baseline_rules(setting: Setting) -> list[dict] | None:
    """The rule table of the given design of a spline spec: its control points, else the convex fit."""
    if setting.data is None:
        return None
    given = given_control(setting.spec)
    scene = scene_for(setting.spec, setting.data.control if given is None else given)
    return [r.record().to_json() for r in scene.rules + _dynamics_rules(scene, dynamics_samples(setting.spec, scene))]


SOLVING = Solving(build=build, recheck=recheck, finish=finish, baseline_rules=baseline_rules, prepare=prepare,
                  samples_hint="[solver] samples_per_segment",
                  relax_hint="Loosen those limits ([rules]), move the key points or tangents, or give the path "
                             "room: more [spline] control_points, a larger [spline] move (control points left to "
                             "the fit) or wider bounds in [spline] control (control points given).")
