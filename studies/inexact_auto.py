"""``--starts auto`` on the inexact fourbar_path set (problems/fourbar_path/INEXACT.md): per problem and seed, the
best objective against the best known, the wall time, the starts solved and why auto stopped, and the stated
probability that the best found is the global optimum; then the calibration: of the runs that claim at least 95 %,
how many found the best known.

    python studies/inexact_auto.py OUT.md [--seeds 0,1,2] [--workers 2] [--max-starts 512] [--compiled FOLDER]
                                          [--only NAME ...]

--compiled FOLDER: the NLPs' functions compiled to C and cached in FOLDER (``solve --compiled``); a row's
``compile_s`` is the part of its wall spent compiling (0 once the libraries are there).

A study, not part of the installed tool or the test suite: its wall times are of whatever else the machine is doing.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from synthesis.core.compiled_code import compile_seconds
from synthesis.core.ipopt import solved_with_method
from synthesis.core.solve import AutoStarts, run_solve
from synthesis.kinds import solving_kind_for
from synthesis.kinds.fourbar_path.inexact import BEST_KNOWN, NAMES, inexact_spec

#: the objective within which a run counts as having found the best known (relative)
HIT = 1e-6


def one(name: str, seed: int, workers: int, max_starts: int, compiled: str | None = None) -> dict:
    loaded = inexact_spec(name, {"seed": seed})
    solved: list[int] = []
    kind = solving_kind_for(loaded)
    if compiled is not None:
        kind = solved_with_method(kind, compiled=compiled)
    compiling = compile_seconds()
    t0 = time.perf_counter()
    result = run_solve(kind, loaded, workers=workers, auto=AutoStarts(max_starts=max_starts),
                       on_start=lambda report, best: solved.append(report.outcome.start))[0]
    wall = time.perf_counter() - t0
    compiling = compile_seconds() - compiling
    value = result.objective.get("value")
    c = result.solver["confidence"] or {}
    best = BEST_KNOWN[name]
    return {"name": name, "seed": seed, "objective": value, "best_known": best,
            "hit": value is not None and value <= best * (1 + HIT), "wall_s": wall, "starts": result.solver["starts"],
            "solved": len(solved), "stopped_by": result.solver["auto"]["stopped_by"],
            "distinct_optima": c.get("distinct_optima"), "starts_at_best": c.get("starts_at_best"),
            "p_global": c.get("probability_best_is_global"), "status": result.status, "compile_s": compiling}


def main(argv: list[str]) -> int:
    out = Path(argv[0])
    seeds = [int(s) for s in argv[argv.index("--seeds") + 1].split(",")] if "--seeds" in argv else [0, 1, 2]
    workers = int(argv[argv.index("--workers") + 1]) if "--workers" in argv else 2
    max_starts = int(argv[argv.index("--max-starts") + 1]) if "--max-starts" in argv else 512
    compiled = str(Path(argv[argv.index("--compiled") + 1]).resolve()) if "--compiled" in argv else None
    only = argv[argv.index("--only") + 1:] if "--only" in argv else list(NAMES)
    rows = []
    for seed in seeds:
        for name in only:
            row = one(name, seed, workers, max_starts, compiled)
            rows.append(row)
            print(json.dumps(row), flush=True)
            out.with_suffix(".jsonl").write_text("\n".join(json.dumps(r) for r in rows) + "\n")
    lines = ["| problem | seed | best / best known | hit | wall s | starts (solved, stopped by) | optima | at best | "
             "P(global) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ratio = "-" if r["objective"] is None else f"{r['objective'] / r['best_known']:.4g}"
        p = "-" if r["p_global"] is None else f"{r['p_global']:.3f}"
        lines.append(f"| {r['name']} | {r['seed']} | {ratio} | {'yes' if r['hit'] else 'no'} | {r['wall_s']:.1f} | "
                     f"{r['starts']} ({r['solved']}, {r['stopped_by']}) | {r['distinct_optima']} | "
                     f"{r['starts_at_best']} | {p} |")
    for seed in seeds:
        of = [r for r in rows if r["seed"] == seed]
        walls = sorted(r["wall_s"] for r in of)
        lines.append(f"\nseed {seed}: best known on {sum(r['hit'] for r in of)} of {len(of)}; median wall "
                     f"{walls[len(walls) // 2] if len(walls) % 2 else 0.5 * (walls[len(walls) // 2 - 1] + walls[len(walls) // 2]):.1f} s, "
                     f"worst {walls[-1]:.1f} s")
    sure = [r for r in rows if r["p_global"] is not None and r["p_global"] >= 0.95]
    lines.append(f"\ncalibration: {len(sure)} runs claim P >= 0.95, of which {sum(r['hit'] for r in sure)} found the "
                 f"best known")
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
