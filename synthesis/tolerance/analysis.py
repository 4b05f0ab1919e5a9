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
   linear worst case sits, so ratios above 1 are expected with many variables).  The samples are re-checked in
   batches on the core's process pool (:mod:`synthesis.core.executor`), each by the same float re-check wherever it
   runs, so the numbers are the same for any number of workers; why samples could not be evaluated is counted by
   reason (:func:`unevaluable_reasons`).
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass

import numpy as np

from synthesis.constraints import not_evaluated
from synthesis.constraints.base import RuleRecord
from synthesis.core import interrupt
from synthesis.core.executor import default_workers, run_starts
from synthesis.core.kind import Kind, Setting
from synthesis.core.outcome import StartOutcome
from synthesis.core.sensitivity import Sensitivity, linear_worst
from synthesis.errors import AgrisynthError, SpecError
from synthesis.spec.common import value_of
from synthesis.spec.operating import at_operating, ranges_of
from synthesis.tolerance.design import (DesignMap, box_of, design_map, fine, freed, kind_start, refuse_crossing_zero,
                                        whole_problem)
from synthesis.tolerance.envelope import SUFFIX, envelope_kind, grid_of


@dataclass
class Linearised:
    """The design's rules with their exact derivatives (a :class:`Sensitivity` point)."""

    dmap: DesignMap
    design: dict
    rules: list            # the analysis NLP's Rule objects (symbolic)
    slices: list
    values: np.ndarray
    jacobian: np.ndarray   # rows x design variables (design units)
    #: operating conditions the NLP was written in (an envelope spec): names, units, rows x conditions, and
    #: the values each rule was resolved at (nominal, or its scenario's); None without
    operating: tuple | None = None
    operating_points: list | None = None
    #: the margins form too ((values, jacobian, slices)) where a rule's NLP rows are the rule itself
    #: (Rule.rows_are_the_rule: an exact minimum, a max()'s branches): its worst case is read there, not at a sample
    #: off the exact minimum or on a max()'s kink, where the derivative of the value is another one
    held: tuple | None = None

    def rule_jacobian(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        s = self.slices[k]
        return self.values[s], self.jacobian[s]


def linearise(kind: Kind, spec, design: dict, seed: int = 0) -> Linearised:
    """Values and dg/dd of every rule of ``spec`` at ``design`` (result.json keys, spec units), and of the margins
    of the NLP's rows of the rules whose rows are the rule itself (``Linearised.held``)."""
    solving = kind.solving()
    aspec = fine(freed(spec))
    data = solving.prepare(aspec)
    # every operating condition a symbol (resolved at its nominal value, the rules' values unchanged): the
    # derivatives w.r.t. forward speed, crank speed, friction, ... of a nominal spec too
    # (no IPOPT instance: the problem is evaluated, never solved)
    nlp = solving.build(Setting(aspec, seed, data, operating_symbols=True, solver=False), False)
    whole_problem(nlp)         # every rule as the whole problem holds it (not the configuration form)
    dmap = design_map(kind, nlp, spec)
    missing = [k for k in dmap.keys if k not in design]
    if missing:
        raise SpecError(f"{kind.name}: the design has no value for {', '.join(missing)}")
    d = np.array([value_of(design[k]) for k in dmap.keys])
    compiled, x0, p = kind_start(nlp, d)
    x0[:dmap.n] = dmap.coordinates(d)
    # the answer's own auxiliaries (the crank angles of its targets, say), where the kind's answer holds them
    x0, p = nlp.answer_start(design, x0, np.asarray(p, float), dmap.n)
    sens = Sensitivity(compiled.problem, dmap.n, dmap.J)
    x = sens.pin(x0, p)
    pt = sens.at(x, p)
    held = None
    if any(r.rows_are_the_rule for r in compiled.problem.rules):
        rows = Sensitivity(compiled.problem, dmap.n, dmap.J, True)
        at_rows = rows.at(x, p)
        held = (at_rows.values, at_rows.jacobian, rows.slices)
    src = compiled.problem.operating_source
    ops = sens.operating(x, p)
    ops = None if ops is None else (*ops, dict(src.nominal))
    return Linearised(dmap, {k: float(v) for k, v in zip(dmap.keys, d)}, list(compiled.problem.rules), sens.slices,
                      pt.values, pt.jacobian, ops, None if src is None else [dict(v) for _, v in src.rules],
                      held)


def stack_up(lin: Linearised, box: np.ndarray, drivers: int = 3) -> list[dict]:
    """Per rule: nominal margin on the analysis grid, linear worst-case margin, the derivative of the
    rule's value at its worst nominal sample w.r.t. every design variable, and the drivers of the worst."""
    rows = []
    # a follower moves with the variables it follows (DesignMap.moves): the stack-up is over the variables the box
    # moves on their own, each rule's derivative in them the chain rule's (J T); its sensitivities stay J's own
    T = lin.dmap.moves if lin.dmap.followers else None
    for k, rule in enumerate(lin.rules):
        values, own = lin.rule_jacobian(k)
        J = own if T is None else own @ T
        lower, upper = rule.lower, rule.upper
        nominal, worst = linear_worst(values, lower, upper, J, box)
        i_nom = int(np.argmin(nominal))
        value, gradient = float(values[i_nom]), own[i_nom]       # the value at its worst sample, its own derivative
        if lin.held is not None and rule.rows_are_the_rule:        # the worst case on the rows the NLP holds
            values, J = lin.held[0][lin.held[2][k]], lin.held[1][lin.held[2][k]]
            J = J if T is None else J @ T
            lower, upper = 0.0, None
            nominal, worst = linear_worst(values, lower, upper, J, box)
        i_lin = int(np.argmin(worst))
        contrib = np.abs(J[i_lin]) * box
        corner = _corner(values[i_lin], lower, upper, J[i_lin], box)
        order = [j for j in np.argsort(-contrib) if contrib[j] > 0][:drivers]
        rows.append({
            "name": rule.name, "unit": rule.unit, "scale": rule.scale,
            "value": value, "nominal_margin": float(np.min(nominal)),
            "linear_worst_margin": float(worst[i_lin]),
            "linear_loss": float(nominal[i_lin] - worst[i_lin]) if math.isfinite(nominal[i_lin]) else None,
            "sensitivity": {key: float(gradient[j]) for j, key in enumerate(lin.dmap.keys)},
            # the box's corner the linear stack-up puts this rule's worst at (sign of dg/dd at its worst sample,
            # towards the nearer limit): the nonlinear re-check there is the sampled worst case to compare with
            "corner": [float(c) for c in (corner if T is None else T @ corner)],
            "drivers": [{"variable": lin.dmap.keys[j], "contribution": float(contrib[j])} for j in order],
            # every variable's share of the stack-up at that worst sample, |dg/dx| tol, signed as the margin to the
            # nearer limit moves when the variable moves by +tol (the corner moves each the way that lowers it)
            "contributions": {lin.dmap.keys[j]: float(-np.sign(c) * contrib[j]) if c else 0.0
                              for j, c in enumerate(corner)},
            # the margin at that worst sample -- to either limit, the nearer one -- and its linear change when each
            # variable alone moves by +tol and by -tol: what the tornado draws (a two-sided rule's margin gained
            # towards one limit is capped by the other: the contributions alone drew a rocker swing held 0.05 deg
            # inside [49.9, 50.1] gaining 0.24 deg where the move breaks its upper limit)
            "worst_sample_margin": _margin(values[i_lin], lower, upper),
            "margin_change": {lin.dmap.keys[j]: [_margin(values[i_lin] + d, lower, upper)
                                                 - _margin(values[i_lin], lower, upper) for d in (step, -step)]
                              for j, step in enumerate(J[i_lin] * box)},
        })
        if lin.operating is not None:
            names, _, W, _ = lin.operating
            rows[-1]["operating_point"] = lin.operating_points[k]
            rows[-1]["operating_sensitivity"] = {n: float(W[lin.slices[k]][i_nom, i]) for i, n in enumerate(names)}
    return rows


def operating_dependence(lin: Linearised) -> dict[str, list[str]]:
    """Per operating condition, the rules whose value moves with it (a non-zero derivative at any of its samples):
    an empty list says in result.json that no rule depends on it, rather than leaving the condition out (it may
    still move a limit or the objective, which are not rule values)."""
    names, _, W, _ = lin.operating
    return {n: [rule.name for k, rule in enumerate(lin.rules) if np.any(W[lin.slices[k], i] != 0.0)]
            for i, n in enumerate(names)}


def _margin(value: float, lower, upper) -> float:
    """The margin of a value to the nearer of its limits (a missing limit is no limit)."""
    return float(min(math.inf if lower is None else value - lower, math.inf if upper is None else upper - value))


def _corner(value: float, lower, upper, grad: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Offsets to the corner of the box where a linear rule value moves furthest towards its nearer limit."""
    lo = -math.inf if lower is None else value - lower
    hi = -math.inf if upper is None else upper - value
    towards = -1.0 if (lower is not None and (upper is None or lo <= hi)) else 1.0
    return towards * np.sign(grad) * box


#: the issue's bound on |linear loss - sampled loss| / sampled loss; a rule above it gets an explanation
GAP_LIMIT = 0.10


class _Settings:
    """The re-check's setting of each stack-up row: the spec's, or for a rule held at an envelope's scenario
    (``<rule>@<condition>=<value>``) the spec at that operating point, where the re-check names it ``<rule>``."""

    def __init__(self, solving, spec, seed: int):
        self.solving, self.spec, self.seed, self.cache = solving, spec, seed, {}

    def __call__(self, row: dict) -> tuple[Setting, str]:
        point = row.get("operating_point") if "@" in row["name"] else None
        key = None if point is None else tuple(sorted(point.items()))
        if key not in self.cache:
            spec = self.spec if point is None else at_operating(self.spec, point)
            self.cache[key] = Setting(spec, self.seed, self.solving.prepare(spec))
        return self.cache[key], row["name"].split("@")[0]


def _margin_at(solving, setting, design: dict, dmap: DesignMap, offsets, name: str) -> tuple[float | None, str | None]:
    """(margin of rule ``name`` at design + offsets by the kind's float re-check, or None and why)."""
    trial = dict(design)
    for key, off in zip(dmap.keys, offsets):
        trial[key] = design[key] + float(off)
    try:
        records = {r.name: r.record() for r in
                   solving.recheck(setting, StartOutcome(0, trial, 0.0, "", True, 0, 0.0, "")).rules}
    except (AgrisynthError, ValueError, ArithmeticError) as exc:
        return None, f"not evaluable: {exc}"
    r = records.get(name)
    if r is None or r.margin is None:
        return None, "not evaluated" + (f": {r.note}" if r is not None and r.note else "")
    return float(r.margin), None


def corner_margins(kind: Kind, spec, design: dict, dmap: DesignMap, rows: list[dict], seed: int = 0) -> None:
    """Each stack-up row's nonlinear margin at its linear worst corner (``corner_margin``, the kind's float
    re-check; None with the reason in ``corner_note`` when that design cannot be evaluated)."""
    solving = kind.solving()
    settings = _Settings(solving, spec, seed)
    for row in rows:
        with interrupt.deferred():          # obeyed between rows, as between Monte-Carlo samples
            setting, name = settings(row)
            row["corner_margin"], note = _margin_at(solving, setting, design, dmap, row["corner"], name)
        row["corner_note"] = None if note is None else f"at the linear worst corner: {note}"


def explain_gaps(kind: Kind, spec, design: dict, dmap: DesignMap, rows: list[dict], seed: int = 0) -> None:
    """``gap_explanation`` of every row whose linear-vs-sampled gap exceeds :data:`GAP_LIMIT` (None elsewhere).

    The rule is re-checked at half the corner's offsets: a smooth rule's second-order term grows with the square
    of the offset, so its relative gap about halves ("second order"); a gap that does not shrink so is a kink
    (the worst sample switching, a max/min of the rule, an active bound).  The absolute difference is stated
    against the nominal margin, which is what the robust transcription's linear worst case gives away."""
    solving = kind.solving()
    settings = _Settings(solving, spec, seed)
    for row in rows:
        row["gap_explanation"] = None
        gap, base = row.get("linear_vs_sampled_gap"), row.get("recheck_margin")
        unit = row.get("recheck_unit") or row["unit"]
        shown_unit = "" if unit in ("", "-", "1") else f" {unit}"
        if gap is None:
            sampled = row.get("sampled_worst_margin")
            if (row["linear_loss"] == 0 and base is not None and sampled is not None
                    and base - sampled > 1e-9 * max(1.0, abs(base))):
                # the rows move with the NLP's own variables only (free crank angles), which the re-check finds anew
                # for each sampled design: the nominal margins agree, and "other terms" would be wrong
                row["gap_explanation"] = (f"not compared: no linear driver (the rule's first derivatives in the "
                                          f"design variables are 0: its NLP rows move only with the NLP's own "
                                          f"variables, e.g. free crank angles, which the re-check finds anew for each "
                                          f"design, or the design sits at the rule's extremum); the samples lose "
                                          f"{base - sampled:.3g}{shown_unit}")
            elif base is not None and row["linear_loss"] is not None and not row["same_terms"]:
                row["gap_explanation"] = (f"not compared: the NLP writes this rule in other terms than the re-check "
                                          f"reports (nominal margin {row['nominal_margin']:.4g} in the NLP's, "
                                          f"{base:.4g} {row.get('recheck_unit', row['unit'])} in the re-check's)")
            elif base is None or row.get("sampled_worst_margin") is None or row["linear_loss"] is None:
                row["gap_explanation"] = "not compared: " + (row.get("corner_note") or "the rule is not evaluated")
            else:
                row["gap_explanation"] = (f"not compared: no margin loss (linear {row['linear_loss']:.3g}, sampled "
                                          f"{base - row['sampled_worst_margin']:.3g} {row['unit']}): the rule's value "
                                          "does not move with the design in the box")
            continue
        if gap <= GAP_LIMIT:
            continue
        diff = row["linear_worst_margin"] - row["sampled_worst_margin"]
        share = f"{abs(diff):.3g}{shown_unit}" + (f" = {100 * abs(diff) / abs(base):.2g} % of the nominal margin"
                                                    if base != 0 else " (the nominal margin is 0: the design is on the limit)")
        if row.get("corner_margin") is None:
            # the linear worst corner could not be re-checked: the sampled worst case is the Monte-Carlo's alone, which
            # rarely comes near a corner -- nothing says whether the rule curves or kinks there
            why = (row.get("corner_note") or "at the linear worst corner: not evaluable").removeprefix(
                "at the linear worst corner: ")
            row["gap_explanation"] = (f"gap {gap:.1%}: the linear worst corner is not evaluable ({why}), so only the "
                                      f"Monte-Carlo samples were compared (they rarely reach a corner of the box); the "
                                      f"linear worst case is {'above' if diff > 0 else 'below'} the worst sample by "
                                      f"{share}")
            continue
        with interrupt.deferred():          # obeyed between rows, as between Monte-Carlo samples
            setting, name = settings(row)
            half, note = _margin_at(solving, setting, design, dmap, 0.5 * np.asarray(row["corner"]), name)
        lin_half = base - 0.5 * row["linear_loss"]
        if half is None or base - half <= 0:
            row["gap_explanation"] = f"gap {gap:.1%}: {share}; at half the tolerance {note or 'no loss'}"
            continue
        gap_half = abs(lin_half - half) / (base - half)
        row["half_tolerance_gap"] = gap_half
        what = ("second order (the rule curves: the gap about halves at half the tolerance)"
                if gap_half <= 0.65 * gap else "a kink (the gap does not shrink with the tolerance)")
        row["gap_explanation"] = (f"gap {gap:.1%} at the tolerance, {gap_half:.1%} at half of it: {what}; "
                                  f"the linear worst case is {'optimistic' if diff > 0 else 'conservative'} by {share}")


#: samples one task of the Monte-Carlo's process pool re-checks (a task's overhead is a few ms; a sample's re-check
#: is some 10-100 ms)
BATCH = 16

#: a number in a reason, read out to count reasons that differ only in their figures as one
_NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


@dataclass(frozen=True)
class Sample:
    """One Monte-Carlo sample re-checked: per rule (name, margin, satisfied, note), or why the re-check raised."""

    rules: list | None
    raised: str | None = None


@dataclass(frozen=True)
class _Batch:
    """The samples of one task of the pool (``start``: the task's index, as the core's pool names a task)."""

    start: int
    samples: list | None
    failure: str | None = None


@dataclass(frozen=True)
class SampleChecker:
    """The kind's float re-check of the Monte-Carlo's samples, ``BATCH`` per task; built once per worker process
    (the core's pool calls it as a start's solver: ``solve(task, _)``)."""

    solving: object
    setting: Setting
    design: dict
    keys: tuple
    offsets: np.ndarray
    batch: int = BATCH

    def __call__(self) -> "SampleChecker":
        """The pool's factory of a worker's solver: the checker itself (built and sent once per worker)."""
        return self

    def solve(self, task: int, _unused=None) -> _Batch:
        first = task * self.batch
        return _Batch(task, [self.sample(i) for i in range(first, min(first + self.batch, len(self.offsets)))])

    def sample(self, i: int) -> Sample:
        trial = dict(self.design)
        for j, key in enumerate(self.keys):
            trial[key] = self.design[key] + float(self.offsets[i, j])
        try:
            # a signal is obeyed between samples (raised as KeyboardInterrupt once the sample is done), never inside
            # one: raised inside a CasADi call it came out as a NotImplementedError traceback, or was swallowed and
            # the remaining thousands of samples run on
            with interrupt.deferred():
                records = [r.record() for r in
                           self.solving.recheck(self.setting, StartOutcome(i, trial, 0.0, "", True, 0, 0.0, "")).rules]
        except (AgrisynthError, ValueError, ArithmeticError) as exc:
            return Sample(None, " ".join(str(exc).split()) or type(exc).__name__)
        return Sample([(r.name, r.margin, bool(r.satisfied), getattr(r, "note", None)) for r in records])


def _failed_batch(task: int, status: str, reason: str) -> _Batch:
    return _Batch(task, None, f"{status}: {reason}")


def check_samples(solving, setting: Setting, design: dict, keys, offsets: np.ndarray,
                  workers: int | None = None) -> list[Sample]:
    """Every sample re-checked by the kind, in sample order, on the core's process pool (``workers``; None: one per
    core, never more than there are tasks; 1: in this process).  Each sample is the same float re-check wherever
    it runs, so the list is the same for any number of workers."""
    tasks = -(-len(offsets) // BATCH)
    workers = min(default_workers() if workers is None else workers, tasks)
    checker = SampleChecker(solving, setting, dict(design), tuple(keys), np.asarray(offsets, float))
    batches = run_starts(checker, np.zeros((tasks, 0)), workers, failure=_failed_batch) if tasks else []
    failed = next((b for b in batches if b.samples is None), None)
    if failed is not None:       # not a design the kind cannot evaluate (those are samples): a defect, or a crash
        raise RuntimeError(f"the Monte-Carlo's re-check of samples {failed.start * BATCH}-"
                           f"{min((failed.start + 1) * BATCH, len(offsets)) - 1} failed: {failed.failure}")
    return [s for b in batches for s in b.samples]


def monte_carlo(kind: Kind, spec, design: dict, dmap: DesignMap, box: np.ndarray, samples: int, seed: int,
                setting_seed: int = 0, workers: int | None = 1) -> dict:
    """``samples`` designs uniform in the box (numpy default_rng(seed)), each re-checked by the kind
    (:func:`check_samples`: on ``workers`` processes of the core's pool, None one per core; the same answer for any
    number.  One by default: a robust solve checks its answer in its own process, as its ``--workers`` asked).

    A spec with operating ranges (an envelope) re-checks each sampled design at every point of the re-check's
    grid of the ranges (the solve's own envelope re-check, :mod:`synthesis.tolerance.envelope`): a sample passes
    when every rule holds at the nominal point and at every grid point (``<rule>@envelope``: its worst point), so
    the pass rate reads "share of machines built within the tolerances that work over the whole range";
    ``pass_rate_at_nominal`` is the same samples at the nominal operating point only.  ``unevaluable_reasons``:
    why samples (or some of their rules) could not be evaluated, counted by reason (:func:`unevaluable_reasons`)."""
    ranges = ranges_of(spec)
    solving = envelope_kind(kind, spec).solving()
    setting = Setting(spec, setting_seed, solving.prepare(spec))
    rng = np.random.default_rng(seed)
    offsets = rng.uniform(-1.0, 1.0, size=(samples, dmap.n)) * box
    if dmap.followers:          # each follower where the variables it follows put it (DesignMap.moves)
        offsets = offsets @ dmap.moves.T
    t0 = time.perf_counter()
    checked = check_samples(solving, setting, design, dmap.keys, offsets, workers)
    within = "uniform in the tolerance box" + "".join(
        f" ({key} where {', '.join(others)} put it)" for key, others in dmap.moved_followers(box).items())
    out = {"samples": samples, "seed": seed, "distribution": within,
           **tally(checked, samples), "unevaluable_reasons": unevaluable_reasons(checked),
           "wall_s": time.perf_counter() - t0}
    if ranges:
        grid = grid_of(spec)
        span = ", ".join(f"{n} {r.range[0]:g}-{r.range[1]:g}" for n, (_, r) in ranges.items())
        out["distribution"] = (f"{within}, each design re-checked at the nominal operating point "
                               f"and at every one of the {len(grid)} points of the re-check grid over {span}")
        out["envelope"] = {"conditions": {n: list(r.range) for n, (_, r) in ranges.items()}, "points": len(grid),
                           "pass_rate_at_nominal": out.pop("pass_rate_at_nominal")}
    else:
        out.pop("pass_rate_at_nominal")
    return out


def tally(checked: list[Sample], samples: int) -> dict:
    """Pass rates (overall, at the nominal operating point, per rule), per rule the worst margin and the samples
    where it could not be evaluated, and the samples the re-check could not evaluate at all."""
    passed: dict[str, int] = {}
    worst: dict[str, float] = {}
    not_evaluated: dict[str, int] = {}       # per rule: samples where that rule could not be evaluated (no margin)
    all_pass = nominal_pass = unevaluable = 0
    verdicts: list[dict[str, bool]] = []     # per evaluated sample: rule name -> satisfied
    for sample in checked:
        if sample.rules is None:
            unevaluable += 1
            continue
        ok = at_nominal = True
        verdicts.append({name: satisfied for name, _, satisfied, _ in sample.rules})
        for name, margin, satisfied, _ in sample.rules:
            m = -math.inf if margin is None or not math.isfinite(margin) else margin
            worst[name] = min(worst.get(name, math.inf), m)
            if m == -math.inf:
                not_evaluated[name] = not_evaluated.get(name, 0) + 1
            ok = ok and satisfied
            if not name.endswith(SUFFIX):
                at_nominal = at_nominal and satisfied
        all_pass += int(ok)
        nominal_pass += int(at_nominal)
    # a <rule>@envelope row is written only where the rule's value changes over the grid; in a sample without it
    # the rule has its nominal value at every operating point, so its nominal verdict is its verdict over the range
    every_name = list(dict.fromkeys(n for v in verdicts for n in v))
    for held_in in verdicts:
        for name in every_name:
            held = held_in.get(name, held_in.get(name[:-len(SUFFIX)]) if name.endswith(SUFFIX) else None)
            passed[name] = passed.get(name, 0) + int(bool(held))
    partly = sum(1 for s in checked if s.rules is None or any(m is None or not math.isfinite(m) for _, m, _, _ in s.rules))
    return {"pass_rate": all_pass / samples if samples else None, "unevaluable": unevaluable,
            # samples the re-check could not evaluate at all, or where some rule has no margin
            "samples_not_fully_evaluable": partly,
            "pass_rate_at_nominal": nominal_pass / samples if samples else None,
            # a rule's worst_margin is null when it could not be evaluated in some sample (its "unevaluable" count;
            # "unevaluable" above counts the samples the re-check could not evaluate at all)
            "rules": {n: {"pass_rate": passed[n] / samples, "worst_margin": worst[n] if math.isfinite(worst[n]) else None,
                          "unevaluable": not_evaluated.get(n, 0)}
                      for n in passed}}


def _sample_causes(sample: Sample) -> dict[str, list[str]]:
    """Why a sample, or some of its rules, could not be evaluated: reason -> the rules it leaves without a margin
    (every rule: ``["(every rule)"]``).  A rule whose note ends in another's ("P2 not searched: P3 not found: ...")
    is that other's consequence and is counted under it."""
    if sample.rules is None:
        return {sample.raised: ["(every rule)"]}
    notes: dict[str, list[str]] = {}
    for name, margin, _, note in sample.rules:
        if margin is None or not math.isfinite(margin):
            notes.setdefault(note or "the margin is not a finite number", []).append(name)
    causes: dict[str, list[str]] = {}
    for text, names in notes.items():
        cause = min((t for t in notes if text.endswith(": " + t)), key=len, default=text)
        causes.setdefault(cause, []).extend(names)
    return causes


def unevaluable_reasons(checked: list[Sample]) -> list[dict]:
    """Every reason a sample (or some of its rules) could not be evaluated, counted: ``reason`` (the kind's words;
    figures that differ between samples shown as their range), ``samples`` (how many), ``rules`` (which it leaves
    without a margin), most frequent first.  Reasons that differ only in their figures count as one."""
    groups: dict[str, dict] = {}
    for sample in checked:
        for text, names in _sample_causes(sample).items():
            group = groups.setdefault(_NUMBER.sub("#", text), {"text": text, "figures": [], "samples": 0, "rules": {}})
            group["samples"] += 1
            group["figures"].append([float(f) for f in _NUMBER.findall(text)])
            group["rules"].update(dict.fromkeys(names))
    rows = [{"reason": _with_ranges(g["text"], g["figures"]), "samples": g["samples"], "rules": list(g["rules"])}
            for g in groups.values()]
    return sorted(rows, key=lambda r: -r["samples"])


def _with_ranges(text: str, figures: list[list[float]]) -> str:
    """``text`` with each figure that differs between the samples written as its range over them ("4.1 mm" ->
    "0.3-4.1 mm")."""
    columns = list(zip(*figures))
    parts = _NUMBER.split(text)
    out = [parts[0]]
    for k, (shown, rest) in enumerate(zip(_NUMBER.findall(text), parts[1:])):
        lo, hi = min(columns[k]), max(columns[k])
        out.append((shown if lo == hi else f"{lo:g} to {hi:g}") + rest)
    return "".join(out)


def _nominal_rules(solving, setting: Setting, lin: Linearised) -> list[RuleRecord]:
    """The design's rules by the kind's float re-check (10x grid).  A design the re-check cannot evaluate (a
    seedling that sticks on a guide tube's wall: the NLP has no sticking, so its derivatives exist) is still a
    design that fails its rules, not a solver failure: its table is the kind's table of the spec's given design
    (the design analysed), which evaluates what can be and fails the rest as not evaluated, else every rule
    not evaluated with the re-check's reason."""
    try:
        return [r.record() for r in solving.recheck(setting, StartOutcome(0, dict(lin.design), 0.0, "", True, 0,
                                                                          0.0, "")).rules]
    except (AgrisynthError, ValueError, ArithmeticError) as exc:
        why = str(exc)
    table = solving.baseline_rules(setting)
    if table:
        return [RuleRecord(**r) for r in table]
    return [not_evaluated(rule.name, rule.lower, rule.upper, rule.unit, "", why).record() for rule in lin.rules]


def _as_reported(row: dict, recheck: RuleRecord, rule) -> None:
    """A rule the NLP writes as a signed value within [-L, L] where the re-check reports its magnitude <= L (a cam's
    pressure angle) has its value and derivatives said in the re-check's terms: the signed angle -56.19 with
    d/d base_radius +0.48 is the magnitude 56.19 with -0.48 (a larger base circle lowers it).  A rule signed in both
    (a pitch curve's normal angle within [-L, L] on both sides) is left as it is, whichever extreme each grid found."""
    limit = list(recheck.limit) if isinstance(recheck.limit, (list, tuple)) else None
    if not (rule.lower is not None and rule.upper is not None and rule.lower == -rule.upper
            and limit is not None and len(limit) == 2 and limit[0] is None and limit[1] == rule.upper):
        return
    value, reported = row.get("value"), recheck.value
    if value is None or reported is None or value == 0.0 or not math.isfinite(value):
        return
    if abs(reported + value) > 1e-9 * max(1.0, abs(value)) or abs(reported - value) <= 1e-9 * max(1.0, abs(value)):
        return
    row["value"] = -value
    row["sensitivity"] = {k: None if v is None else -v for k, v in row["sensitivity"].items()}
    if "operating_sensitivity" in row:
        row["operating_sensitivity"] = {k: None if v is None else -v for k, v in row["operating_sensitivity"].items()}


def _not_evaluated_at_the_design(row: dict, note: str | None) -> None:
    """A rule the float re-check cannot evaluate at the design (a seedling that never reaches the wall end) has no
    stack-up: the NLP's smooth model has numbers there (or NaN), but they describe a motion the design does not make."""
    row.update(nominal_margin=None, linear_worst_margin=None, linear_loss=None, drivers=[], corner=None,
               corner_margin=None, sensitivity={k: None for k in row["sensitivity"]},
               contributions={k: None for k in row["contributions"]}, worst_sample_margin=None,
               margin_change={k: None for k in row["margin_change"]})
    if "operating_sensitivity" in row:
        row["operating_sensitivity"] = {k: None for k in row["operating_sensitivity"]}
    row["gap_explanation"] = "not compared: the rule is not evaluated at the design" + (f" ({note})" if note else "")


def tolerance_table(dmap: DesignMap, box: np.ndarray) -> dict:
    """result.json ``tolerance``: each variable's half-width and unit; a follower's is how far the box moves it, with
    ``follows`` (other -> d follower / d other) where that is more than 0."""
    out: dict = {key: {"half_width": float(b), "unit": u} for key, b, u in zip(dmap.keys, dmap.spread(box), dmap.units)}
    for key, others in dmap.moved_followers(box).items():      # as a robust solve's facts.tolerance.follows
        out[key]["follows"] = others
    return out


def analyse(kind: Kind, spec, design: dict, *, length: float | None, angle: float | None,
            per_variable: dict[str, float] | None = None, samples: int = 1000, seed: int = 0,
            workers: int | None = None) -> dict:
    """The whole analysis as result.json ``facts`` (see the module docstring), with the nominal re-check; the
    Monte-Carlo on ``workers`` processes (None: one per core)."""
    lin = linearise(kind, spec, design, seed)
    box = box_of(lin.dmap, length, angle, per_variable or {})
    refuse_crossing_zero(spec, lin.dmap, lin.design, box)
    rows = stack_up(lin, box)
    solving = kind.solving()
    nominal = _nominal_rules(solving, Setting(spec, seed, solving.prepare(spec)), lin)
    mc = monte_carlo(kind, spec, lin.design, lin.dmap, box, samples, seed, workers=workers)
    corner_margins(kind, spec, lin.design, lin.dmap, rows, seed)
    recheck = {r.name: r for r in nominal}
    settings = _Settings(solving, spec, seed)
    for row, rule in zip(rows, lin.rules):
        r = recheck.get(row["name"])
        if r is None and "@" in row["name"]:         # a rule held at an envelope's scenario: re-checked there
            setting, name = settings(row)
            r = next((q.record() for q in solving.recheck(setting, StartOutcome(0, dict(lin.design), 0.0, "", True, 0,
                                                                                  0.0, "")).rules if q.name == name),
                     None)
        if r is not None:
            _as_reported(row, r, rule)
        row["recheck_margin"] = None if r is None else r.margin
        row["recheck_unit"] = row["unit"] if r is None else r.unit      # margin, MC and corner columns: the re-check's
        m = mc["rules"].get(row["name"], {})
        row["mc_pass_rate"], row["mc_worst_margin"] = m.get("pass_rate"), m.get("worst_margin")
        row["mc_unevaluable"] = m.get("unevaluable", 0)
        base = row["recheck_margin"]
        if base is not None and row["mc_worst_margin"] is not None and row["linear_loss"] is not None:
            sampled_loss = base - row["mc_worst_margin"]
            row["sampled_loss"] = sampled_loss
            row["linear_over_sampled"] = row["linear_loss"] / sampled_loss if sampled_loss > 1e-12 else None
        else:
            row["sampled_loss"] = row["linear_over_sampled"] = None
        # the sampled worst case: the Monte-Carlo samples and the rule's linear worst corner; the gap is
        # |linear loss - sampled loss| / sampled loss
        worst = [m for m in (row["mc_worst_margin"], row["corner_margin"]) if m is not None]
        row["sampled_worst_margin"] = min(worst) if worst else None
        row["linear_vs_sampled_gap"] = None
        # the NLP may write a rule in other terms than the re-check reports (a curvature for a radius, cos^2 for an
        # angle): then the two losses are in different units and are not compared
        row["same_terms"] = (base is not None and row["linear_loss"] is not None
                             and abs(row["nominal_margin"] - base) <= 0.1 * max(row["linear_loss"], 1e-9 * max(1.0, abs(base))))
        if not row["same_terms"]:           # a ratio of losses in different units says nothing
            row["linear_over_sampled"] = None
        if row["same_terms"] and worst:
            loss = base - min(worst)
            if loss > 1e-9 * max(1.0, abs(row["scale"] or 1.0)):
                row["linear_vs_sampled_gap"] = abs(row["linear_loss"] - loss) / loss
    explain_gaps(kind, spec, lin.design, lin.dmap, rows, seed)
    for row in rows:
        r = recheck.get(row["name"])
        if r is not None and r.value is None:
            _not_evaluated_at_the_design(row, r.note)
    return {"design": lin.design, "nominal_rules": [r.to_json() for r in nominal],
            "tolerance": tolerance_table(lin.dmap, box),
            "stack_up": rows, "monte_carlo": mc,
            **({"operating": {n: {"unit": u, "nominal": lin.operating[3][n]}
                              for n, u in zip(lin.operating[0], lin.operating[1])},
                "operating_dependence": operating_dependence(lin)} if lin.operating else {}),
            "method": "exact AD sensitivities (implicit function theorem through the structural rows), rules on "
                      "the re-check's 10x grid; Monte-Carlo with the kind's float re-check"}
