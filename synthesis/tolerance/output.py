"""The folder of ``agrisynth tolerance``: result.json (result-like, schema version 2, the analysis under
``facts``), report.md (the stack-up table) and tornado.png (each rule's linear margin loss by variable)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from synthesis.result import atomic_write_text, finite_json_text


def result_json(kind: str, name: str, sha: str, facts: dict) -> dict:
    rules = facts["nominal_rules"]
    return {"schema_version": 2, "kind": kind, "name": f"{name}-tolerance", "spec_sha256": sha,
            "status": "evaluated", "design": facts["design"], "rules": rules, "facts": {"tolerance": facts}}


def table(facts: dict) -> str:
    mc = facts["monte_carlo"]
    lines = [f"Monte-Carlo: {mc['samples']} samples (seed {mc['seed']}, {mc['distribution']}): "
             f"{100 * (mc['pass_rate'] or 0):.2f} % pass every rule"
             + (f" at every operating point ({100 * (mc['envelope']['pass_rate_at_nominal'] or 0):.2f} % at the nominal "
                "point alone)" if mc.get("envelope") else ""), *_envelope_lines(mc), "",
             "| rule | unit | margin | linear worst margin | drivers | MC pass | MC worst margin | linear / sampled loss "
             "| margin at the linear worst corner | linear vs sampled gap |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    notes = []
    for r in facts["stack_up"]:
        def f(v, fmt="{:.4g}"):
            return "-" if v is None else fmt.format(v)
        drivers = ", ".join(f"{d['variable']} {d['contribution']:.3g}" for d in r["drivers"])
        lines.append(f"| {r['name']} | {r['unit']} | {f(r['recheck_margin'])} | {f(r['linear_worst_margin'])} | {drivers} "
                     f"| {f(r['mc_pass_rate'], '{:.1%}')} | {f(r['mc_worst_margin'])} | {f(r['linear_over_sampled'], '{:.2f}')} "
                     f"| {f(r.get('corner_margin'))} | {f(r.get('linear_vs_sampled_gap'), '{:.1%}')} |")
        if r.get("gap_explanation"):
            notes.append(f"* {r['name']}: {r['gap_explanation']}")
    if facts.get("operating"):
        ops = facts["operating"]
        lines += ["", "Derivatives w.r.t. the operating conditions (exact, each rule at its scenario's values; "
                      "nominal " + ", ".join(f"{n} = {o['nominal']:g} {o['unit']}" for n, o in ops.items()) + "):", "",
                  "| rule | unit | " + " | ".join(f"d/d {n} (per {o['unit']})" for n, o in ops.items()) + " |",
                  "|---|---|" + "---|" * len(ops)]
        for r in facts["stack_up"]:
            sens = r.get("operating_sensitivity") or {}
            lines.append(f"| {r['name']} | {r['unit']} | " + " | ".join(f"{sens.get(n, 0.0):.4g}" for n in ops) + " |")
        unused = [n for n, rules in (facts.get("operating_dependence") or {}).items() if not rules]
        if unused:
            lines += ["", f"No rule's value depends on {', '.join(unused)}: the derivative is exactly 0 for every rule "
                          "(the condition may still move a rule's limit or the objective)."]
    if notes:
        lines += ["", "Linear vs sampled worst case (sampled: the Monte-Carlo and each rule's linear worst corner; "
                      "the gap is |linear loss - sampled loss| / sampled loss, 10 % expected) explained:"] + notes
    return "\n".join(lines) + "\n"


def _envelope_lines(mc: dict) -> list[str]:
    """The Monte-Carlo's pass rate of each rule over the operating range (its worst grid point), for an envelope."""
    rows = {n: r for n, r in mc["rules"].items() if n.endswith("@envelope")}
    if not rows:
        return []
    return ["", "| rule over the operating range | MC pass (every point) | MC worst margin |", "|---|---|---|"] + [
        f"| {n} | {r['pass_rate']:.1%} | {'-' if r['worst_margin'] is None else format(r['worst_margin'], '.4g')} |"
        for n, r in rows.items()]


def tornado(facts: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = facts["stack_up"]
    keys = list(facts["tolerance"])
    box = np.array([facts["tolerance"][k]["half_width"] for k in keys])
    # normalised loss per rule and variable: |dg/dd_j| tol_j / rule scale
    loss = np.array([[abs(r["sensitivity"][k]) * b / r["scale"] for k, b in zip(keys, box)] for r in rows])
    order = np.argsort(loss.sum(axis=1))
    fig, ax = plt.subplots(figsize=(8, 0.35 * len(rows) + 1.5))
    left = np.zeros(len(rows))
    for j, k in enumerate(keys):
        if not np.any(loss[:, j] > 0):
            continue
        ax.barh(np.arange(len(rows)), loss[order, j], left=left[order], label=k)
        left[order] += loss[order, j]
    ax.set_yticks(np.arange(len(rows)), [rows[i]["name"] for i in order])
    ax.set_xlabel("linear margin loss at the box's worst corner / rule scale")
    ax.set_title("tolerance stack-up by design variable")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def artifacts(kind: str, name: str, sha: str, facts: dict) -> dict:
    return {"result.json": lambda p: atomic_write_text(p, finite_json_text(result_json(kind, name, sha, facts))),
            "report.md": lambda p: atomic_write_text(p, table(facts)),
            "tornado.png": lambda p: tornado(facts, p)}
