"""Tolerance analysis of one design, for every kind that solves.

1. Exact sensitivities: the kind's NLP is built at the design (every fixed variable carried as a
   decision entry, the rules sampled on the re-check's 10x grid); its auxiliaries are put on their
   structural rows (Newton, AD Jacobian) and every rule sample's total derivative w.r.t. every design
   variable follows by the implicit function theorem (:mod:`synthesis.core.sensitivity`).
2. Linear stack-up per rule: min over its samples and sides of margin - sum_j |dg/dd_j| tol_j, and the
   variables that drive that worst sample.
3. Seeded Monte-Carlo: N designs drawn uniformly in the box, each re-checked by the kind's own float
   re-check (``Solving.recheck``): pass rate per rule and overall, worst sampled margin, and the ratio of
   the linear to the sampled margin loss (a uniform sample rarely reaches a corner of the box, where the
   linear worst case sits, so ratios above 1 are expected with many variables).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from synthesis.core.kind import Kind, Setting
from synthesis.core.outcome import StartOutcome
from synthesis.core.sensitivity import Sensitivity, linear_worst
from synthesis.errors import AgrisynthError, SpecError
from synthesis.spec.common import value_of
from synthesis.tolerance.design import DesignMap, box_of, design_map, fine, freed, kind_start, without_ipopt


@dataclass
class Linearised:
    """The design's rules with their exact derivatives (a :class:`Sensitivity` point)."""

    dmap: DesignMap
    design: dict
    rules: list            # the analysis NLP's Rule objects (symbolic)
    slices: list
    values: np.ndarray
    jacobian: np.ndarray   # rows x design variables (design units)

    def rule_jacobian(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        s = self.slices[k]
        return self.values[s], self.jacobian[s]


def linearise(kind: Kind, spec, design: dict, seed: int = 0) -> Linearised:
    """Values and dg/dd of every rule of ``spec`` at ``design`` (result.json keys, spec units)."""
    solving = kind.solver_side()
    aspec = fine(freed(spec))
    data = solving.prepare(aspec)
    with without_ipopt():
        nlp = solving.build(Setting(aspec, seed, data), False)
    dmap = design_map(kind.name, nlp, spec)
    missing = [k for k in dmap.keys if k not in design]
    if missing:
        raise SpecError(f"{kind.name}: the design has no value for {', '.join(missing)}")
    d = np.array([value_of(design[k]) for k in dmap.keys])
    compiled, x0, p = kind_start(nlp, d)
    x0[:dmap.n] = dmap.coordinates(d)
    sens = Sensitivity(compiled.problem, dmap.n, dmap.J)
    x = sens.pin(x0, p)
    pt = sens.at(x, p)
    return Linearised(dmap, {k: float(v) for k, v in zip(dmap.keys, d)}, list(compiled.problem.rules), sens.slices,
                      pt.values, pt.jacobian)


def stack_up(lin: Linearised, box: np.ndarray, drivers: int = 3) -> list[dict]:
    """Per rule: nominal margin on the analysis grid, linear worst-case margin, the derivative of the
    rule's value at its worst nominal sample w.r.t. every design variable, and the drivers of the worst."""
    rows = []
    for k, rule in enumerate(lin.rules):
        values, J = lin.rule_jacobian(k)
        nominal, worst = linear_worst(values, rule.lower, rule.upper, J, box)
        i_nom, i_lin = int(np.argmin(nominal)), int(np.argmin(worst))
        contrib = np.abs(J[i_lin]) * box
        order = [j for j in np.argsort(-contrib) if contrib[j] > 0][:drivers]
        rows.append({
            "name": rule.name, "unit": rule.unit, "scale": rule.scale,
            "value": float(values[i_nom]), "nominal_margin": float(nominal[i_nom]),
            "linear_worst_margin": float(worst[i_lin]),
            "linear_loss": float(nominal[i_lin] - worst[i_lin]) if math.isfinite(nominal[i_lin]) else None,
            "sensitivity": {key: float(J[i_nom, j]) for j, key in enumerate(lin.dmap.keys)},
            "drivers": [{"variable": lin.dmap.keys[j], "contribution": float(contrib[j])} for j in order],
        })
    return rows


def monte_carlo(kind: Kind, spec, design: dict, dmap: DesignMap, box: np.ndarray, samples: int, seed: int,
                setting_seed: int = 0) -> dict:
    """``samples`` designs uniform in the box (numpy default_rng(seed)), each re-checked by the kind."""
    solving = kind.solver_side()
    setting = Setting(spec, setting_seed, solving.prepare(spec))
    rng = np.random.default_rng(seed)
    offsets = rng.uniform(-1.0, 1.0, size=(samples, dmap.n)) * box
    passed: dict[str, int] = {}
    worst: dict[str, float] = {}
    all_pass = unevaluable = 0
    t0 = time.perf_counter()
    for i in range(samples):
        trial = dict(design)
        for j, key in enumerate(dmap.keys):
            trial[key] = design[key] + float(offsets[i, j])
        try:
            records = [r.record() for r in solving.recheck(setting, StartOutcome(i, trial, 0.0, "", True, 0, 0.0, "")).rules]
        except (AgrisynthError, ValueError, ArithmeticError):
            unevaluable += 1
            continue
        ok = True
        for r in records:
            passed[r.name] = passed.get(r.name, 0) + int(bool(r.satisfied))
            m = -math.inf if r.margin is None else r.margin
            worst[r.name] = min(worst.get(r.name, math.inf), m)
            ok = ok and bool(r.satisfied)
        all_pass += int(ok)
    return {"samples": samples, "seed": seed, "distribution": "uniform in the tolerance box",
            "pass_rate": all_pass / samples if samples else None, "unevaluable": unevaluable,
            "rules": {n: {"pass_rate": passed[n] / samples, "worst_margin": worst[n] if math.isfinite(worst[n]) else None}
                      for n in passed},
            "wall_s": time.perf_counter() - t0}


def analyse(kind: Kind, spec, design: dict, *, length: float | None, angle: float | None,
            per_variable: dict[str, float] | None = None, samples: int = 1000, seed: int = 0) -> dict:
    """The whole analysis as result.json ``facts`` (see the module docstring), with the nominal re-check."""
    lin = linearise(kind, spec, design, seed)
    box = box_of(lin.dmap, length, angle, per_variable or {})
    rows = stack_up(lin, box)
    solving = kind.solver_side()
    nominal = [r.record() for r in solving.recheck(Setting(spec, seed, solving.prepare(spec)),
                                                   StartOutcome(0, dict(lin.design), 0.0, "", True, 0, 0.0, "")).rules]
    mc = monte_carlo(kind, spec, lin.design, lin.dmap, box, samples, seed)
    recheck = {r.name: r for r in nominal}
    for row in rows:
        r = recheck.get(row["name"])
        row["recheck_margin"] = None if r is None else r.margin
        m = mc["rules"].get(row["name"], {})
        row["mc_pass_rate"], row["mc_worst_margin"] = m.get("pass_rate"), m.get("worst_margin")
        base = row["recheck_margin"]
        if base is not None and row["mc_worst_margin"] is not None and row["linear_loss"] is not None:
            sampled_loss = base - row["mc_worst_margin"]
            row["sampled_loss"] = sampled_loss
            row["linear_over_sampled"] = row["linear_loss"] / sampled_loss if sampled_loss > 1e-12 else None
        else:
            row["sampled_loss"] = row["linear_over_sampled"] = None
    return {"design": lin.design, "nominal_rules": [r.to_json() for r in nominal],
            "tolerance": {key: {"half_width": float(b), "unit": u} for key, b, u in zip(lin.dmap.keys, box, lin.dmap.units)},
            "stack_up": rows, "monte_carlo": mc,
            "method": "exact AD sensitivities (implicit function theorem through the structural rows), rules on "
                      "the re-check's 10x grid; Monte-Carlo with the kind's float re-check"}
