"""The solve side of kind combing_chain (:data:`SOLVING`): its NLP, the re-check on a (beta, V_s) grid 10x
finer in each direction, and the result's facts (with the closed-form answer beside the optimum)."""

from __future__ import annotations

from synthesis.kinds.combing_chain.check import evaluate, facts
from synthesis.core.declared import declared
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.kinds.combing_chain.nlp import problem
from synthesis.core.verdict import FINE, Recheck, StartReport

OBJECTIVE_UNITS = {"max_window_margin": "deg", "min_chain_speed": "m/s"}


def fine_samples(spec) -> tuple[int, int]:
    return FINE * spec.solver.beta_samples, FINE * spec.solver.speed_samples


def window_margin(spec, tr) -> float:
    """The smallest margin (deg) of any plant on the trace's grid to the window: the measured objective."""
    lo, hi = spec.requirements.window
    return min(min(d - lo, hi - d) for gt in tr.gears for row in gt.delta for d in row)


def recheck(setting: Setting, outcome) -> Recheck:
    """The rules of a returned design on floats, on a grid 10x finer in beta and in V_s."""
    spec = setting.spec
    rules, tr = evaluate(spec, dict(outcome.design), *fine_samples(spec))
    measured = None
    if spec.objective.name == "max_window_margin":
        measured = lambda report, tr=tr: window_margin(spec, tr)      # noqa: E731
    return Recheck(rules, tr, measured)


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    design = dict(best.outcome.design)
    tr = best.context
    if tr is None:
        _, tr = evaluate(spec, design, *fine_samples(spec))
    details = best.outcome.details
    binding = details.get("binding_rules", [])
    if spec.objective.name == "max_window_margin" and best.records:
        # the epigraph rows bind, not the rules' own: the limiting rules are those at the smallest margin
        window = [r for r in best.records if "window_" in r.name and r.margin is not None]
        if window:
            least = min(r.margin for r in window)
            binding = [r.name for r in window if r.margin <= least + 1e-6]
    return Finished(
        design=design,
        objective={"name": spec.objective.name, "value": best.outcome.objective,
                   "unit": OBJECTIVE_UNITS[spec.objective.name]},
        facts={**facts(spec, design, tr), "binding_rules": binding,
               "variables_at_bounds": details.get("variables_at_bounds", [])},
        solver_settings={"beta_samples": spec.solver.beta_samples, "speed_samples": spec.solver.speed_samples})


def baseline_rules(setting: Setting) -> list[dict] | None:
    spec = setting.spec
    rules, _ = evaluate(spec, spec.design_values())
    return [r.record().to_json() for r in rules]


def maximise(setting: Setting) -> bool:
    return setting.spec.objective.name == "max_window_margin"


SOLVING = Solving(build=declared(problem), recheck=recheck, finish=finish, baseline_rules=baseline_rules, maximise=maximise,
                  samples_hint="[solver] beta_samples and speed_samples",
                  relax_hint="Widen the window, narrow the plant-angle or machine-speed range, widen the chain-speed "
                             "bounds, or (one chain gear) add a second: speeds = [gear 1, gear 2] with a "
                             "switch_speed; (two gears) free the switch_speed or widen its bounds.")
