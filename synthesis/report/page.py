"""The HTML page of one run (report.html) or of several candidates (compare.html).

One self-contained file: inline CSS, no script, no network fetch; figures are files beside it.
Built from the tables of :mod:`synthesis.report.tables` alone.
"""

from __future__ import annotations

import html
import json
import math

from synthesis.constraints.base import limit_text
from synthesis.report.tables import (GIVEN_HEADING, Candidate, Headline, RuleCell, design_rows, headlines, is_single_solve,
                                     operating_conditions, rule_rows, run_facts, shows_given, shows_given_rules, worst_margin,
                                     solved_heading, worst_margins)

IMAGE_SUFFIXES = (".png", ".svg", ".jpg", ".jpeg", ".gif")

CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 2em auto; max-width: 1200px;
       padding: 0 1em; color: #1d1d1f; line-height: 1.4; }
h1 { margin-bottom: .2em; } h2 { margin-top: 1.6em; border-bottom: 2px solid #e4e4e4; }
.lede { color: #555; margin-top: 0; }
.verdicts { display: flex; flex-wrap: wrap; gap: .6em; margin: 1em 0; }
.verdict { border-radius: 6px; padding: .5em .8em; background: #eaf6ea; border: 1px solid #b9dcb9; }
.verdict.bad { background: #fdecec; border-color: #f0b4b4; }
.verdict b { display: block; }
.verdict p.diagnosis { margin: .4em 0 0; max-width: 60em; font-size: .92em; }
.verdict ul.headline { margin: .4em 0 0; padding-left: 1.2em; font-variant-numeric: tabular-nums; }
table { border-collapse: collapse; margin: .8em 0; font-size: 14px; }
th, td { border-bottom: 1px solid #e4e4e4; padding: 4px 10px; text-align: left; vertical-align: top; }
th { background: #f5f5f7; position: sticky; top: 0; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.num .note { display: block; white-space: nowrap; }
td.limit { white-space: nowrap; }
table.facts td, .note { overflow-wrap: anywhere; }
.scroll { overflow-x: auto; max-width: 100%; }
.bound { display: block; font-size: 12px; color: #8a5a00; background: #fff1cc; border-radius: 3px; padding: 0 4px;
         white-space: nowrap; }
dl.columns { font-size: 13px; color: #444; margin: .4em 0 .8em; }
dl.columns dt { font-weight: 600; float: left; clear: left; margin-right: .5em; }
dl.columns dd { margin: 0 0 .2em 0; }
td.diff { background: #fff4cc; font-weight: 600; }
td.fail { background: #fde2e2; color: #a40000; font-weight: 600; }
td.pass { color: #1a7f37; }
tr.summary td { border-bottom: 2px solid #bbb; font-style: italic; }
.note { color: #666; font-size: 12px; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; box-sizing: border-box; border: 1px solid #eee; }
figcaption { color: #555; font-size: 13px; }
.missing { background: #fff8e1; border-left: 4px solid #f0b400; padding: .4em .8em; }
td, .verdict { print-color-adjust: exact; -webkit-print-color-adjust: exact; }
@media print { body { max-width: none; margin: 0; padding: 0; } th { position: static; }
               figure { break-inside: avoid; } .scroll { overflow: visible; }
               table { font-size: 11px; } th, td { padding: 3px 5px; } td.num .note { white-space: normal; } }
"""


def _num(v, digits: int = 4) -> str:
    if v is None:
        return "&ndash;"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_num(x, digits) for x in v) + "]"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "&ndash;" if not math.isfinite(v) else f"{v:.{digits}g}"
    return html.escape(str(v))


def _limit(limit) -> str:
    return limit_text(limit, ge="&ge;", le="&le;", none="&ndash;")


def _header(cands: list[Candidate]) -> str:
    if is_single_solve(cands):          # a solve's page: the question (given) beside the answer (solved)
        return f"<th>{html.escape(solved_heading(cands[0].result))}</th>"
    return "".join(f"<th>{html.escape(c.label)}{' (baseline)' if i == 0 and len(cands) > 1 else ''}</th>"
                   for i, c in enumerate(cands))


def _bounds_text(free, bounds) -> str:
    if free is None:
        return "&ndash;"
    if not free:
        return "fixed"
    return _num(bounds) if bounds else "free"


def _bounds_cell(row, cands: list[Candidate]) -> str:
    if row.per_candidate is not None:        # the specs disagree: each text once, with the headings that have it
        said: dict[str, list[str]] = {}
        for c, (free, bounds) in zip(cands, row.per_candidate):
            said.setdefault(_bounds_text(free, bounds), []).append(c.label)
        lines = [f"{html.escape(', '.join(labels))}: {text}" for text, labels in said.items()]
        return f"<td class='note'>{'<br>'.join(lines)}</td>"
    text = _bounds_text(row.free, row.bounds)
    return f"<td class='{'limit' if row.free and row.bounds else 'note'}'>{text}</td>"


_AT_BOUND = {"lower": "at lower bound", "upper": "at upper bound"}


def design_table(cands: list[Candidate]) -> str:
    given = shows_given(cands)
    rows = []
    for row in design_rows(cands):
        cells = []
        for i, (v, d) in enumerate(zip(row.values, row.differs)):
            mark = row.at_bound[i] if i < len(row.at_bound) else ""
            flag = f"<span class='bound'>{_AT_BOUND[mark]}</span>" if mark else ""
            cells.append(f"<td class='num{' diff' if d else ''}'>{_num(v, 6)}{flag}</td>")
        start = f"<td class='num'>{_num(row.given, 6)}</td>" if given else ""
        rows.append(f"<tr><td>{html.escape(row.name)}</td><td>{html.escape(row.unit)}</td>{_bounds_cell(row, cands)}"
                    f"{start}{''.join(cells)}</tr>")
    head = f"<th>{GIVEN_HEADING}</th>" if given else ""
    return (f"<table class='design'><tr><th>variable</th><th>unit</th><th>bounds</th>{head}{_header(cands)}</tr>\n"
            + "\n".join(rows) + "</table>")


def design_columns(cands: list[Candidate]) -> str:
    """What each column of the design table means, said once."""
    items = [("unit", "as written in the spec (mm, deg, m/s, r/min)."),
             ("bounds", "[lo, hi] within which <code>solve</code> may move a free variable; <i>fixed</i>: the spec "
                        "gives a number, kept as it is; &ndash;: the result does not say.  Where the designs' specs "
                        "disagree (a published design beside a redesign), each design's own is listed.")]
    if shows_given(cands):
        items.append(("given (start 0)", "the design written in the spec: the question; the next column is the answer."))
    if any(c.result.solver is not None for c in cands):
        items.append(("at lower / upper bound", "the value sits on that bound: in a solved design the optimiser was "
                                               "held there, and widening the bound (if the machine allows) may improve "
                                               "the objective; in a checked one it is the spec's own value."))
    else:         # checks only: no optimiser moved anything
        items.append(("at lower / upper bound", "the spec's value sits on that bound: a solve from it could move it "
                                               "no further that way."))
    if len(cands) > 1:
        items.append(("highlighted", "differs from the baseline (first candidate)."))
    return "<dl class='columns'>" + "".join(f"<dt>{k}</dt><dd>{v}</dd>" for k, v in items) + "</dl>"


RULE_COLUMNS = (
    ("limit", "the allowed range of the rule's value (&ge; lo, &le; hi, or [lo, hi])."),
    ("value", "the rule's value at its worst sample; sampled rules (over a crank turn, a phase, a range) are "
              "evaluated on the fine check grid, 10x the solver's samples."),
    ("margin", "distance from the value to the nearest limit, in the rule's unit; negative = violated (red)."),
    ("normalised margin", "the margin divided by the rule's scale, so that rules of different units compare; "
                          "the first row names each candidate's smallest: its tightest rule."),
)


def rule_columns(cands: list[Candidate] | None = None) -> str:
    items = list(RULE_COLUMNS)
    if cands is not None and shows_given_rules(cands):
        items.insert(1, ("given (start 0)", "the rule at the design written in the spec (the question); the next "
                                            "column is the solution's (the answer)."))
    return "<dl class='columns'>" + "".join(f"<dt>{k}</dt><dd>{v}</dd>" for k, v in items) + "</dl>"


def _rule_cell(cell: RuleCell | None, row_limit) -> str:
    if cell is None:
        return "<td class='note'>no such rule</td>"
    own_limit = "" if cell.limit == row_limit else f" (limit {_limit(cell.limit)})"
    if cell.satisfied:
        return (f"<td class='num pass' title='{html.escape(cell.note)}'>{_num(cell.value)} "
                f"<span class='note'>margin {_num(cell.margin, 3)}{own_limit}</span></td>")
    if cell.value is None:        # its own limit still said: the row's is the first candidate's
        return (f"<td class='fail'>not evaluated <span class='note'>{html.escape(cell.note)}{own_limit}</span>"
                f"</td>")
    return (f"<td class='num fail' title='{html.escape(cell.note)}'>{_num(cell.value)} FAIL"
            f"<span class='note'>margin {_num(cell.margin, 3)}{own_limit}</span></td>")


def _worst_cell(w) -> str:
    if w.rule is None:
        return "<td>&ndash;</td>"
    if not w.evaluated:
        margin = "not evaluated"
    elif w.normalised_margin is not None:
        margin = f"normalised margin {w.normalised_margin:.3g}"
    elif w.margin is not None and math.isfinite(w.margin):
        margin = f"margin {w.margin:.3g}{f' {w.unit}' if w.unit and w.unit not in ('-', '1') else ''}"
    else:
        margin = "violated"
    tally = f"{w.violated} violated" if w.violated else "all pass"
    return f"<td class='{'fail' if w.violated else 'pass'}'>{html.escape(w.rule)}: {margin}; {tally}</td>"


def rule_table(cands: list[Candidate]) -> str:
    given = shows_given_rules(cands)
    summary = [_worst_cell(w) for w in worst_margins(cands)]
    # the given design's column says its tightest rule as the candidates' do
    start = _worst_cell(worst_margin(cands[0].given_rules or [])) if given else ""
    rows = [f"<tr class='summary'><td>worst margin</td><td></td><td></td>{start}{''.join(summary)}</tr>"]
    for row in rule_rows(cands):
        first = _rule_cell(row.given, row.limit) if given and row.given is not None else (
            "<td class='note'>&ndash;</td>" if given else "")
        cells = "".join(_rule_cell(cell, row.limit) for cell in row.cells)
        rows.append(f"<tr><td>{html.escape(row.name)}</td><td class='limit'>{_limit(row.limit)}</td>"
                    f"<td>{html.escape(row.unit)}</td>{first}{cells}</tr>")
    head = f"<th>{GIVEN_HEADING}</th>" if given else ""
    return (f"<table class='rules'><tr><th>rule</th><th>limit</th><th>unit</th>{head}{_header(cands)}</tr>\n"
            + "\n".join(rows) + "</table>")


def conditions_table(cands: list[Candidate]) -> str:
    """The operating conditions (crank and forward speed ...) the designs were evaluated at; "" if none."""
    rows = operating_conditions(cands)
    if not rows:
        return ""
    body = "\n".join(f"<tr><td>{html.escape(name)}</td><td>{html.escape(unit)}</td>"
                     + "".join(f"<td class='num'>{_num(v, 6)}</td>" for v in values) + "</tr>"
                     for name, unit, values in rows)
    return ("<h2>Operating conditions</h2>\n<div class='scroll'><table class='conditions'><tr><th>condition</th>"
            f"<th>unit</th>{_header(cands)}</tr>\n{body}</table></div>")


def facts_table(cands: list[Candidate]) -> str:
    rows = "\n".join(f"<tr><td>{html.escape(name)}</td>{''.join(f'<td>{_num(v, 3)}</td>' for v in values)}</tr>"
                     for name, values in run_facts(cands))
    return f"<table class='facts'><tr><th></th>{_header(cands)}</tr>\n{rows}</table>"


def _headline(head: Headline) -> str:
    """A candidate's headline lines, in its verdict box (the page's first screen)."""
    if not head.lines:
        return ""
    return "<ul class='headline'>" + "".join(f"<li>{html.escape(line)}</li>" for line in head.lines) + "</ul>"


def result_tables(heads: list[Headline]) -> str:
    """The kinds' tables of their results' own figures (a path's error per target), each under its title; with
    several candidates, each candidate's own, labelled."""
    parts = []
    for head in heads:
        for table in head.tables:
            label = f" &mdash; {html.escape(head.label)}" if len(heads) > 1 else ""
            columns = "".join(f"<th>{html.escape(c)}</th>" for c in table.columns)
            rows = "\n".join("<tr>" + "".join(f"<td class='num'>{_num(v)}</td>" if not isinstance(v, str)
                                              else f"<td>{html.escape(v)}</td>" for v in row) + "</tr>"
                             for row in table.rows)
            parts.append(f"<h2>{html.escape(table.title)}{label}</h2>\n<div class='scroll'><table class='result'>"
                         f"<tr>{columns}</tr>\n{rows}</table></div>")
    return "\n".join(parts)


def _verdicts(cands: list[Candidate], heads: list[Headline] | None = None) -> str:
    heads = headlines(cands) if heads is None else heads
    out = []
    for c, head in zip(cands, heads):
        bad = [r["name"] for r in c.result.violated()]
        text = "every rule satisfied" if not bad else f"{len(bad)} rule(s) violated: {', '.join(bad)}"
        # an infeasible or failed solve keeps its exit-3 message: which rules are out of reach, what to change
        diagnosis = (c.result.solver or {}).get("diagnosis")
        said = f"<p class='diagnosis'>{html.escape(diagnosis)}</p>" if isinstance(diagnosis, str) else ""
        out.append(f"<div class='verdict{' bad' if bad else ''}'><b>{html.escape(c.label)}</b>"
                   f"{html.escape(c.result.status)}: {html.escape(text)}{_headline(head)}{said}</div>")
    return f"<div class='verdicts'>{''.join(out)}</div>"


def _text(value) -> str:
    """A cell's text, escaped: a bench.json a hand edited may hold any JSON value where text belongs (a method of null
    or 1e300 was an AttributeError out of html.escape); none or empty is a dash."""
    if value is None or value == "":
        return "–"
    return html.escape(value if isinstance(value, str) else json.dumps(value)[:80])


def bench_table(bench: list[dict]) -> str:
    """Objective reached, median wall time and time to target of each method per problem, with the ratio of the
    times to target."""
    rows = []
    for res in bench:
        for row in res["rows"]:
            rows.append(f"<tr><td>{_text(row.get('problem'))}</td><td>{_text(row.get('method'))}</td>"
                        f"<td class='num'>{_num(row.get('objective'))}</td>"
                        f"<td class='num'>{_num(row.get('objective_gap'), 3)}</td>"
                        f"<td class='num'>{_num(row.get('worst_violation'), 3)}</td>"
                        f"<td class='num'>{_num(row.get('median_s'), 3)}</td>"
                        f"<td class='num'>{_text(row.get('time_to_target_text'))}</td>"
                        f"<td class='num'>{_text(row.get('time_ratio_text'))}</td></tr>")
    return ("<table class='bench'><tr><th>problem</th><th>method</th><th>objective</th><th>gap to best</th>"
            "<th>worst violation</th><th>median s</th><th>time to target s</th><th>time-to-target ratio</th></tr>\n"
            + "\n".join(rows) + "</table>")


def tolerance_section(cands: list[Candidate]) -> str:
    """The Monte-Carlo check of a tolerance-robust solve's answer (result facts ``tolerance.monte_carlo``): N, seed,
    the pass rate of all rules and of every rule, each rule's worst sampled margin; empty without one."""
    parts = []
    for c in cands:
        tol = (c.result.extra or {}).get("tolerance")
        mc = tol.get("monte_carlo") if isinstance(tol, dict) else None
        if not isinstance(mc, dict):
            continue
        info = c.result.design_variables or {}
        # a hand-edited result may hold anything here: what is not a table of numbers is left out
        follows = tol.get("follows") if isinstance(tol.get("follows"), dict) else {}
        widths = tol.get("box") if isinstance(tol.get("box"), dict) else {}
        box = ", ".join(f"{k} ±{v:g}" + (f" {info[k]['unit']}" if (info.get(k) or {}).get("unit") else "")
                        + (f" (follows {', '.join(map(str, follows[k]))})" if isinstance(follows.get(k), dict) else "")
                        for k, v in widths.items() if isinstance(v, (int, float)) and not isinstance(v, bool) and v)
        rate = mc.get("pass_rate")
        rules = mc.get("rules") if isinstance(mc.get("rules"), dict) else {}
        rows = "".join(f"<tr><td>{html.escape(str(n))}</td><td class='num'>{_rate(r.get('pass_rate'))}</td>"
                       f"<td class='num'>{_num(r.get('worst_margin'))}</td></tr>"
                       for n, r in rules.items() if isinstance(r, dict))
        label = f"<b>{html.escape(c.label)}</b>: " if len(cands) > 1 else ""
        if mc.get("samples") == 0:        # tolerance --samples 0: the linear stack-up alone is the verdict
            parts.append(f"<p>{label}no Monte-Carlo check (0 samples): the verdict is the linear stack-up's, the "
                         f"<code>@tolerance</code> rows of the rule table.</p>")
            continue
        unevaluable = mc.get("unevaluable")
        parts.append(
            f"<p>{label}Monte-Carlo check of the answer: {html.escape(str(mc.get('samples')))} samples (seed "
            f"{html.escape(str(mc.get('seed')))}, "
            f"{html.escape(str(mc.get('distribution', '')))}{'; box ' + html.escape(box) if box else ''}): "
            f"<b>{_rate(rate)}</b> pass every rule"
            + (f"; {html.escape(str(unevaluable))} sample(s) could not be evaluated" if unevaluable else "") + ".</p>"
            f"<table class='tolerance'><tr><th>rule</th><th>MC pass rate</th><th>worst sampled margin</th></tr>"
            f"<tr><td><i>all rules</i></td><td class='num'>{_rate(rate)}</td><td></td></tr>{rows}</table>")
    return "<h2>Tolerance</h2>\n" + "\n".join(parts) if parts else ""


def _rate(rate) -> str:
    """A pass rate as a percentage; "-" for none, or for anything a hand-edited result put there that is no number."""
    if not isinstance(rate, (int, float)) or isinstance(rate, bool) or not math.isfinite(rate):
        return "&ndash;"
    return f"{100 * rate:.2f} %"


def render(cands: list[Candidate], figures: list[tuple[str, str]], notes: list[str], title: str,
           bench: list[dict] | None = None) -> str:
    """``figures`` = [(file name, caption)], ``notes`` = figures that could not be drawn, and why;
    ``bench`` = the per-problem results of an ``agrisynth bench`` run, shown as a table."""
    kind = cands[0].result.kind
    source = cands[0].result.extra.get("source") or ""
    names = {f for f, _ in figures}
    # an SVG beside a PNG of the same figure is the scalable copy: linked, not shown twice
    copies = {f for f in names if f.lower().endswith(".svg") and f[:-4] + ".png" in names}
    images = [(f, cap) for f, cap in figures if f.lower().endswith(IMAGE_SUFFIXES) and f not in copies]
    exports = [f for f, _ in figures if not f.lower().endswith(IMAGE_SUFFIXES) or f in copies]   # CSV, DXF, SVG
    figs = "\n".join(f"<figure><img src='{html.escape(f)}' alt='{html.escape(cap)}'>"
                     f"<figcaption>{html.escape(cap)}</figcaption></figure>" for f, cap in images)
    if exports:
        figs += "\n<p>Files: " + ", ".join(f"<a href='{html.escape(f)}'>{html.escape(f)}</a>" for f in exports) + "</p>"
    missing = "\n".join(f"<p class='missing'>{html.escape(n)}</p>" for n in notes)
    heads = headlines(cands)
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{html.escape(title)} &mdash; agrisynth</title>
<style>{CSS}</style></head><body>
<h1>{html.escape(title)}</h1>
<p class="lede">kind <code>{html.escape(kind)}</code>{(' &middot; ' + html.escape(source)) if source else ''}</p>
{_verdicts(cands, heads)}
{result_tables(heads)}
<h2>Rules</h2>
{rule_columns(cands)}
<div class="scroll">{rule_table(cands)}</div>
<h2>Design</h2>
{design_columns(cands)}
<div class="scroll">{design_table(cands)}</div>
{conditions_table(cands)}
{tolerance_section(cands)}
<h2>Figures</h2>
{figs}
{missing}
{'<h2>Error against run time</h2>' + bench_table(bench) if bench else ''}
<h2>Run facts</h2>
<div class="scroll">{facts_table(cands)}</div>
</body></html>
"""
