"""``agrisynth compare``: several results of one kind side by side in one page, from result.json alone.

Among the inputs may be the output of ``agrisynth bench`` (its --out folder, the bench/ folder in it, or bench.json):
its error-against-run-time plot and table are added to the page.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from synthesis.errors import OutputError, ResultError
from synthesis.files import read_json
from synthesis.report import comparison_figures
from synthesis.report.page import render
from synthesis.report.tables import Candidate, candidates
from synthesis.result import MAX_RESULT_BYTES, RUN_NAME, atomic_write_text, load_result, open_run_folder
from synthesis.spec import KINDS


def bench_file(path: Path) -> Path | None:
    """The bench.json ``path`` names: the file, a folder holding it, or the folder `agrisynth bench --out` was
    given (it writes OUT/bench/bench.json); None when ``path`` is no bench."""
    if path.name == "bench.json":
        return path
    if path.is_dir() and not (path / "result.json").exists():
        for candidate in (path / "bench.json", path / "bench" / "bench.json"):
            if candidate.exists():
                return candidate
    return None


def is_bench(path: Path) -> bool:
    return bench_file(path) is not None


def load_bench(path: Path) -> list[dict]:
    """The per-problem results of a bench.json, shaped as ``synthesis.bench.run_case`` returns them."""
    path = bench_file(path) or path / "bench.json"
    data = read_json(path, MAX_RESULT_BYTES, "bench.json", ResultError, "a bench.json")
    try:
        rows, problems = data["rows"], data["problems"]
        for row in rows:
            missing = [key for key in BENCH_ROW_KEYS if key not in row]
            if missing:
                raise KeyError(f"a row lacks {', '.join(missing)}")
            row["worst_violation"] = _number(row["worst_violation"])
        return [dict(p, rows=[r for r in rows if r["problem"] == p["problem"]], best_known=_number(p["best_known"]))
                for p in problems]
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ResultError(f"{path}: not a readable agrisynth bench.json ({type(exc).__name__}: "
                          f"{str(exc)[:120]})") from None


def bench_of_kind(path: Path, problems: list[dict], kind: str) -> list[dict]:
    """The problems of a bench that are of the compared results' kind (a bench of every kind gives its rows for
    this one); a bench with none of them is refused: its error-against-run-time figures are another mechanism's.
    A problem whose kind the bench.json does not say is kept."""
    kept = [p for p in problems if p.get("kind", kind) == kind]
    if problems and not kept:
        theirs = ", ".join(sorted({str(p.get("kind")) for p in problems}))
        raise ResultError(f"{path}: a bench of {theirs} problems, not of {kind} like the results compared; give the "
                          f"bench of a {kind} run (agrisynth bench {kind})")
    return kept


#: what the error-against-run-time plot and table read from each bench row
BENCH_ROW_KEYS = ("problem", "method", "objective", "objectives", "objective_gap", "worst_violation",
                  "wall_s", "median_s", "trace")


def _number(v) -> float:
    """bench.json writes a value that could not be measured as null."""
    return math.nan if v is None else float(v)


def load_candidates(paths: list[Path]) -> list[Candidate]:
    """Read every result (run folder or result.json); one kind only, the first is the baseline."""
    if not paths:
        raise ResultError("compare needs at least one RESULT (a run folder or its result.json)")
    results = [load_result(p) for p in paths]
    files = [p / "result.json" if p.is_dir() else p for p in paths]
    for f, r in zip(files, results):
        if r.kind not in KINDS:
            raise ResultError(f"{f}: kind {r.kind!r} is not one this agrisynth knows ({', '.join(KINDS)})")
    kinds = {r.kind for r in results}
    if len(kinds) > 1:
        listing = "; ".join(f"{f}: {r.kind}" for f, r in zip(files, results))
        raise ResultError(f"compare takes results of one kind, got {len(kinds)} kinds ({listing})")
    return candidates(results, files)


def _different_targets(cands: list[Candidate]) -> list[str]:
    """A note when the candidates trace different target points (facts.targets, a path's): their objectives,
    distances to their own targets, are then not comparable, and a page of them side by side should say so."""
    targets = [c.result.extra.get("targets") if isinstance(c.result.extra, dict) else None for c in cands]
    if len(cands) < 2 or any(not isinstance(t, list) for t in targets) or all(t == targets[0] for t in targets):
        return []
    sizes = ", ".join(f"{c.label}: {len(t)}" for c, t in zip(cands, targets))
    return [f"the candidates trace different target points ({sizes} points): each objective measures the distance to "
            f"its own targets, so they do not compare"]


#: objectives measured from each spec's own given design: two of them from different given designs do not compare
FROM_THE_GIVEN_DESIGN = ("nearest",)


def _different_objectives(cands: list[Candidate]) -> list[str]:
    """A note when the solved candidates' objectives do not compare: different objectives (or units), or one measured
    from each spec's own given design (a redesign's "nearest") where those given designs differ."""
    solved = [c for c in cands if isinstance(c.result.objective, dict)]
    if len(solved) < 2:
        return []
    kinds_of = {(c.result.objective.get("name"), c.result.objective.get("unit")) for c in solved}
    if len(kinds_of) > 1:
        said = ", ".join(f"{c.label}: {c.result.objective.get('name')}" for c in solved)
        return [f"the candidates minimise different objectives ({said}): their values do not compare"]
    name = next(iter(kinds_of))[0]
    # the given design and the bounds the distance is scaled by (planting's: relative to the bounds)
    given = [(c.result.baseline_design, {k: (v or {}).get("bounds") for k, v in (c.result.design_variables or {}).items()
                                         if isinstance(v, dict)}) for c in solved]
    if name in FROM_THE_GIVEN_DESIGN and any(g != given[0] for g in given):
        return [f"each candidate's {name} objective is its design's distance from its own spec's given design (and "
                f"bounds), and those differ: the values do not compare"]
    return []


def different_versions(cands: list[Candidate]) -> list[str]:
    """A note when the candidates were written by different versions of agrisynth or CasADi (``versions``): a rule's
    model, a default or the solver may have changed between them, so a difference on the page may be the tool's."""
    notes = []
    for package in ("agrisynth", "casadi"):
        # a hand-edited file may hold any JSON there: compared and shown as text
        seen = {c.label: (c.result.versions if isinstance(c.result.versions, dict) else {}).get(package)
                for c in cands}
        texts = {label: "not recorded" if v is None else str(v) for label, v in seen.items()}
        if len(cands) >= 2 and len(set(texts.values())) > 1:
            shown = ", ".join(f"{label}: {text[:40]}" for label, text in texts.items())
            notes.append(f"the candidates were written by different versions of {package} ({shown}): a difference "
                         f"between them may be the tool's, not the design's")
    return notes


def write_comparison(cands: list[Candidate], out: Path, bench: list[dict] | None = None, *, force: bool = False,
                     folder=None) -> Path:
    """Write the folder ``out`` (compare.html and its figures) as a run folder (``.agrisynth-run``
    marker): through a staging folder moved into place at the end.  An earlier agrisynth output there
    is replaced only with ``force``; anything else there is never replaced (OutputError, exit 2).
    ``folder``: the :class:`~synthesis.result.RunFolder` already opened for ``out`` (the CLI opens it
    before reading anything, so a refusal comes before any work)."""
    folder = open_output_folder(out, force) if folder is None else folder
    folder.fill(lambda staging: write_comparison_files(cands, staging, bench))
    return Path(out) / "compare.html"


def write_comparison_files(cands: list[Candidate], staging: Path, bench: list[dict] | None = None) -> None:
    """compare.html and its figures, written into ``staging`` (a run folder's staging folder: the writer of run
    folders, ``RunFolder.fill``, moves it into place)."""
    figures, notes = comparison_figures(cands, staging)
    notes = different_versions(cands) + _different_targets(cands) + _different_objectives(cands) + notes
    if bench:
        from synthesis.report.bench_plots import plot_error_vs_time

        try:
            plot_error_vs_time(bench, staging / "error_vs_time.png")
            figures.append(("error_vs_time.png", "error against run time (agrisynth bench): objective gap "
                                                 "and worst fine-grid violation against wall time"))
        except Exception as exc:    # noqa: BLE001 - the table still shows the bench; say why the plot is missing
            notes.append(f"error_vs_time.png not drawn: {type(exc).__name__}: {exc}")
    title = "compare: " + " vs ".join(c.label for c in cands)
    atomic_write_text(staging / "compare.html", render(cands, figures, notes, title, bench))


def open_output_folder(out: Path, force: bool = False):
    """The run folder of an output written to ``out`` itself (compare, bench): :func:`open_run_folder` of
    its parent and name (OutputError, exit 2, when something that must be kept is there)."""
    full = Path(os.path.abspath(out))
    if not RUN_NAME.match(full.name):
        raise OutputError(f"--out {out}: the output folder's name must be letters, digits and _ . - only "
                          f"(at most 100 characters, starting with a letter or digit)")
    return open_run_folder(full.parent, full.name, force=force)
