"""One verdict for every kind: a start's fine-grid re-check, the best start, the run's status, the
elastic diagnosis and the exit-3 message.

A start's design is re-evaluated by the kind's own re-check (float kinematics, root-found extremes,
a grid 10x finer than the solver's samples), never by the NLP's constraint values.  The status is a
promise about the returned design:

    optimal     every rule holds on the fine grid and IPOPT met its full tolerances there (Solve_Succeeded)
    feasible    every rule holds on the fine grid; IPOPT stopped otherwise (acceptable level, iteration
                limit, even infeasibility reported against its backed-off rows): the status says so
    infeasible  no start satisfies every rule, and an elastic re-solve (one slack per rule) *converged*
                with slacks that name the rules giving way
    failed      anything else: nothing shows a conflict, IPOPT found no design (the message says what to try)
                (an elastic re-solve that needs no slack is first solved from as one more start: core.solve)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, cast

from synthesis.errors import AgrisynthError, SolverError
from synthesis.core.ipopt_log import reached_optimum

#: the fine re-check grid is this many times finer than the solver's samples (docs/ARCHITECTURE.md, "Verdicts")
FINE = 10
#: objectives within this relative distance (of max(1, |f|)) are a tie: a converged start, then the lower index wins
TIE = 1e-9
#: an elastic slack counts (the rule gives way) above this fraction of the rule's scale
SLACK_TOL = 1e-6


@dataclass
class StartReport:
    """A start's outcome with its independent re-check."""

    outcome: Any                     # core.outcome.StartOutcome
    satisfied: bool                  # every rule holds on the fine grid
    worst_violation: float           # largest normalised violation on the fine grid (0 when satisfied;
                                     # math.inf when the design cannot be evaluated: see :func:`measured`)
    records: list = field(default_factory=list)     # RuleRecord per rule
    context: Any = None              # whatever the kind's re-check keeps (scene, motion facts)
    why: str | None = None           # why the design could not be evaluated at all

    @property
    def smallest_normalised_margin(self) -> float:
        """The fine-grid smallest normalised margin of the design (-inf when it cannot be evaluated)."""
        margins = [r.normalised_margin for r in self.records]
        if not margins or any(m is None for m in margins):
            return -math.inf
        return min(margins)


@dataclass(frozen=True)
class Recheck:
    """What a kind's re-check returns: the rules on floats, what to keep, and optionally the objective
    measured on the fine grid (it then replaces the solver's, e.g. a max-min-margin objective)."""

    rules: list
    context: Any = None
    objective: Callable[["StartReport"], float] | None = None
    #: why the returned design is no design of the spec although its rules could be evaluated (e.g. a length the
    #: spec fixes moved, where the kind holds lengths as rows IPOPT did not meet): never satisfied, ranked last
    #: among the starts that ran, the reason kept (None: it is one)
    invalid: str | None = None


def report_of(outcome, recheck: Callable[[Any], Recheck]) -> StartReport:
    """Re-evaluate ``outcome``; a design the re-check cannot evaluate (AgrisynthError, ValueError)
    gets an infinite violation and the reason.  A non-finite objective is never feasible.  A start that
    could not be solved (it raised, its worker died: ``details["failure"]``) is not re-checked."""
    failure = failure_of(outcome)
    if failure is not None:
        return StartReport(outcome, False, math.inf, why=failure)
    try:
        rc = recheck(outcome)
    except (AgrisynthError, ValueError, ArithmeticError) as exc:
        return StartReport(outcome, False, math.inf, why=str(exc))
    records = [r.record() for r in rc.rules]
    # a margin that is not a finite number counts as an infinite violation, never as none (max() skips NaN)
    worst = max([0.0] + [-(r.normalised_margin if r.normalised_margin is not None
                           and math.isfinite(r.normalised_margin) else -math.inf)
                         for r in records if not r.satisfied])
    report = StartReport(outcome, all(r.satisfied for r in records), worst, records, rc.context)
    if rc.invalid is not None:
        report.satisfied, report.worst_violation, report.why = False, math.inf, rc.invalid
    if rc.objective is not None:
        outcome.objective = rc.objective(report)
    if not math.isfinite(outcome.objective):
        report.satisfied = False
        report.why = report.why or "the objective cannot be evaluated at this design"
    return report


def failure_of(outcome) -> str | None:
    """Why a start could not be solved at all (it raised, its worker process died), else None."""
    details = getattr(outcome, "details", None)
    return details.get("failure") if isinstance(details, dict) else None


def better(a: StartReport, b: StartReport, maximise: bool, by_index: bool = True) -> bool:
    """Feasible first; among feasible ones the objective (ties within TIE: a start IPOPT finished at its full
    tolerances before one it did not -- the same design, but only the first makes the run's "optimal" true --
    then the lower start index);
    among infeasible ones the smaller worst violation (ties within TIE -- starts held at the same bound miss
    it alike, to float noise -- the objective, then the lower start index), a start that could not be solved at
    all last.  ``by_index=False``: a tie down to the start index is not "better" (starts of two runs)."""
    if a.satisfied != b.satisfied:
        return a.satisfied
    if not a.satisfied:
        failed_a, failed_b = failure_of(a.outcome) is not None, failure_of(b.outcome) is not None
        if failed_a != failed_b:
            return failed_b
        va, vb = a.worst_violation, b.worst_violation
        if math.isfinite(va) != math.isfinite(vb):      # a design the model cannot evaluate (inf) comes after
            return math.isfinite(va)
        if math.isfinite(va) and abs(va - vb) > TIE * max(1.0, abs(va), abs(vb)):
            return va < vb
    fa, fb = a.outcome.objective, b.outcome.objective
    if maximise:
        fa, fb = -fa, -fb
    tie = TIE * max(1.0, abs(fb))
    return fa < fb - tie or (abs(fa - fb) <= tie and (not _converged(a), a.outcome.start if by_index else 0)
                             < (not _converged(b), b.outcome.start if by_index else 0))


def _converged(report: StartReport) -> bool:
    """IPOPT stopped at this start's design meeting its full tolerances (what status_of calls optimal)."""
    out = report.outcome
    return bool(getattr(out, "success", False)) and reached_optimum(getattr(out, "return_status", ""))


def best_in_start_order(reports: list[StartReport], maximise: bool) -> StartReport:
    """The best report, judged in start order, so the choice does not depend on the worker count."""
    chosen = reports[0]
    for rep in reports[1:]:
        if better(rep, chosen, maximise):
            chosen = rep
    return chosen


def measured(x: float | None) -> float | None:
    """A figure for result.json: JSON has no infinity or NaN, and a figure that could not be measured
    (the design cannot be evaluated) is written as null rather than as a number."""
    return x if x is not None and math.isfinite(x) else None


@dataclass
class ElasticDiagnosis:
    """What an elastic re-solve (one slack per rule, minimise their sum) says about a rule set."""

    return_status: str
    converged: bool
    slacks: dict[str, float]        # rule -> how far it must be relaxed, in the rule's unit
    units: dict[str, str]
    scales: dict[str, float]        # rule -> its typical margin (a slack counts above SLACK_TOL x scale)
    binding: list[str] = field(default_factory=list)   # rules with a non-zero multiplier there
    tol: float = SLACK_TOL
    #: the elastic re-solve's design (variable -> value), where the relaxation's misses are measured; None unknown
    design: dict | None = None
    #: relaxed rule -> the slack it still needs re-solved alone from the elastic design, every other rule relaxed away
    #: (core.solve.alone_slacks; None: nothing is known)
    alone: dict[str, float | None] = field(default_factory=dict)
    #: the rules the elastic form keeps hard (no slack: without them the model is undefined), held in every re-solve
    hard: list[str] = field(default_factory=list)
    #: the free design variables at a bound of the elastic design (core.solve.at_bounds): where wider bounds may help
    at_bounds: list[dict] = field(default_factory=list)
    #: rule -> the spec field that fixes its value, no design variable moving it (core.pinned; result.json
    #: ``elastic.fixed_by``): what to change for such a rule, rather than the bounds
    fixed: dict[str, str] = field(default_factory=dict)
    #: rule -> {"miss", "unit"} (the check's) at the elastic design on the check's finer grid, for a rule the
    #: relaxation does not give up on: held at the NLP's samples, it misses between them (result.json
    #: ``elastic.missed_between_samples``)
    between_samples: dict[str, dict] = field(default_factory=dict)

    @property
    def relaxed(self) -> list[str]:
        """The rules the relaxation gives up on, largest normalised slack first (none unless it converged)."""
        if not self.converged:
            return []
        return [n for n, s in sorted(self.slacks.items(), key=lambda kv: -kv[1] / self.scales[kv[0]])
                if s > self.tol * self.scales[n]]

    @property
    def out_of_reach(self) -> list[str]:
        """The rules given up on that miss their limit even re-solved alone from the elastic design, every other
        rule relaxed away: near that design the variable bounds or the mechanism (and the rules kept hard) hold them
        back, not the other rules (in the order of ``relaxed``).  Local, like the diagnosis: another region of the
        bounds may meet them."""
        return [n for n in self.relaxed
                if (alone := self.alone.get(n)) is not None and alone > self.tol * self.scales[n]]

    @property
    def held_back(self) -> list[str]:
        """The rules given up on that the other rules hold back: re-solved alone they need less slack (or that
        re-solve did not converge, and nothing says otherwise)."""
        return [n for n in self.relaxed
                if (alone := self.alone.get(n)) is None or self.slacks[n] - alone > self.tol * self.scales[n]]

    @property
    def conflicting(self) -> list[str]:
        """The rules in conflict: those given up on, then those holding against them (binding there).  The binding
        rules are named only when they hold back a rule given up on: when every such rule needs as much slack
        re-solved alone, they are bystanders (relaxing them would not bring it nearer its limit)."""
        relaxed = self.relaxed
        if not relaxed:
            return []
        return relaxed + ([n for n in self.binding if n not in relaxed] if self.held_back else [])

    def to_json(self) -> dict:
        return {"return_status": self.return_status, "converged": self.converged,
                "slacks": {n: measured(s) for n, s in self.slacks.items()}, "units": self.units,
                "scales": self.scales, "binding": self.binding, "relaxed": self.relaxed,
                "conflicting": self.conflicting, "alone": {n: measured(s) for n, s in self.alone.items()},
                "out_of_reach": self.out_of_reach, "hard": self.hard, "at_bounds": self.at_bounds,
                **({"fixed_by": self.fixed} if self.fixed else {}),
                **({"missed_between_samples": {n: {"miss": measured(v.get("miss")), "unit": v.get("unit")}
                                               for n, v in self.between_samples.items()}}
                   if self.between_samples else {}),
                **({} if self.design is None else {"design": {k: measured(v) for k, v in self.design.items()}})}

    @classmethod
    def from_json(cls, data: dict) -> "ElasticDiagnosis":
        slacks = {n: math.inf if s is None else s for n, s in data["slacks"].items()}
        return cls(data["return_status"], data["converged"], slacks, data["units"], data["scales"],
                   data.get("binding", []), design=data.get("design"), alone=dict(data.get("alone", {})),
                   hard=list(data.get("hard", [])), at_bounds=list(data.get("at_bounds", [])),
                   fixed=dict(data.get("fixed_by") or {}),
                   between_samples={n: v for n, v in (data.get("missed_between_samples") or {}).items()
                                    if isinstance(v, dict) and isinstance(v.get("miss"), (int, float))})


def diagnosis_of(compiled, raw) -> ElasticDiagnosis:
    """The diagnosis of an elastic :class:`synthesis.core.ipopt.CompiledNLP` solved to ``raw``."""
    rules = [r for r, hard in zip(compiled.rules, compiled.t.hard) if not hard]
    return ElasticDiagnosis(raw.return_status, raw.success, compiled.slack_values(raw.x),
                            # a slack relaxes the rule's rows: in their unit where it is not the rule's (a pose's
                            # squared distance, mm^2: a 1,610 mm miss was said as 2.59e+06 mm)
                            {r.name: r.row_unit or r.unit for r in rules}, {r.name: r.scale for r in rules},
                            compiled.active_rules(raw),
                            hard=[r.name for r, hard in zip(compiled.rules, compiled.t.hard) if hard])


def status_of(best: StartReport, elastic: ElasticDiagnosis | None) -> str:
    """The status of a multistart run (the module docstring; docs/ARCHITECTURE.md, "Verdicts")."""
    if best.satisfied:
        # success: the stage whose design was kept converged (a multi-stage kind may keep an earlier stage's)
        return "optimal" if best.outcome.success and reached_optimum(best.outcome.return_status) else "feasible"
    if elastic is not None and elastic.relaxed:
        return "infeasible"
    return "failed"


def said(reports: list[StartReport]) -> str:
    """IPOPT's return statuses over the starts, most frequent first: "Maximum_Iterations_Exceeded x5, ..."."""
    counts: dict[str, int] = {}
    for r in reports:
        counts[r.outcome.return_status] = counts.get(r.outcome.return_status, 0) + 1
    return ", ".join(f"{s} x{n}" if n > 1 else s for s, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))


def status_note(best: StartReport) -> str | None:
    """What a user must know about a feasible (not optimal) status: how IPOPT stopped at the best start."""
    if best.satisfied and not reached_optimum(best.outcome.return_status):
        return (f"every rule holds on the fine grid, but IPOPT stopped at {best.outcome.return_status} at the "
                f"best start (start {best.outcome.start}): a feasible design, not a proven local optimum")
    return None


def _bounds_text(at: list[dict]) -> str:
    """" At the elastic design, l2 (31.5) and l3 (67.5) sit at their lower bounds and x (-140) at its upper bound."."""
    parts = []
    for side in ("lower", "upper"):
        named = [f"{b['name']} ({b['bound']:g})" for b in at if b["side"] == side]
        if named:
            listed = named[0] if len(named) == 1 else f"{', '.join(named[:-1])} and {named[-1]}"
            parts.append(f"{listed} {'sits at its' if len(named) == 1 else 'sit at their'} {side} "
                         f"bound{'' if len(named) == 1 else 's'}")
    return f" At the elastic design {' and '.join(parts)}." if parts else ""


#: a violation below this many of its rule's scales is the solver's tolerance (IPOPT meets rows to ~1e-8), not a
#: miss between samples
SOLVER_TOLERANCE = 1e-6


def _within_solver_tolerance(best: StartReport | None, violated: list[str]) -> str:
    """"timing_hold_far[0] by 3.3e-09 deg" when every violated rule of ``best`` misses by at most
    :data:`SOLVER_TOLERANCE` of its scale, else ""."""
    if best is None or not violated:
        return ""
    records = {r.name: r for r in best.records}
    misses = [records.get(name) for name in violated]
    if any(r is None or r.normalised_margin is None or r.margin is None or r.normalised_margin < -SOLVER_TOLERANCE
           for r in misses):
        return ""
    return ", ".join(f"{r.name} by {-r.margin:.2g} {r.unit}".rstrip() for r in misses if r is not None)


def unsatisfied_error(status: str, violated: list[str], reports: list[StartReport],
                      elastic: ElasticDiagnosis | None, *, samples_hint: str,
                      relax_hint: str = "Loosen those requirements or widen the bounds of the design variables.",
                      max_iter_hint: str = "[solver] max_iter", best: StartReport | None = None) -> SolverError:
    """The exit-3 message of a run where no start satisfies every rule (status infeasible or failed); ``best``: the
    run's best start, whose violated rules ``violated`` names."""
    n = len(reports)
    bad = ", ".join(violated) or (f"none, but {best.why.rstrip('.')}" if best is not None and best.why and best.records
                                  else "none evaluated")
    # the best start's own reason first (it is the one named above), else the first start that has one
    unevaluable = best if best is not None and best.why else next((r for r in reports if r.why), None)
    cannot = f" Start {unevaluable.outcome.start}: {(unevaluable.why or '').rstrip('.')}." if unevaluable else ""
    if status == "infeasible":
        assert elastic is not None, "an infeasible verdict is the elastic diagnosis's (status_of)"
        relaxed, out = elastic.relaxed, elastic.out_of_reach

        def unit(name: str) -> str:        # a rule the NLP holds as a ratio (unit "1") misses by a ratio
            return " (a ratio of its NLP row)" if elastic.units[name] == "1" else f" {elastic.units[name]}"

        def in_rule_unit(name: str) -> str:
            """A squared row's slack (value^2 <= limit^2 + s: a key pose's distance, a force's magnitude) as the
            rule's own miss: sqrt(limit^2 + s) - limit, in the unit of its rule table."""
            row_unit = elastic.units[name]
            record = next((r for r in (best.records if best is not None else []) if r.name == name), None)
            upper = record.limit[1] if record is not None and isinstance(record.limit, (list, tuple)) else None
            slack = elastic.slacks[name]
            if (not row_unit.endswith("^2") or record is None or record.unit != row_unit[:-2]
                    or not isinstance(upper, (int, float)) or upper < 0 or not slack > 0):
                return ""
            return f", {math.sqrt(upper * upper + slack) - upper:.3g} {record.unit} beyond its {upper:g} {record.unit}"

        def misses(name: str) -> str:
            text = f"{name} (misses its limit by {elastic.slacks[name]:.3g}{unit(name)}{in_rule_unit(name)}"
            if name in out:
                kept = f" but {', '.join(elastic.hard)}" if elastic.hard else ""
                # a rule the spec's inputs fix: the field to change, not the bounds (core.pinned)
                held = (f"{elastic.fixed[name]} fixes it (no design variable moves it)" if name in elastic.fixed
                        else "near that design the variable bounds or the mechanism hold it back")
                text += (f"; still by {elastic.alone[name]:.3g}{unit(name)} re-solved alone from there, every other "
                         f"rule{kept} relaxed: {held}, not the other rules")
            elif name in elastic.fixed:
                text += f"; {elastic.fixed[name]} fixes it (no design variable moves it)"
            return text + ")"

        holding = [name for name in elastic.conflicting if name not in relaxed]
        if len(out) == len(relaxed):
            which = "Rules out of reach"
            # only those held back, by how much of their miss: the rest is the bounds' or the mechanism's
            # every rule given up on is out of reach here, so each was re-solved alone (``alone`` holds a number)
            held = [f"{name} by {elastic.slacks[name] - cast(float, elastic.alone[name]):.3g}{unit(name)} of its "
                    f"{elastic.slacks[name]:.3g}" for name in elastic.held_back]
            against = (f"; {', '.join(holding)} {'holds' if len(holding) == 1 else 'hold'} back {', '.join(held)} "
                       f"(binding there)" if holding and held else "")
        else:
            which = "Rules that conflict"
            against = f"; they conflict with {', '.join(holding)} (binding there)" if holding else ""
        missed = ", ".join(f"{name} by {v['miss']:.2g}"
                           + (f" {v.get('unit')}" if v.get("unit") not in (None, "", "-", "1") else "")
                           for name, v in elastic.between_samples.items())
        between = (f" On the check's finer grid its design also misses {missed}, between the NLP's samples (more "
                   f"samples: {samples_hint})." if missed else "")
        return SolverError(
            f"no start satisfies every rule ({n} starts; IPOPT said: {said(reports)}). {which} "
            f"(the smallest relaxation an elastic re-solve found ({elastic.return_status}), a local one, gives up on "
            f"them, largest first): {', '.join(misses(name) for name in relaxed)}{against}.{between}"
            f"{_bounds_text(elastic.at_bounds)} {relax_hint}{cannot}")
    if elastic is None:
        why = "and no elastic re-solve could be run (no start gives a design the model can evaluate)"
    elif not elastic.converged:
        why = (f"and an elastic re-solve did not converge either ({elastic.return_status}), so nothing is known "
               f"about conflicts")
    else:
        why = "and an elastic re-solve needs no slack, so the rules do not conflict"
    converged = [r for r in reports if r.outcome.success]
    # "between samples" only when the start whose violations are named converged: the rules then hold at its
    # samples (a start that stopped infeasible misses them at the samples too)
    best_converged = best.outcome.success if best is not None else bool(converged)
    if best_converged and elastic is not None and elastic.converged:
        slight = _within_solver_tolerance(best, violated)
        if slight:
            return SolverError(
                f"no start satisfies every rule on the 10x finer check grid ({n} starts; IPOPT said: {said(reports)}), "
                f"{why}, yet the best start misses only by the solver's tolerance ({slight}): not between samples. "
                f"Rules that hold a design variable at a single value from both sides (a hold window as long as its "
                f"dwell, a range the other rules leave one point of) leave no room inside them: fix that variable "
                f"at its value, or widen one of those rules.{cannot}")
        return SolverError(
            f"no start satisfies every rule on the 10x finer check grid ({n} starts; IPOPT said: {said(reports)}), "
            f"{why}: the rules hold at the solver's samples. Violated between samples: {bad}. Raise "
            f"{samples_hint}, or try more --starts.{cannot}")
    search = (f"more --starts, a higher {max_iter_hint}, or a given design (start 0) nearer one that meets the "
              f"rules")
    if elastic is not None and elastic.converged:       # no slack needed: the rules can be met together
        verdict = f"This is a solver failure, not an infeasible rule set: try {search}."
    else:       # nothing shows whether the rules can be met together: say so, and both ways out
        verdict = (f"Whether the rules can be met together is not known: if they can, {search} may find a design; "
                   f"if they cannot, loosen {'those rules' if violated else 'the rules'} or widen the bounds.")
    return SolverError(
        f"IPOPT found no design that satisfies every rule: {len(converged)} of the {n} starts converged "
        f"(IPOPT said: {said(reports)}), {why}. Violated at the best start: {bad}. {verdict}{cannot}")
