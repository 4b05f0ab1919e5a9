"""The solve side of kind fourbar_path (:data:`SOLVING`): its NLP, the re-check of a start and the
result's facts.  The multistart, the verdict and the elastic diagnosis are the core's
(:mod:`synthesis.core.solve`).

Every start's design is re-checked by :func:`synthesis.kinds.fourbar_path.check.evaluate` (the same rule
function as the NLP, on floats; the sampled rules of grashof = "any" 10x more finely).  With
[solver] stop_at_objective the multistart ends at the first start, in start order, that satisfies
every rule with an objective at or below it (the same start for any number of workers).
"""

from __future__ import annotations

import functools

import numpy as np

from synthesis.constraints import not_evaluated
from synthesis.core.kind import Finished, Setting, Solving
from synthesis.core.verdict import Recheck, StartReport
from synthesis.kinds.fourbar_path.check import evaluate, path_facts, result_design, trajectory
from synthesis.kinds.fourbar_path.dynamics import dynamics_facts_of
from synthesis.kinds.fourbar_path.nlp import PathNLP
from synthesis.kinds.fourbar_path.rule_set import path_rules
from synthesis.kinds.fourbar_path.starts import grashof_anchor, takes_auto_order
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

OBJECTIVE = "sum_squared_distance"


def build(setting: Setting, elastic: bool = False) -> PathNLP:
    return PathNLP(setting.spec, seed=setting.seed, elastic=elastic, setting=setting)


def recheck(setting: Setting, outcome) -> Recheck:
    """The rules of a start's design at its crank angles and direction (the start's details; a design
    without them: its ``crank_deg``, else the nearest points of its coupler curve)."""
    details = getattr(outcome, "details", {}) or {}
    crank = details.get("crank_deg", outcome.design.get("crank_deg"))
    # a direction the spec fixes is the one checked, whatever a start's details say
    fixed = setting.spec.rules.direction
    direction = fixed if fixed in ("ccw", "cw") else details.get("direction")
    ev = evaluate(setting.spec, outcome.design, crank, timing="solved" if crank is not None else "nearest",
                  direction=direction if direction in ("ccw", "cw") else None)
    return Recheck(ev.rules, ev)


def grashof_room(spec: FourbarPathSpec) -> dict | None:
    """When no linkage of the Grashof class fits in the bounds of r1..r4 (a linear programme): the
    largest smallest class slack there (negative), so the result says why no start can satisfy it."""
    anchor = grashof_anchor(np.array(spec.bounds_array(), dtype=float), spec.rules.grashof)
    if anchor is None or anchor[1] >= 0.0:
        return None
    return {"class": spec.rules.grashof, "best_smallest_slack_mm": anchor[1],
            "lengths_mm": [float(r) for r in anchor[0]],
            "note": f"no {spec.rules.grashof} fits in the bounds of r1..r4 (the best smallest Grashof slack there "
                    f"is {anchor[1]:.3g} mm): widen the bounds of r1..r4 or choose another [rules] grashof"}


def finish(setting: Setting, best: StartReport) -> Finished:
    spec = setting.spec
    out = best.outcome
    crank, direction = out.details["crank_deg"], out.details["direction"]
    ev = best.context          # None: the design could not be evaluated (best.why says why)
    sign = -1.0 if direction == "cw" else 1.0
    facts = {**(path_facts(spec, ev) if ev is not None else {}), "crank_direction": direction,
             **dynamics_facts_of(spec, out.design, sign)}
    room = grashof_room(spec)
    if room is not None:
        facts["grashof_in_bounds"] = room
    return Finished(
        design=result_design(out.design, crank),
        objective={"name": OBJECTIVE, "value": out.objective, "unit": "mm^2"},
        facts=facts,
        trajectory=trajectory(spec, out.design, crank, sign),
        solver_settings={"stop_at_objective": spec.solver.stop_at_objective, "samples": spec.solver.samples,
                         "mu_strategy": spec.solver.mu_strategy},
        rules=None if ev is not None else unevaluated(spec, best.why),
        note=spec.targets.same_targets_note())


def unevaluated(spec: FourbarPathSpec, why: str | None) -> list[dict]:
    """The rule table of a design that cannot be evaluated: every rule of the spec, "not evaluated", and why."""
    rules = path_rules(spec, spec.design_values(), None, 1.0, spec.solver.samples)
    return [not_evaluated(r.name, r.lower, r.upper, r.unit, r.where, why or "").record().to_json() for r in rules]


def baseline_rules(setting: Setting) -> list[dict] | None:
    """The rule table of the spec's given design, for the side-by-side table."""
    spec = setting.spec
    ev = evaluate(spec, spec.design_values(), spec.design.crank_deg)
    return [r.record().to_json() for r in ev.rules]


def reached(target: float, report: StartReport) -> bool:
    return report.satisfied and report.outcome.objective <= target


def stop_when(setting: Setting):
    """[solver] stop_at_objective: end the multistart at the first start, in start order, that reaches it."""
    target = setting.spec.solver.stop_at_objective
    return None if target is None else functools.partial(reached, target)


def auto_order(setting: Setting) -> bool:
    """``--starts auto`` takes the screened starts first (starts.auto_role) where the spec is screened."""
    return takes_auto_order(setting.spec)


SOLVING = Solving(build=build, recheck=recheck, finish=finish, baseline_rules=baseline_rules, stop_when=stop_when,
                  samples_hint='[solver] samples (grashof = "any")', auto_order=auto_order)
