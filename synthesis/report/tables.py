"""The data a report page shows, computed from Results alone: design, rule and run-fact tables.

Kept apart from the HTML so that what the page says (which cells are red, which values differ from
the baseline) is tested as data.  The first candidate is the baseline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from synthesis import kinds
from synthesis.core.kind import ResultTable
from synthesis.errors import AgrisynthError
from synthesis.result import Result

#: a design value differs from the baseline's when it moves by more than this (relative, or absolute near 0)
DIFFERENCE_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Candidate:
    label: str          # unique column heading
    result: Result
    source: Path | None = None
    #: a solve's report: the rule table of the spec's given design (start 0), shown beside the solution's
    given_rules: list | None = None


def candidates(results: list[Result], sources: list[Path | None] | None = None) -> list[Candidate]:
    """Label each result by its name; repeated names get the source folder (or a number) added."""
    sources = sources or [None] * len(results)
    names = [r.name for r in results]
    labels = []
    for i, (r, src) in enumerate(zip(results, sources)):
        label = r.name
        if names.count(r.name) > 1:
            label = f"{r.name} ({src.parent.name if src is not None and src.name == 'result.json' else src or i + 1})"
        while label in labels:
            label = f"{label} #{i + 1}"
        labels.append(label)
    return [Candidate(lbl, r, s) for lbl, r, s in zip(labels, results, sources)]


@dataclass(frozen=True)
class DesignRow:
    name: str
    values: list            # one per candidate; None where a candidate has no such variable
    differs: list[bool]     # per candidate: differs from the baseline (always False for the baseline)
    unit: str = ""          # from the spec's field description ("" when the result does not say)
    bounds: list | None = None      # [lo, hi] of a free variable (every candidate that says agrees)
    free: bool | None = None        # None: the result does not say (check-only kinds, older results)
    at_bound: list[str] = field(default_factory=list)   # per candidate: "lower", "upper" or ""
    given: object = None    # the spec's given design (start 0), for a single solve's report
    #: per candidate (free, bounds) when the candidates' specs disagree (a published design's fixed value beside
    #: a redesign's free one): then ``bounds`` and ``free`` are None and each candidate's is shown; None: they agree
    per_candidate: list | None = None


def _as_list(bounds):
    return list(bounds) if isinstance(bounds, (list, tuple)) else bounds


def _differs(a, b) -> bool:
    if a is None or b is None:
        return a is not b
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) != len(b) or any(_differs(x, y) for x, y in zip(a, b))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return abs(a - b) > DIFFERENCE_TOLERANCE * max(1.0, abs(a), abs(b))
    return a != b


def design_rows(cands: list[Candidate]) -> list[DesignRow]:
    """Every design variable (baseline's order, then any others), one value per candidate, with what the
    spec says of it (unit, bounds, free or fixed) and whether each candidate's value sits on a bound."""
    from synthesis.spec.design_info import at_bound

    names: list[str] = []
    for c in cands:
        names += [n for n in c.result.design if n not in names]
    rows = []
    for n in names:
        values = [c.result.design.get(n) for c in cands]
        infos = [(c.result.design_variables or {}).get(n) for c in cands]
        info = next((i for i in infos if i), None) or {}
        given = (cands[0].result.baseline_design or {}).get(n) if len(cands) == 1 else None
        said = [(i.get("free"), _as_list(i.get("bounds"))) for i in infos if i]
        agree = all(x == said[0] for x in said)
        per = None if agree else [(i.get("free"), _as_list(i.get("bounds"))) if i else (None, None) for i in infos]
        rows.append(DesignRow(n, values, [i > 0 and _differs(values[0], v) for i, v in enumerate(values)],
                              info.get("unit") or "", info.get("bounds") if agree else None,
                              info.get("free") if agree else None,
                              [at_bound(v, i) for v, i in zip(values, infos)], given, per))
    # the assembly a linkage is solved on is a setting of its spec, not a design value (result.json holds it in
    # facts.branch: a name, "open" / "crossed", or a sign, +1 / -1), yet two designs of the same
    # dimensions on the two assemblies are different mechanisms: the table names it
    assemblies = [c.result.extra.get("branch") for c in cands]
    if "branch" not in names and any(isinstance(a, (str, int)) and not isinstance(a, bool) for a in assemblies):
        rows.append(DesignRow("branch (assembly)", assemblies,
                              [i > 0 and _differs(assemblies[0], a) for i, a in enumerate(assemblies)],
                              free=False, at_bound=[""] * len(cands),
                              given=assemblies[0] if len(cands) == 1 and cands[0].result.baseline_design else None))
    return rows


#: the column headings of a solve's question and answer, on the page and in the terminal alike
GIVEN_HEADING = "given (start 0)"


def solved_heading(result: Result) -> str:
    """The heading of a solve's answer column: "solved", or what the answer is when no start met every rule: an
    interrupted run's best so far, an infeasible or failed run's least violated start (IPOPT's last iterate there,
    not a best compromise between the rules it misses)."""
    if result.status == "interrupted":
        return "best so far (interrupted)"
    if result.status in ("infeasible", "failed"):
        return f"least violated ({result.status})"
    return "solved"


def is_single_solve(cands: list[Candidate]) -> bool:
    """One candidate, and a solve's result: its page heads the answer "solved", not the design's name."""
    return len(cands) == 1 and cands[0].result.solver is not None


def shows_given(cands: list[Candidate]) -> bool:
    """A single solve's report shows the given design (start 0) beside the solution."""
    return len(cands) == 1 and cands[0].result.solver is not None and bool(cands[0].result.baseline_design)


@dataclass(frozen=True)
class RuleCell:
    value: float | None
    limit: list
    margin: float | None
    normalised_margin: float | None
    satisfied: bool
    note: str               # where it was evaluated, or why it could not be


@dataclass(frozen=True)
class RuleRow:
    name: str
    unit: str
    limit: list                        # the baseline's limit (cells carry their own when they differ)
    cells: list[RuleCell | None]       # None: the candidate has no such rule
    given: RuleCell | None = None      # a single solve: the rule at the spec's given design (start 0)

    @property
    def violated(self) -> list[bool]:
        return [c is not None and not c.satisfied for c in self.cells]


def _cell(r: dict) -> RuleCell:
    note = r.get("note") or r.get("where") or ""
    return RuleCell(r.get("value"), r.get("limit", [None, None]), r.get("margin"), r.get("normalised_margin"),
                    bool(r.get("satisfied")), note)


def rule_rows(cands: list[Candidate]) -> list[RuleRow]:
    """One row per rule (the baseline's order, then any others), one cell per candidate."""
    by_candidate = [{r["name"]: r for r in c.result.rules} for c in cands]
    names: list[str] = []
    for c in cands:
        names += [r["name"] for r in c.result.rules if r["name"] not in names]
    given = {r["name"]: r for r in (cands[0].given_rules or [])} if shows_given_rules(cands) else {}
    rows = []
    for n in names:
        first = next(b[n] for b in by_candidate if n in b)
        rows.append(RuleRow(n, first.get("unit") or "", first.get("limit", [None, None]),
                            [_cell(b[n]) if n in b else None for b in by_candidate],
                            _cell(given[n]) if n in given else None))
    return rows


def shows_given_rules(cands: list[Candidate]) -> bool:
    """A single solve's report shows the rules of the given design (start 0) beside the solution's."""
    return len(cands) == 1 and cands[0].result.solver is not None and bool(cands[0].given_rules)


#: result key suffix -> unit, for the operating-conditions table
_SUFFIX_UNITS = (("_m_s2", "m/s^2"), ("_m_s", "m/s"), ("_r_min", "r/min"), ("_rpm", "r/min"), ("_mm", "mm"),
                 ("_deg", "deg"), ("_s", "s"))


def _condition(key: str) -> tuple[str, str]:
    for suffix, unit in _SUFFIX_UNITS:
        if key.endswith(suffix):
            return key[: -len(suffix)].replace("_", " "), unit
    return key.replace("_", " "), ""


#: conditions a kind's facts hold at their top level (a comb's operation; the lock range a steering linkage is
#: evaluated over): candidates solved for different ones are not comparable without seeing them
TOP_LEVEL_CONDITIONS = {"machine_speed_m_s": ("machine speed", "m/s"), "row_spacing_mm": ("row spacing", "mm"),
                        "max_inside_lock_deg": ("inside locks evaluated, 0 to", "deg")}


def operating_conditions(cands: list[Candidate]) -> list[tuple[str, str, list]]:
    """(condition, unit, one value per candidate): the speeds and sizes a design was evaluated at (crank and
    forward speed, plant spacing, the vehicle ...), from the result's facts: its ``operation`` and ``vehicle``
    tables, a cam's speed, a path's crank speed."""
    rows: dict[tuple[str, str], list] = {}

    def put(label: str, unit: str, i: int, value) -> None:
        if isinstance(value, (int, float, str)) and not isinstance(value, bool):
            rows.setdefault((label, unit), [None] * len(cands))[i] = value

    for i, c in enumerate(cands):
        facts = _table(c.result.extra)
        # a design solved over an operating range (facts.envelope) holds over the range, not at its nominal value
        ranges = {(cond.get("section"), name): cond.get("range")
                  for name, cond in _table(_table(facts.get("envelope")).get("conditions")).items()
                  if isinstance(cond, dict)}
        for section in ("operation", "vehicle"):
            for key, value in _table(facts.get(section)).items():
                span = next((r for (sec, name), r in ranges.items()
                             if sec == section and (key == name or key.startswith(name + "_"))), None)
                if (isinstance(span, list) and len(span) == 2 and isinstance(value, (int, float))
                        and not isinstance(value, bool)):
                    value = f"{value:g} (nominal; over {span[0]:g}-{span[1]:g})"
                put(*_condition(key), i, value)
        for key, (label, unit) in TOP_LEVEL_CONDITIONS.items():
            if key in facts:
                put(label, unit, i, facts[key])
        cam = _table(facts.get("cam"))
        if "crank_speed_rpm" in cam:
            put("crank speed", "r/min", i, cam["crank_speed_rpm"])
        tr = _table(c.result.trajectory)
        if "crank_speed_rpm" in tr:
            put("crank speed", "r/min", i, tr["crank_speed_rpm"])
    return [(label, unit, values) for (label, unit), values in rows.items()]


def _table(value) -> dict:
    """A result's table as read, or {} where the file holds something else there (a hand-edited or damaged
    result.json is compared without its conditions, never a traceback)."""
    return value if isinstance(value, dict) else {}


@dataclass(frozen=True)
class WorstMargin:
    rule: str | None                 # None when the candidate has no evaluated rule
    normalised_margin: float | None
    violated: int                    # how many rules it violates
    #: the rule's margin in its own unit where it has no normalised one (a tolerance analysis' verdict rows)
    margin: float | None = None
    unit: str | None = None
    evaluated: bool = True           # false: the rule could not be evaluated at the design


def worst_margins(cands: list[Candidate]) -> list[WorstMargin]:
    """Per candidate, its tightest (smallest normalised margin) rule: the first line of the rule table."""
    return [worst_margin(c.result.rules) for c in cands]


def worst_margin(rules: list[dict]) -> WorstMargin:
    """The tightest rule of a rule table (result.json ``rules`` records): a rule not evaluated first, else the one
    of smallest normalised margin -- unless that one holds while a rule without a normalised margin is violated (a
    tolerance analysis' ``@monte_carlo`` and ``@linear_worst_corner`` rows), which is then named with its own margin;
    and how many are violated."""
    bad = sum(1 for r in rules if not r.get("satisfied"))
    scored = [(r["normalised_margin"], r["name"]) for r in rules
              if isinstance(r.get("normalised_margin"), (int, float)) and math.isfinite(r["normalised_margin"])]
    unevaluated = [r["name"] for r in rules if r.get("value") is None]
    if unevaluated:
        return WorstMargin(unevaluated[0], None, bad, evaluated=False)
    if scored:
        m, name = min(scored)
        if m < 0 or not bad:
            return WorstMargin(name, m, bad)
    unscored = [r for r in rules if not r.get("satisfied") and not (
        isinstance(r.get("normalised_margin"), (int, float)) and math.isfinite(r["normalised_margin"]))]
    if unscored:
        r = unscored[0]
        margin = r.get("margin") if isinstance(r.get("margin"), (int, float)) else None
        return WorstMargin(r["name"], None, bad, margin, r.get("unit") if isinstance(r.get("unit"), str) else None)
    if scored:
        m, name = min(scored)
        return WorstMargin(name, m, bad)
    return WorstMargin(None, None, bad)


def objective_text(objective: dict | None) -> str | None:
    """"name = value unit"; a value that could not be measured (null in result.json) reads "not measured"."""
    if not objective:
        return None
    value = objective.get("value")
    shown = "not measured" if value is None else f"{value:.6g}"
    unit = objective.get("unit")
    shows_unit = unit and unit not in ("-", "1") and value is not None       # a pure number reads without "-"
    return f"{objective.get('name') or 'objective'} = {shown}{f' {unit}' if shows_unit else ''}"


def _starts_text(solver: dict | None):
    """The starts asked for, or "37 of 40" when fewer ran (interrupted, or stopped early by the kind's rule)."""
    if not solver or solver.get("starts") is None:
        return None
    ran, asked = solver.get("starts_run"), solver["starts"]
    if ran is None or ran == asked:
        return asked
    return f"{asked} + 1 from the elastic re-solve" if ran > asked else f"{ran} of {asked} run"


def said(stated: dict, reaching: int | None = None) -> str:
    """result.json ``solver.confidence`` (:func:`synthesis.core.confidence.statement`) in one line: "3 distinct optima
    in 28 converged starts, best reached by 19; P(best is global) ~ 0.89 (Boender & Rinnooy Kan; assumes uniform
    starts)".  Here, not beside the statement, so a report or the command line reads one without importing the
    posterior's mathematics (scipy.special)."""
    n, w = stated.get("starts_counted", 0), stated.get("distinct_optima", 0)
    if not n:
        return "no start converged with every rule held: no statement on the global optimum"
    p = stated.get("probability_best_is_global")
    # two decimals, but never rounded up to a certainty the estimate does not give (0.997 is not "1.00")
    shown = (f"{p:.2f}" if p < 0.995 else f"{math.floor(p * 1000) / 1000:.3f}") if p is not None else None
    chance = (f"P(best is global) ~ {shown}" if p is not None
              else "P(best is global) not defined (too few starts for the optima seen)")
    caveat = "; ".join(["assumes uniform starts", *(stated.get("assumptions_not_met") or [])])
    # an answer outside the counted starts: "best" is the best counted optimum, not the design returned
    best = "best" if stated.get("answer_counted", True) else "best counted"
    chance = chance.replace("P(best is", f"P({best} is")
    # ``reaching`` (solver.starts_reaching_best): starts that met every rule at the best objective, counted or not --
    # more than the statement's when some stopped short of IPOPT's full tolerance (or one is the start from the
    # elastic re-solve), which the statement leaves out
    at_best = stated.get("starts_at_best")
    more = (f" ({reaching} starts met every rule at the answer's objective; the statement counts only drawn starts "
            f"IPOPT finished at its full tolerance)" if isinstance(reaching, int) and isinstance(at_best, int)
            and reaching > at_best else "")
    return (f"{w} distinct optim{'um' if w == 1 else 'a'} in {n} converged start{'' if n == 1 else 's'}, {best} "
            f"reached by {at_best}{more}; {chance} (Boender & Rinnooy Kan; {caveat})")


def _confidence_text(solver: dict | None) -> str | None:
    """The confidence statement's line (result.json ``solver.confidence``, a solve of schema version 5 on), and for
    ``--starts auto`` why it stopped."""
    stated = (solver or {}).get("confidence")
    if not isinstance(stated, dict):
        return None
    return said(stated, (solver or {}).get("starts_reaching_best")) + auto_said(solver or {})


def auto_said(solver: dict) -> str:
    """"; --starts auto: 32 starts, stopped by rule" (empty for fixed starts); where an earlier batch's design is the
    answer, the batches run and whose answer it is."""
    auto = solver.get("auto")
    if not isinstance(auto, dict):
        return ""
    batches = auto.get("batches")
    if auto.get("answer_batch") is not None and isinstance(batches, list) and batches:
        return (f"; --starts auto: batches of {', '.join(str(b) for b in batches)} starts, stopped by "
                f"{auto.get('stopped_by')}; the answer and this statement are the {auto['answer_batch']}-start "
                f"batch's (no later batch found as good a design)")
    asked, ran = solver.get("starts"), solver.get("starts_run")
    # the kind's early stop ends a batch at the start that reached its target: fewer ran than the batch had
    count = f"{ran} of {asked}" if isinstance(ran, int) and isinstance(asked, int) and ran < asked else f"{asked}"
    return f"; --starts auto: {count} starts, stopped by {auto.get('stopped_by')}"


def _objectives(cands: list[Candidate]) -> list:
    """Each candidate's objective; beside a solve's, a check's says it has none (a check evaluates the
    rules only) rather than a bare dash a reader takes for a missing number."""
    texts = [objective_text(c.result.objective) for c in cands]
    if not any(texts):
        return texts
    return [t if t is not None or c.result.status != "evaluated"
            else "none: a tolerance analysis evaluates the rules only" if is_tolerance_analysis(c.result)
            else "none: a check evaluates the rules only"
            for t, c in zip(texts, cands)]


def is_tolerance_analysis(result: Result) -> bool:
    """An ``agrisynth tolerance`` result (its facts hold the stack-up), not a check's."""
    facts = result.extra.get("tolerance") if isinstance(result.extra, dict) else None
    return isinstance(facts, dict) and "stack_up" in facts


def run_facts(cands: list[Candidate]) -> list[tuple[str, list]]:
    """What a reader needs to reproduce each candidate: status, solver, starts, seed, versions, spec hash."""
    def solver(c: Candidate, key: str):
        return (c.result.solver or {}).get(key)

    facts = [
        ("status", [c.result.status for c in cands]),
        ("objective", _objectives(cands)),
        ("solver status", [solver(c, "return_status") for c in cands]),
        ("iterations", [solver(c, "iterations") for c in cands]),
        ("wall time (build and starts), s", [solver(c, "wall_s") for c in cands]),
        ("workers", [solver(c, "workers") for c in cands]),
        ("starts", [_starts_text(c.result.solver) for c in cands]),
        ("seed", [solver(c, "seed") for c in cands]),
        ("best start", [solver(c, "best_start") for c in cands]),
        ("global optimum (how sure)", [_confidence_text(c.result.solver) for c in cands]),
        ("fine-grid worst violation (violation / rule scale)", [c.result.fine_grid_worst_violation for c in cands]),
        ("spec sha256", [c.result.spec_sha256 for c in cands]),
        ("source", [c.result.extra.get("source") for c in cands]),
        ("result file", [None if c.source is None else str(c.source) for c in cands]),
    ]
    versions = sorted({k for c in cands for k in c.result.versions})
    facts += [(f"{k} version", [c.result.versions.get(k) for c in cands]) for k in versions]
    return [(name, values) for name, values in facts if any(v is not None for v in values)]


@dataclass(frozen=True)
class Headline:
    """A candidate's first screen: the figures its kind says an engineer looks at first (:meth:`Kind.headline`), and
    the kind's tables of its own figures (:meth:`Kind.result_tables`: a path's error per target)."""

    label: str
    lines: list[str]
    tables: list[ResultTable]


def headlines(cands: list[Candidate]) -> list[Headline]:
    """Each candidate's headline, from its result alone.  A result its kind cannot read (an unknown kind, facts of
    an older or hand-edited file) has none: the page is never lost for it."""
    out = []
    for c in cands:
        try:
            kind = kinds.get(c.result.kind)
            lines, tables = list(kind.headline(c.result)), list(kind.result_tables(c.result))
        except (AgrisynthError, KeyError, TypeError, ValueError, AttributeError, IndexError):
            lines, tables = [], []
        out.append(Headline(c.label, [str(line) for line in lines], tables))
    return out

