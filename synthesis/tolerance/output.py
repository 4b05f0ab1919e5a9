"""The folder of ``agrisynth tolerance``: result.json (result-like, result.json's schema version, the analysis under
``facts``), report.md (the stack-up table, with tornado.png embedded) and tornado.png (a tornado of the linear
stack-up of each of the worst rules)."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from synthesis.result import SCHEMA_VERSION, atomic_write_text, finite_json_text, versions


def verdict_rows(facts: dict) -> list[dict]:
    """The rows the analysis's exit code reads, in result.json's rule form, after the design's own rules: with a
    Monte-Carlo, ``<rule>@monte_carlo`` per sampled rule (value its pass rate, satisfied when every sample holds it)
    and ``<rule>@linear_worst_corner`` per rule missed at that corner; with none (--samples 0), ``<rule>@tolerance``
    per rule (value its linearised worst-case margin, satisfied when >= 0 and the rule holds at that corner).  So a
    reader of result.json (``agrisynth compare``) sees what made the command exit 1."""
    mc = facts["monte_carlo"]
    rows: list[dict] = []
    if no_box(facts):               # --samples 0 with every half-width 0: the design's own rows decide, nothing more
        return rows
    if mc["samples"]:
        for name, r in mc["rules"].items():
            rate = r.get("pass_rate")
            rows.append({"name": f"{name}@monte_carlo", "value": rate, "limit": [1.0, None], "unit": "",
                         "satisfied": rate is not None and rate >= 1.0, "margin": None if rate is None else rate - 1.0,
                         "where": f"share of the {mc['samples']} Monte-Carlo samples (seed {mc['seed']}) in the "
                                  f"tolerance box that hold the rule", "note": None})
        if mc.get("unevaluable"):
            rows.append({"name": "monte_carlo_evaluable", "value": 1.0 - mc["unevaluable"] / mc["samples"],
                         "limit": [1.0, None], "unit": "", "satisfied": False,
                         "margin": -mc["unevaluable"] / mc["samples"],
                         "where": "share of the Monte-Carlo samples the kind's check could evaluate", "note": None})
        # a rule's linear worst corner is a design in the box too, one the samples rarely come near: re-checked there
        # and missed, the box breaks the rule however many samples pass (asking for more checking must not pass it)
        for r in facts["stack_up"]:
            why = _corner_breaks(r)
            if why is not None:
                corner = r.get("corner_margin")
                rows.append({"name": f"{r['name']}@linear_worst_corner", "value": corner, "limit": [0.0, None],
                             "unit": r.get("recheck_unit") or r["unit"], "satisfied": False, "margin": corner,
                             "where": "the rule re-checked at the box's corner where its linear stack-up puts its "
                                      "worst case", "note": why})
        return rows
    for r in facts["stack_up"]:
        m = r.get("linear_worst_margin")
        # the rule re-checked at its linear worst corner is a design inside the box: missing there, the box breaks
        # the rule whatever the linearisation says (a curved rule; a trial: +0.018 linear, -0.0058 deg there)
        why = _corner_breaks(r)
        rows.append({"name": f"{r['name']}@tolerance", "value": m, "limit": [0.0, None], "unit": r["unit"],
                     "satisfied": m is not None and m >= 0 and why is None, "margin": m,
                     "where": "margin at the linearised worst case in the tolerance box",
                     "note": None if why is None else f"re-checked at that corner of the box the rule {why}: a "
                                                      f"design in the box breaks it"})
    return rows


def no_box(facts: dict) -> bool:
    """Whether the analysis had no tolerance box (every half-width 0: ``--samples 0`` for the sensitivities alone)."""
    return not any(t.get("half_width") for t in facts["tolerance"].values())


#: what a run without a box is, said where a box's results would be
NO_BOX = "no tolerance box, every half-width 0: the design's sensitivities alone, nothing stacked up"


def _corner_breaks(row: dict) -> str | None:
    """Why the design at a rule's linear worst corner breaks it (missed there; or not evaluable there although the
    design itself is, as an unevaluable Monte-Carlo sample counts), else None."""
    corner = row.get("corner_margin")
    unit = row.get("recheck_unit") or row["unit"]
    if corner is not None:
        return f"misses by {-corner:.4g} {unit}" if corner < 0 else None
    if row.get("corner") is not None and row.get("recheck_margin") is not None and row.get("corner_note"):
        return f"is {row['corner_note'].removeprefix('at the linear worst corner: ')} there"
    return None


def result_json(kind: str, name: str, sha: str, facts: dict) -> dict:
    rules = facts["nominal_rules"] + verdict_rows(facts)
    return {"schema_version": SCHEMA_VERSION, "kind": kind, "name": f"{name}-tolerance", "spec_sha256": sha,
            "status": "evaluated", "design": facts["design"], "rules": rules, "versions": versions(),
            "facts": {"tolerance": facts}}


def full_table(facts: dict) -> str:
    """report.md's tables: every rule's stack-up, Monte-Carlo and corner columns, the derivatives w.r.t. the operating
    conditions, the explanation of every linear-vs-sampled gap and every reason a sample could not be evaluated."""
    mc = facts["monte_carlo"]

    if no_box(facts):
        return _sensitivity_report(facts)
    box = _box_line(facts["tolerance"])
    lines = [*([box, ""] if box else []), (f"Monte-Carlo: {mc['samples']} samples (seed {mc['seed']}, {mc['distribution']}): "
              f"{100 * (mc['pass_rate'] or 0):.2f} % pass every rule"
              + (f" at every operating point ({100 * (mc['envelope']['pass_rate_at_nominal'] or 0):.2f} % at the "
                 "nominal point alone)" if mc.get("envelope") else "")) if mc["samples"] else
             "Monte-Carlo: none (--samples 0): sensitivities and the linear stack-up only", *_envelope_lines(mc), "",
             "| rule | unit | margin | linear worst margin | drivers | MC pass | MC worst margin | linear / sampled loss "
             "| margin at the linear worst corner | linear vs sampled gap |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    notes = []
    for r in facts["stack_up"]:
        def f(v, fmt="{:.4g}"):
            return "-" if v is None else fmt.format(v)
        drivers = ", ".join(f"{d['variable']} {d['contribution']:.3g}" for d in r["drivers"])
        unit = r.get("recheck_unit") or r["unit"]
        # the stack-up is in the NLP's terms of the rule; where those are not the re-check's (a curvature for a
        # radius) its cell says so and the unit column is the re-check's (margin, MC and corner columns)
        linear = f(r['linear_worst_margin']) + ("" if r.get("same_terms", True) or r["unit"] == unit else
                                               f" (NLP's terms, {r['unit'] or '-'})")
        lines.append(f"| {r['name']} | {unit} | {f(r['recheck_margin'])} | {linear} | {drivers} "
                     f"| {f(r['mc_pass_rate'], '{:.1%}')} | {f(r['mc_worst_margin'])}"
                     f"{_not_evaluable(r.get('mc_unevaluable'), mc['samples'])} "
                     f"| {f(r['linear_over_sampled'], '{:.2f}')} "
                     f"| {f(r.get('corner_margin'))} | {f(r.get('linear_vs_sampled_gap'), '{:.1%}')} |")
        if r.get("gap_explanation"):
            notes.append(f"* {r['name']}: {r['gap_explanation']}")
    lines += _design_derivative_lines(facts)
    lines += _operating_lines(facts)
    if notes:
        lines += ["", "Linear vs sampled worst case (sampled: the Monte-Carlo and each rule's linear worst corner; "
                      "the gap is |linear loss - sampled loss| / sampled loss, 10 % expected) explained:"] + notes
    reasons = mc.get("unevaluable_reasons") or []
    if reasons:
        lines += ["", "Why samples could not be evaluated (each reason once per sample; a sample may have several):", "",
                  "| samples | reason | rules without a margin |", "|---|---|---|"]
        lines += [f"| {r['samples']} | {r['reason']} | {', '.join(r['rules'])} |" for r in reasons]
    return "\n".join(lines) + "\n"


def _sensitivity_report(facts: dict) -> str:
    """report.md of a run without a box: the design's rules (margin, pass or fail) and each rule's derivatives."""
    failing = [r["name"] for r in facts["nominal_rules"] if not r["satisfied"]]
    verdict = (f"FAILS at the design: {len(failing)} rule(s) break ({', '.join(failing)})" if failing else
               "holds at the design: it passes every rule")
    lines = [f"Verdict: {verdict}; {NO_BOX}", "", "| rule | unit | value | margin | at the design |",
             "|---|---|---|---|---|"]
    for r in facts["nominal_rules"]:
        def f(v):
            return "-" if v is None else f"{v:.6g}"
        lines.append(f"| {r['name']} | {r.get('unit') or ''} | {f(r.get('value'))} | {f(r.get('margin'))} "
                     f"| {'holds' if r['satisfied'] else 'FAILS'} |")
    return "\n".join(lines + _design_derivative_lines(facts) + _operating_lines(facts)) + "\n"


def _design_derivative_lines(facts: dict) -> list[str]:
    """The derivative of each rule's value (at its worst sample) w.r.t. each design variable, exact (CasADi AD)."""
    units = {k: t.get("unit") or "" for k, t in facts["tolerance"].items()}
    keys = list(units)
    if not keys or not facts["stack_up"]:
        return []
    lines = ["", "Derivatives w.r.t. the design variables (exact, each rule's value at its worst sample on the "
                 "analysis grid; per unit of the variable):", "",
             "| rule | unit | " + " | ".join(f"d/d {k} (per {units[k] or '1'})" for k in keys) + " |",
             "|---|---|" + "---|" * len(keys)]
    for r in facts["stack_up"]:
        sens = r.get("sensitivity") or {}
        cells = ("-" if (v := sens.get(k)) is None else f"{v:.4g}" for k in keys)
        lines.append(f"| {r['name']} | {r['unit']} | " + " | ".join(cells) + " |")
    return lines


def _operating_lines(facts: dict) -> list[str]:
    """The derivative of each rule w.r.t. each operating condition, and the conditions no rule reads."""
    if not facts.get("operating"):
        return []
    ops = facts["operating"]
    lines: list[str] = []
    lines += ["", "Derivatives w.r.t. the operating conditions (exact, each rule at its scenario's values; "
                  "nominal " + ", ".join(f"{n} = {o['nominal']:g} {o['unit']}" for n, o in ops.items()) + "):", "",
              "| rule | unit | " + " | ".join(f"d/d {n} (per {o['unit']})" for n, o in ops.items()) + " |",
              "|---|---|" + "---|" * len(ops)]
    for r in facts["stack_up"]:
        sens = r.get("operating_sensitivity") or {}
        cells = ("-" if (v := sens.get(n, 0.0)) is None else f"{v:.4g}" for n in ops)   # None: not evaluated
        lines.append(f"| {r['name']} | {r['unit']} | " + " | ".join(cells) + " |")
    unused = [n for n, rules in (facts.get("operating_dependence") or {}).items() if not rules]
    if unused:
        lines += ["", f"No rule's value depends on {', '.join(unused)}: the derivative is exactly 0 for every rule "
                      "(the condition may still move a rule's limit or the objective)."]
    return lines


#: the terminal summary: its width (columns), the failing rules it says how they fail, the rules its table shows and
#: the reasons for unevaluable samples it names, at most
WIDTH, SHOWN_FAILURES, SHOWN_RULES, SHOWN_REASONS = 100, 3, 6, 3
#: the suffixes of the verdict rows (:func:`verdict_rows`) after the rule's own name
_VERDICT_SUFFIXES = ("@monte_carlo", "@linear_worst_corner", "@tolerance")


def table(facts: dict) -> str:
    """What `agrisynth tolerance` prints: one screen of at most :data:`WIDTH` columns -- the verdict, the box, the
    Monte-Carlo's pass rate, the rules that decide the verdict (else the tightest ones) with their drivers, what to
    tighten first, the top reasons samples could not be evaluated, and where the full tables are (report.md)."""
    mc, rows = facts["monte_carlo"], facts["stack_up"]
    failing = failing_rules(facts)
    if no_box(facts):
        return _sensitivity_table(facts, failing)
    shown = _shown_rules(rows, failing)
    box = _box_line(facts["tolerance"])
    lines = [_verdict_line(facts, failing, [r["name"] for r in shown]), *([box] if box else []), _monte_carlo_line(mc), ""]
    lines += _rule_lines(shown, failing, mc["samples"])
    if len(rows) > len(shown):
        lines.append(f"({len(rows) - len(shown)} more rule(s) in report.md)")
    lines += _tighten_line(shown, failing) + _reason_lines(mc)
    lines += ["Full tables (every rule, operating derivatives, gap notes, every reason): report.md"]
    return "\n".join(line for text in lines for part in text.split("\n") for line in _fit(part)) + "\n"


def _sensitivity_table(facts: dict, failing: dict) -> str:
    """The terminal summary of a run without a box: the verdict at the design and its rules, tightest first."""
    rules = sorted(facts["nominal_rules"], key=lambda r: (r["satisfied"], math.inf if r.get("margin") is None
                                                         else r["margin"] / (r.get("scale") or 1.0)))
    head = (f"Verdict: FAILS at the design: {len(failing)} rule(s) break ({NO_BOX})" if failing else
            f"Verdict: holds at the design: it passes every rule ({NO_BOX})")
    width = max([len("rule")] + [len(r["name"]) for r in rules])
    lines = [head, "", f"{'rule':<{width}}  {'':4} {'unit':<7}{'margin':>10}"]
    lines += [f"{r['name']:<{width}}  {'ok' if r['satisfied'] else 'FAIL':4} {r.get('unit') or '-':<7}"
              f"{_num(r.get('margin')):>10}" for r in rules[:SHOWN_RULES]]
    if len(rules) > SHOWN_RULES:
        lines.append(f"({len(rules) - SHOWN_RULES} more rule(s) in report.md)")
    lines.append("Each rule's derivatives w.r.t. every design variable and operating condition: report.md")
    return "\n".join(line for text in lines for line in _fit(text)) + "\n"


def failing_rules(facts: dict) -> dict[str, list[str]]:
    """Rule name -> how it fails (at the design, in samples, at its linear worst corner), from the rows the exit code
    reads; a sample the re-check could not evaluate at all is under "(samples)"."""
    failing: dict[str, list[str]] = {}
    for r in facts["nominal_rules"]:
        if not r["satisfied"]:
            failing.setdefault(r["name"], []).append("at the design")
    for r in verdict_rows(facts):
        if r["satisfied"]:
            continue
        name = r["name"]
        base = next((name.removesuffix(s) for s in _VERDICT_SUFFIXES if name.endswith(s)), "(samples)")
        how = {"@monte_carlo": f"in {100 * (1 - (r['value'] or 0)):.1f} % of the samples",
               "@linear_worst_corner": f"at its linear worst corner ({r['note']})",
               "@tolerance": "at its linear worst case"}
        failing.setdefault(base, []).append(next((v for s, v in how.items() if name.endswith(s)),
                                                 "some samples not evaluable"))
    return failing


def _scaled_worst(row: dict) -> float:
    m = row.get("linear_worst_margin")
    return math.inf if m is None else m / (row.get("scale") or 1.0)


def _shown_rules(rows: list[dict], failing: dict) -> list[dict]:
    """The rules that fail (fewest samples passing first), then the tightest that hold (smallest linear worst margin
    relative to the rule's scale), at least three and at most :data:`SHOWN_RULES`."""
    def order(r):
        rate = r.get("mc_pass_rate")
        return (r["name"] not in failing, 1.0 if rate is None else rate, _scaled_worst(r))
    ranked = sorted(rows, key=order)
    return ranked[:min(SHOWN_RULES, max(3, sum(r["name"] in failing for r in rows)))]


def _verdict_line(facts: dict, failing: dict, ranked: list[str]) -> str:
    """The verdict, and how each of the first failing rules (in the table's order) fails."""
    mc = facts["monte_carlo"]
    if failing:
        names = sorted((n for n in failing if n != "(samples)"),
                       key=lambda n: ranked.index(n) if n in ranked else len(ranked))
        return "\n".join([f"Verdict: FAILS in the tolerance box: {len(names)} rule(s) break"
                          + ("; some samples cannot be evaluated" if "(samples)" in failing else "")]
                         + [f"  {n}: {', '.join(failing[n])}" for n in names[:SHOWN_FAILURES]]
                         + ([f"  ... and {len(names) - SHOWN_FAILURES} more (FAIL in the table, all in report.md)"]
                            if len(names) > SHOWN_FAILURES else []))
    if mc["samples"]:
        return f"Verdict: holds: the design and all {mc['samples']} samples pass every rule; no linear worst corner breaks one"
    return "Verdict: holds: the design passes every rule and every linear worst case in the box holds"


def _box_line(tolerance: dict) -> str:
    groups: dict[tuple, list[str]] = {}
    for key, t in tolerance.items():
        if t["half_width"] and "follows" not in t:
            groups.setdefault((t["half_width"], t["unit"]), []).append(key)
    followers = [f"{key} follows {', '.join(t['follows'])} (±{t['half_width']:g} {t['unit']}".rstrip() + ")"
                 for key, t in tolerance.items() if "follows" in t and t["half_width"]]
    parts = [f"±{w:g} {u}".rstrip() + f" on {', '.join(keys)}" for (w, u), keys in groups.items()] + followers
    return "Box: " + "; ".join(parts) if parts else ""


def _monte_carlo_line(mc: dict) -> str:
    if not mc["samples"]:
        return "Monte-Carlo: none (--samples 0): sensitivities and the linear stack-up only"
    text = f"Monte-Carlo: {mc['samples']} samples (seed {mc['seed']}): {_pct(mc['pass_rate'])} pass every rule"
    env = mc.get("envelope")
    if env:
        text += (f" at all {env['points']} operating points and the nominal one ({_pct(env['pass_rate_at_nominal'])} "
                 f"at the nominal point alone)")
    partly = mc.get("samples_not_fully_evaluable")
    if partly:
        text += f"; {partly} ({partly / mc['samples']:.1%}) not fully evaluable (failing)"
    return text


def _rule_lines(shown: list[dict], failing: dict, samples: int) -> list[str]:
    width = max([len("rule")] + [len(r["name"]) for r in shown])
    head = f"{'rule':<{width}}  {'':4} {'unit':<7}{'margin':>9} {'lin. worst':>10} {'MC pass':>8} {'MC worst':>9}  "
    lines = [head + ("drivers (loss share)" if len(head) + 20 <= WIDTH else "drivers")]
    other_terms = []        # rows whose linear worst margin is in the NLP's terms, not the unit shown (report.md's note)
    for r in shown:
        unit = r.get("recheck_unit") or r["unit"]
        linear = _num(r.get('linear_worst_margin'))
        if not (r.get("same_terms", True) or r["unit"] == unit):
            other_terms.append(f"{r['name']} ({r['unit'] or '-'})")
            linear += "*"
        cells = (f"{r['name']:<{width}}  {'FAIL' if r['name'] in failing else 'ok':4} {unit or '-':<7}"
                 f"{_num(r.get('recheck_margin')):>9} {linear:>10} "
                 f"{_num(r.get('mc_pass_rate'), '{:.1%}') if samples else '-':>8} {_num(r.get('mc_worst_margin')):>9}  ")
        drivers = [f"{v} {100 * s:.0f}%" for v, s in _shares(r)[:3]]
        while drivers and len(cells + ", ".join(drivers)) > WIDTH:
            drivers.pop()
        lines.append(cells + ", ".join(drivers))
    if other_terms:
        lines.append(f"* lin. worst in the NLP's terms of the rule, not the unit shown: {', '.join(other_terms)}")
    return lines


def _shares(row: dict) -> list[tuple[str, float]]:
    """The row's driving variables with their share of its linear loss, largest first."""
    total = sum(abs(c) for c in (row.get("contributions") or {}).values() if c)
    return [(d["variable"], d["contribution"] / total) for d in row.get("drivers") or []] if total else []


def _tighten_line(shown: list[dict], failing: dict) -> list[str]:
    """The variables with the largest summed share of the failing rules' linear losses: where a tighter tolerance
    helps most."""
    share: dict[str, float] = {}
    for r in shown:
        if r["name"] in failing:
            for v, s in _shares(r):
                share[v] = share.get(v, 0.0) + s
    if not share:
        return []
    top = sorted(share, key=lambda v: -share[v])[:3]
    return ["Tighten first (most of the failing rules' linear loss): " + ", ".join(top)]


def _reason_lines(mc: dict) -> list[str]:
    reasons = mc.get("unevaluable_reasons") or []
    if not reasons:
        return []
    lines = ["", "Not evaluable, by reason (samples):"]
    for r in reasons[:SHOWN_REASONS]:
        lines += textwrap.wrap(f"{r['samples']:>7}  {r['reason']}", WIDTH, subsequent_indent=" " * 9, max_lines=2,
                               placeholder=" ...")
    if len(reasons) > SHOWN_REASONS:
        lines.append(f"  ({len(reasons) - SHOWN_REASONS} more reason(s) in report.md)")
    return lines


def _fit(text: str) -> list[str]:
    """``text`` as lines of at most :data:`WIDTH` columns: wrapped (the continuation indented as the text is), at most
    two lines, the rest cut with "..."."""
    if len(text) <= WIDTH:
        return [text]
    indent = " " * (len(text) - len(text.lstrip()) + 2)
    return textwrap.wrap(text, WIDTH, subsequent_indent=indent, max_lines=2, placeholder=" ...")


def _num(value, fmt: str = "{:.4g}") -> str:
    return "-" if value is None else fmt.format(value)


def _envelope_lines(mc: dict) -> list[str]:
    """The Monte-Carlo's pass rate of each rule over the operating range (its worst grid point), for an envelope."""
    rows = {n: r for n, r in mc["rules"].items() if n.endswith("@envelope")}
    if not rows:
        return []
    return ["", "| rule over the operating range | MC pass (every point) | MC worst margin |", "|---|---|---|"] + [
        f"| {n} | {r['pass_rate']:.1%} | {'-' if r['worst_margin'] is None else format(r['worst_margin'], '.4g')} |"
        for n, r in rows.items()]


#: rules and variables a tornado shows: the rules with the smallest linear worst margin (relative to their
#: scale), each with its largest contributions
TORNADO_RULES, TORNADO_BARS = 6, 8


def tornado_rules(facts: dict) -> list[dict]:
    """The stack-up rows the tornado draws: those with a finite linear worst margin and a non-zero contribution,
    worst (smallest linear worst margin / rule scale) first."""
    rows = [r for r in facts["stack_up"]
            if r.get("linear_worst_margin") is not None and np.isfinite(r["linear_worst_margin"])
            and any(c for c in (r.get("contributions") or {}).values())]
    rows.sort(key=lambda r: r["linear_worst_margin"] / (r.get("scale") or 1.0))
    return rows[:TORNADO_RULES]


def tornado(facts: dict, path: Path) -> None:
    """tornado.png: for each of the worst rules (:func:`tornado_rules`) a tornado of its linear stack-up -- one
    horizontal pair of bars per driving variable, its margin's linear change when it alone moves by +tol_i (blue)
    and -tol_i (orange), to the nearer of the rule's limits (a two-sided rule's gain towards one limit capped by the
    other), centred on the rule's nominal margin at its worst sample, largest at the top; the red line is the limit
    (margin 0), the dashed one the linear worst case (every variable at its corner at once)."""
    # imported here: the terminal's Monte-Carlo lines (every solve's views) need this module, not matplotlib
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = tornado_rules(facts)
    tol = facts["tolerance"]
    if not rows:
        fig, ax = plt.subplots(figsize=(7, 1.6))
        ax.axis("off")
        ax.text(0.5, 0.5, "no tolerance box (every half-width 0): nothing to stack up;\nthe rules' derivatives are in "
                "report.md" if no_box(facts) else "no rule's margin moves with the design in the tolerance box",
                ha="center", va="center")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return
    heights = []
    for r in rows:
        n = sum(1 for c in r["contributions"].values() if c)
        heights.append(min(n, TORNADO_BARS) * 0.32 + 0.9)
    fig, axes = plt.subplots(len(rows), 1, figsize=(8, sum(heights) + 0.6), squeeze=False,
                             gridspec_kw={"height_ratios": heights})
    for ax, r in zip(axes[:, 0], rows):
        contrib = sorted(((k, c) for k, c in r["contributions"].items() if c), key=lambda kc: -abs(kc[1]))
        shown = contrib[:TORNADO_BARS]
        loss = sum(abs(c) for _, c in contrib)
        # the nominal margin at the worst sample, and each variable's margin change at +tol and -tol with both limits
        # (a result written before they were recorded: the one-sided linear change, mirrored)
        centre = r.get("worst_sample_margin")
        centre = r["linear_worst_margin"] + loss if centre is None else centre
        changes = r.get("margin_change") or {}
        y = np.arange(len(shown))[::-1]                  # the largest at the top
        plus = np.array([(changes.get(k) or [c, -c])[0] for k, c in shown])
        minus = np.array([(changes.get(k) or [c, -c])[1] for k, c in shown])
        # the two moves side by side (both may lower a two-sided rule's margin: one bar would hide the other)
        ax.barh(y + 0.2, plus, height=0.4, left=centre, color="tab:blue", label="+tol")
        ax.barh(y - 0.2, minus, height=0.4, left=centre, color="tab:orange", label="-tol")
        ax.set_yticks(y, [f"{k} ±{tol[k]['half_width']:g} {tol[k]['unit']}".rstrip() for k, _ in shown], fontsize=7)
        ax.axvline(centre, color="black", linewidth=0.8)
        ax.axvline(r["linear_worst_margin"], color="black", linestyle="--", linewidth=0.8)
        # the bars, the nominal and the linear worst margin in view (a bar's base is sticky: no autoscale margin there)
        lo = min(r["linear_worst_margin"], centre + min(plus.min(), minus.min(), 0.0))
        hi = centre + max(plus.max(), minus.max(), 0.0)
        width = max(hi - lo, 1e-12)
        if lo - 3 * width <= 0.0 <= hi + 3 * width:      # the limit near the bars: drawn, and in view
            ax.axvline(0.0, color="red", linewidth=1)
            lo, hi = min(lo, 0.0), max(hi, 0.0)
            width = max(hi - lo, 1e-12)
        else:                                             # far away: named, so the bars keep their size
            ax.set_xlabel(f"the limit (margin 0) is off the axis to the {'left' if 0.0 < lo else 'right'}", fontsize=7,
                          color="red")
        ax.set_xlim(lo - 0.06 * width, hi + 0.06 * width)
        more = f" (+{len(contrib) - len(shown)} smaller)" if len(contrib) > len(shown) else ""
        ax.set_title(f"{r['name']}: margin ({r['unit']}), nominal {centre:.4g}, linear worst {r['linear_worst_margin']:.4g}"
                     f"{more}", fontsize=8)
        ax.tick_params(axis="x", labelsize=7)
    axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle("tolerance tornado: the margin's linear change, one variable at +tol or -tol\n(black: nominal margin, "
                 "red: the limit, dashed: linear worst case)", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _not_evaluable(count: int | None, samples: int) -> str:
    """Why a rule's sampled worst margin is missing: the samples where it could not be evaluated (failing)."""
    return f" (not evaluable in {count} of {samples} samples: counted as failing)" if count else ""


def monte_carlo_lines(mc: dict) -> list[str]:
    """The Monte-Carlo check in words: N, seed, the pass rate of all rules, then of every rule."""
    head = (f"Monte-Carlo check: {mc['samples']} samples (seed {mc['seed']}, {mc['distribution']}): "
            f"{_pct(mc.get('pass_rate'))} pass every rule")
    if mc.get("unevaluable"):
        head += f"; {mc['unevaluable']} sample(s) could not be evaluated (counted as failing)"
    return [head] + [f"  {n}: {_pct(r.get('pass_rate'))} pass, worst sampled margin "
                     f"{'-' if r.get('worst_margin') is None else format(r['worst_margin'], '.4g')}"
                     + _not_evaluable(r.get("unevaluable"), mc["samples"])
                     for n, r in (mc.get("rules") or {}).items()]


def _pct(rate) -> str:
    return "-" if rate is None else f"{100 * rate:.2f} %"


TORNADO_LINK = ("\n![tolerance tornado: each of the worst rules' margin, two bars per driving variable (its "
                "linear change at +tol and -tol, from the nominal margin)](tornado.png)\n\n"
                "[tornado.png](tornado.png): the linear stack-up of the worst rules, the largest contribution at the top\n")


NO_BOX_LINK = ("\n[tornado.png](tornado.png): empty -- with no tolerance box there is no stack-up to draw; the tables "
               "above are the derivatives\n")


def artifacts(kind: str, name: str, sha: str, facts: dict) -> dict:
    return {"result.json": lambda p: atomic_write_text(p, finite_json_text(result_json(kind, name, sha, facts))),
            "report.md": lambda p: atomic_write_text(p, full_table(facts) + (NO_BOX_LINK if no_box(facts) else
                                                                             TORNADO_LINK)),
            "tornado.png": lambda p: tornado(facts, p)}
