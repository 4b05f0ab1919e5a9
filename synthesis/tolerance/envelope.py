"""``solve`` of a spec with an operating condition given as a range (an operating envelope), for every
kind whose NLP declares its operating conditions (:class:`synthesis.core.problem.Operating`).

The kind's NLP reads the ranges from the spec: the core holds every rule that depends on a sampled condition
once per sampled value (``<rule>@forward_speed=0.5833``, one shared design; :mod:`synthesis.core.problem`).
:func:`envelope_kind` wraps the kind's :class:`~synthesis.core.kind.Solving` so that every start is re-checked,
independently of the solver, at every point of the re-check's finer grid of the ranges (the kind's own float
re-check of the spec at that operating point): one ``<rule>@envelope`` row per rule whose value changes over
the range (its worst point), beside the nominal rows, so a start is feasible only if every rule holds over
the whole grid; the result's ``facts.envelope`` holds each such rule's value at every grid point (the
report's ``envelope.png``).
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np

from synthesis.constraints.base import Rule
from synthesis.core.kind import Finished, Kind, Setting, Solving
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import scenario_label
from synthesis.core.verdict import Recheck
from synthesis.spec.design_info import describe
from synthesis.errors import AgrisynthError
from synthesis.spec.common import value_of
from synthesis.spec.operating import at_operating, ranges_of

SUFFIX = "@envelope"


def grid_of(spec) -> list[dict[str, float]]:
    """Every point of the re-check's grid: each range's re-check values, all combinations."""
    ranges = ranges_of(spec)
    names = list(ranges)
    return [dict(zip(names, combo)) for combo in itertools.product(*(ranges[n][1].recheck_values() for n in names))]


class _Points:
    """The settings of the grid's operating points (the kind's ``prepare`` once per point and process)."""

    def __init__(self, solving: Solving):
        self.solving = solving
        self.cache: dict = {}

    def __call__(self, setting: Setting, values: dict[str, float]) -> Setting:
        key = (id(setting.spec), tuple(values.items()))
        if key not in self.cache:
            spec = at_operating(setting.spec, values)
            self.cache[key] = (setting.spec, Setting(spec, setting.seed, self.solving.prepare(spec)))
        return self.cache[key][1]


def _varies(rules_at: list[list[Rule]], k: int) -> bool:
    """Whether rule k's value changes over the grid (missing somewhere counts as changing)."""
    first = None
    for rules in rules_at:
        r = rules[k]
        if r.missing is not None:
            return True
        v = np.atleast_1d(np.asarray(r.expr, float)).ravel()
        if first is None:
            first = v
        elif v.shape != first.shape or np.any(np.abs(v - first) > 1e-12 * max(1.0, float(np.max(np.abs(first))))):
            return True
    return False


def envelope_rules(grid: list[dict], rules_at: list[list[Rule]]) -> tuple[list[Rule], dict]:
    """``<rule>@envelope`` Rules (every grid point's samples; the record is the worst) and the per-point table."""
    out, table = [], {}
    base = rules_at[0]
    for k, rule in enumerate(base):
        if any(len(rules) != len(base) or rules[k].name != rule.name for rules in rules_at):
            raise ValueError(f"the rules differ between operating points (at rule {rule.name})")
        if not _varies(rules_at, k):
            continue
        records = [rules[k].record() for rules in rules_at]
        margins = [(-math.inf if r.margin is None else r.margin) for r in records]
        worst = int(np.argmin(margins))
        label = scenario_label(grid[worst])
        missing = next((f"{r.note or 'not evaluated'} at {scenario_label(g)}" for r, g in zip(records, grid)
                        if r.value is None), None)
        expr = None if missing else np.concatenate([np.atleast_1d(np.asarray(rules[k].expr, float)).ravel()
                                                     for rules in rules_at])
        span = ", ".join(f"{n} {min(g[n] for g in grid):g}-{max(g[n] for g in grid):g}" for n in grid[0])
        out.append(dataclasses.replace(rule, name=rule.name + SUFFIX, expr=expr, nlp_rows=(), box_rows=(), missing=missing,
                                       where=f"over {span} ({len(grid)} points), worst at {label}"))
        table[rule.name] = {"unit": rule.unit, "limit": [rule.lower, rule.upper],
                            "values": [r.value for r in records], "margins": [r.margin for r in records],
                            "worst_at": grid[worst], "worst_margin": None if missing else records[worst].margin,
                            "satisfied": all(r.satisfied for r in records)}
    return out, table


@dataclasses.dataclass
class EnvelopeRecheck:
    """The kind's re-check at the nominal point, plus one ``@envelope`` row per rule that changes over the grid."""

    base: object
    points: _Points

    def over_grid(self, setting: Setting, outcome) -> tuple[Recheck, list[dict], list[list[Rule]]]:
        nominal = self.base(setting, outcome)
        grid = grid_of(setting.spec)
        rules_at = [list(self.base(self.points(setting, values), outcome).rules) for values in grid]
        return nominal, grid, rules_at

    def __call__(self, setting: Setting, outcome) -> Recheck:
        nominal, grid, rules_at = self.over_grid(setting, outcome)
        extra, _ = envelope_rules(grid, rules_at)
        return Recheck(list(nominal.rules) + extra, nominal.context, nominal.objective, nominal.invalid)


@dataclasses.dataclass
class EnvelopeFinish:
    base: object
    recheck: EnvelopeRecheck

    def __call__(self, setting: Setting, best) -> Finished:
        finished = self.base(setting, best)
        facts = dict(finished.facts)
        if best.why is None:
            _, grid, rules_at = self.recheck.over_grid(setting, best.outcome)
            _, table = envelope_rules(grid, rules_at)
            ranges = ranges_of(setting.spec)
            facts["envelope"] = {
                "conditions": {n: {"range": list(r.range), "nominal": r.centre, "solver_values": list(r.solver_values()),
                                   "recheck_values": list(r.recheck_values()), "section": field}
                               for n, (field, r) in ranges.items()},
                "grid": grid, "rules": table,
                "all_satisfied": all(row["satisfied"] for row in table.values()),
                "method": "the NLP holds every rule that depends on a sampled condition at each solver value (one "
                          "shared design); the kind's float re-check runs at every re-check value",
            }
        return dataclasses.replace(finished, facts=facts)


def given_design(spec) -> dict[str, float]:
    """The spec's given design by result.json key (each variable's number or start value, as the spec model lists
    it; read by walking its TOML path, clamp_cam's ``motion.return`` -- attribute ``return_`` -- was an
    AttributeError after every start had finished)."""
    described = describe(spec)
    return {key: value_of(v) for key, v in spec.variables().items() if key in described}


@dataclasses.dataclass
class EnvelopeBaseline:
    """The given design's rule table with its ``@envelope`` rows (none when it cannot be evaluated over the grid)."""

    base: object
    recheck: EnvelopeRecheck

    def __call__(self, setting: Setting) -> list[dict] | None:
        rows = self.base(setting)
        if rows is None:
            return None
        try:
            outcome = StartOutcome(0, given_design(setting.spec), 0.0, "", True, 0, 0.0, "")
            _, grid, rules_at = self.recheck.over_grid(setting, outcome)
            extra, _ = envelope_rules(grid, rules_at)
        except (AgrisynthError, ValueError, ArithmeticError):    # the given design fails to evaluate somewhere
            return rows                                          # (a programming error still raises)
        return rows + [r.record().to_json() for r in extra]


def envelope_kind(kind: Kind, spec) -> Kind:
    """The kind, re-checking over the spec's operating ranges (the kind itself when the spec has none)."""
    if not ranges_of(spec):
        return kind
    base = kind.solving()
    if isinstance(base.recheck, EnvelopeRecheck):       # wrapped already (a robust solve's kind, re-wrapped)
        return kind
    recheck = EnvelopeRecheck(base.recheck, _Points(base))
    names = ", ".join(f"{n} {r.range[0]:g}-{r.range[1]:g}" for n, (_, r) in ranges_of(spec).items())
    hint = (f"Every rule must hold over the operating range ({names}): narrow the range, or loosen those rules. ")
    solving = dataclasses.replace(base, recheck=recheck, finish=EnvelopeFinish(base.finish, recheck),
                                  baseline_rules=EnvelopeBaseline(base.baseline_rules, recheck),
                                  relax_hint=hint + base.relax_hint)

    return kind.solving_with(solving)


def plot(result, path) -> None:
    """envelope.png: each rule that changes over the range, its value against the condition, with its limit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    env = result.extra["envelope"]
    grid, rules = env["grid"], env["rules"]
    names = list(env["conditions"])
    x_name = names[0]
    fig, axes = plt.subplots(len(rules), 1, figsize=(7, 2.4 * max(1, len(rules))), squeeze=False)
    for ax, (rule, row) in zip(axes[:, 0], rules.items()):
        others = sorted({tuple((n, g[n]) for n in names[1:]) for g in grid})
        for other in others:
            idx = [i for i, g in enumerate(grid) if tuple((n, g[n]) for n in names[1:]) == other]
            xs = [grid[i][x_name] for i in idx]
            ys = [np.nan if row["values"][i] is None else row["values"][i] for i in idx]
            ax.plot(xs, ys, marker=".", label=scenario_label(dict(other)) or None)
        for lim, style in zip(row["limit"], ("--", ":")):
            if lim is not None:
                ax.axhline(lim, color="red", linestyle=style, linewidth=1)
        for v in env["conditions"][x_name]["solver_values"]:
            ax.axvline(v, color="grey", linewidth=0.5)
        ax.set_ylabel(f"{rule} ({row['unit']})", fontsize=8)
        if len(others) > 1:
            ax.legend(fontsize=7)
    axes[-1, 0].set_xlabel(f"{x_name} (grey: the solver's samples; red: the rule's limit)")
    fig.suptitle(f"{result.name}: rules over the operating range")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
