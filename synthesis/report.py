"""Single-result HTML report, built from a Result alone (one file plus the figures beside it)."""

from __future__ import annotations

import html
from pathlib import Path

from constraints.base import limit_text
from synthesis.result import Result


IMAGE_SUFFIXES = (".png", ".svg", ".jpg", ".jpeg", ".gif")


def _fmt(v) -> str:
    if v is None:
        return "&ndash;"
    if isinstance(v, float):
        return f"{v:.4g}"
    return html.escape(str(v))


def _limit(limit) -> str:
    return limit_text(limit, ge="&ge;", le="&le;", none="&ndash;")


def render(result: Result, figures: list[str]) -> str:
    rows = "\n".join(
        f"<tr class='{'ok' if r['satisfied'] else 'bad'}'><td>{html.escape(r['name'])}</td>"
        f"<td>{_fmt(r['value'])}</td><td>{_limit(r['limit'])}</td><td>{html.escape(r['unit'])}</td>"
        f"<td>{_fmt(r['margin'])}</td><td>{'pass' if r['satisfied'] else 'FAIL'}</td>"
        f"<td>{html.escape(r.get('where') or '')}{(' &mdash; ' + html.escape(r['note'])) if r.get('note') else ''}</td></tr>"
        for r in result.rules)
    design = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>" for k, v in result.design.items())
    facts = {"kind": result.kind, "status": result.status, "spec sha256": result.spec_sha256,
             **{f"version {k}": v for k, v in result.versions.items()}}
    if result.solver:
        facts.update({f"solver {k}": v for k, v in result.solver.items()})
    fact_rows = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>" for k, v in facts.items())
    images = [f for f in figures if f.lower().endswith(IMAGE_SUFFIXES)]
    files = [f for f in figures if f not in images]       # exports (CSV, DXF ...): linked, not shown
    imgs = "\n".join(f"<figure><img src='{html.escape(f)}' alt='{html.escape(f)}'></figure>" for f in images)
    if files:
        imgs += "\n<p>Files: " + ", ".join(f"<a href='{html.escape(f)}'>{html.escape(f)}</a>" for f in files) + "</p>"
    n_bad = len(result.violated())
    verdict = "every rule satisfied" if n_bad == 0 else f"{n_bad} rule(s) violated"
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(result.name)} &mdash; agrisynth</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border-bottom: 1px solid #ddd; padding: 3px 10px; text-align: left; font-variant-numeric: tabular-nums; }}
tr.bad td {{ background: #fde2e2; color: #a40000; }}
img {{ max-width: 100%; }}
</style></head><body>
<h1>{html.escape(result.name)}</h1>
<p>{html.escape(result.extra.get('source', ''))}</p>
<p><strong>{result.status}</strong>: {verdict}.</p>
{imgs}
<h2>Rules</h2>
<table><tr><th>rule</th><th>value</th><th>limit</th><th>unit</th><th>margin</th><th></th><th>where</th></tr>
{rows}</table>
<h2>Design</h2><table>{design}</table>
<h2>Run</h2><table>{fact_rows}</table>
</body></html>
"""


def write_report(result: Result, path: Path, figures: list[str]) -> None:
    path.write_text(render(result, figures))
