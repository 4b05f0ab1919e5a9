"""How sure is each library answer?  For every library spec that solves (free variables; the slow tolerance-robust
and envelope specs only with ``--all``): the spec's own fixed starts and ``--starts auto``, one worker each, and a
markdown table of the distinct optima among the converged starts, the starts reaching the best, Boender & Rinnooy
Kan's P(best is global) (synthesis/core/confidence.py), and what ``auto`` used (starts solved, batches, why it
stopped, time) against the fixed default.

    python studies/confidence_table.py OUT.md [--all] [--max-starts N] [--only SUBSTRING ...]

A study, not part of the installed tool or the test suite.  Wall times are of one worker on whatever else the
machine is doing at the time: compare them within a row, not across runs.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

LIBRARY = Path(__file__).resolve().parents[1] / "problems"
#: specs whose solve takes minutes: only with --all (as studies/library_answers.py)
SLOW = ("robust_", "envelope_", "mu_envelope")


def _row(path: Path, max_starts: int) -> str | None:
    from synthesis import kinds
    from synthesis.core.solve import AutoStarts, run_solve
    from synthesis.errors import AgrisynthError
    from synthesis.spec import load_spec

    loaded = load_spec(path)
    if not kinds.get(loaded.kind).solves:
        return None
    kind = kinds.solving_kind_for(loaded)
    name = str(path.relative_to(LIBRARY))
    try:
        t0 = time.perf_counter()
        fixed = run_solve(kind, loaded, workers=1)[0]
        fixed_s = time.perf_counter() - t0
        solved = []
        t0 = time.perf_counter()
        auto = run_solve(kind, loaded, workers=1, auto=AutoStarts(max_starts=max_starts),
                         on_start=lambda report, best: solved.append(report.outcome.start))[0]
        auto_s = time.perf_counter() - t0
    except AgrisynthError as err:
        return f"| {name} | {loaded.kind} | exit {err.exit_code}: {str(err).splitlines()[0][:80]} |" + " |" * 9
    c = fixed.solver["confidence"] or {}
    a = auto.solver["confidence"] or {}
    fa, ff = auto.objective.get("value"), fixed.objective.get("value")
    if fa == ff:
        same = "bit-identical"
    elif fa is None or ff is None:
        same = "no"
    else:
        gap = (fa - ff) / max(1.0, abs(ff))
        same = "same to 1e-6" if abs(gap) <= 1e-6 else f"{fa:.6g} ({gap:+.2g} relative)"

    def p(v):
        return "-" if v is None else f"{v:.2f}"

    return (f"| {name} | {loaded.kind} | {fixed.status} | {fixed.solver['starts']} | {c.get('starts_counted')} | "
            f"{c.get('distinct_optima')} | {c.get('starts_at_best')} | {p(c.get('probability_best_is_global'))} | "
            f"{fixed_s:.1f} | {auto.solver['starts']} ({len(solved)} solved, {auto.solver['auto']['stopped_by']}) | "
            f"{a.get('distinct_optima')} / {p(a.get('probability_best_is_global'))} | {auto_s:.1f} | {same} |")


def main(argv: list[str]) -> int:
    if not argv or argv[0].startswith("-"):
        print(__doc__.split("\n\n")[1].strip() if __doc__ else "", file=sys.stderr)
        return 0 if argv[:1] in (["-h"], ["--help"]) else 2
    out = Path(argv[0])
    every = "--all" in argv
    only = argv[argv.index("--only") + 1:] if "--only" in argv else []
    max_starts = int(argv[argv.index("--max-starts") + 1]) if "--max-starts" in argv else 512
    lines = ["| spec | kind | status | fixed starts | converged | distinct optima | starts at best | P(global) | "
             "fixed s | auto starts (solved, stopped by) | auto optima / P(global) | auto s | auto's objective |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for path in sorted(LIBRARY.rglob("*.toml")):
        if (not every and any(s in path.name for s in SLOW)) or (only and not any(o in str(path) for o in only)):
            continue
        try:
            row = _row(path, max_starts)
        except Exception as exc:          # a spec that is not a problem (a data file) or cannot be loaded
            row = f"| {path.relative_to(LIBRARY)} | not solved: {type(exc).__name__} |" + " |" * 11
        if row is not None:
            lines.append(row)
            print(row, flush=True)
            out.write_text("\n".join(lines) + "\n")
    out.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
