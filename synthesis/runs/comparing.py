"""``compare``: result folders (and bench outputs) side by side in one page, OUT/compare.html."""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

from synthesis.errors import OutputError, ResultError
from synthesis.report.compare import (bench_of_kind, different_versions, is_bench, load_bench, load_candidates, open_output_folder,
                                      write_comparison_files)
from synthesis.core.library_log import captured_warnings
from synthesis.result import atomic_write_text, is_run_folder
from synthesis.runs.events import Note, Subscriber
from synthesis.runs.output import RunOutput
from synthesis.runs.requests import CompareRequest, Comparison, Outcome


def refuse_overlap(results: tuple[Path, ...], out: Path, said: str = "--out") -> None:
    """--force would replace a result being compared: OUT may neither hold nor be inside a RESULT."""
    target = Path(os.path.realpath(out))              # realpath, not resolve(): a symlink loop is the loader's to name
    for given in results:
        read = Path(os.path.realpath(given))
        if read.name == "result.json" and is_run_folder(read.parent):
            read = read.parent                        # a run given as its result.json: the run folder is the result
        if read == target or target in read.parents or read in target.parents:
            raise OutputError(f"{said} {out} holds or is inside RESULT {given}: the page would replace what it "
                              f"compares; write it to another folder")


#: where compare writes without --out: a folder per comparison, so comparing other runs needs no --force
COMPARE_ROOT = Path("results/compare")
#: the longest folder name a run folder takes (synthesis.result.RUN_NAME)
MAX_FOLDER_NAME = 100


def default_out(results: tuple[Path, ...]) -> Path:
    """results/compare/<A>_vs_<B>...: each RESULT by its run folder's name (a result.json by its folder's).  Where the
    names alone could name another comparison -- a name repeated (old/arm, new/arm), one holding "_vs_", more than
    fit in a folder name (then the first and how many more) -- a short hash of the RESULTs' full paths is added."""
    names, full, cleaned = [], [], False
    for given in results:
        path = Path(os.path.abspath(given))
        folder = path.parent if path.name in ("result.json", "bench.json") else path
        name = re.sub(r"[^A-Za-z0-9_.-]", "_", folder.name).lstrip("._-") or "run"
        cleaned = cleaned or name != folder.name
        names.append(name)
        full.append(os.fsencode(os.path.realpath(folder)))      # a run as its folder or its result.json: one run
    joined = "_vs_".join(names)
    # names alone name another comparison too: one repeated, one whose "_vs_" splits otherwise, one changed to fit
    ambiguous = len(set(names)) < len(names) or joined.split("_vs_") != names or cleaned
    digest = "_" + hashlib.sha256(b"\0".join(full)).hexdigest()[:8]
    if len(joined) > MAX_FOLDER_NAME - len(digest):
        tail = f"_and_{len(names) - 1}_more"
        joined = names[0][:MAX_FOLDER_NAME - len(tail) - len(digest)] + tail
        ambiguous = True
    return COMPARE_ROOT / (joined + (digest if ambiguous else ""))


def compare(request: CompareRequest, emit: Subscriber) -> Outcome:
    """Write OUT/compare.html and its figures; ``details``: :class:`Comparison` (the candidates, the first the
    baseline; the page).  Nothing is re-solved: the page is built from the result files alone (no events)."""
    out = default_out(request.results) if request.out is None else request.out
    if request.out is None and is_run_folder(COMPARE_ROOT):
        # an earlier version wrote every comparison into results/compare/ itself
        raise OutputError(f"{COMPARE_ROOT} is itself a comparison's folder (an earlier version's default, or an "
                          f"--out given so), where comparisons are now written into folders inside it: move it away, "
                          f"or give --out")
    refuse_overlap(request.results, out, "--out" if request.out is not None else "the default output folder")
    # refused (exit 2) before anything is read; the staging folder is discarded if the comparison stops
    with RunOutput.around(open_output_folder(out, request.force)) as output:
        results = [p for p in request.results if not is_bench(p)]
        if not results:       # only bench folders: a bench is shown beside a run of its kind, never alone
            benches = ", ".join(str(p) for p in request.results)
            raise ResultError(f"compare needs at least one RESULT (a run folder or its result.json): {benches} "
                              f"{'is a bench' if len(request.results) == 1 else 'are benches'}, which compare shows "
                              f"beside a run of their kind")
        cands = load_candidates(results)
        for text in different_versions(cands):
            emit(Note(text))
        bench = [res for p in request.results if is_bench(p)
                 for res in bench_of_kind(p, load_bench(p), cands[0].result.kind)]
        output.fill(lambda staging: _write_page(cands, staging, bench))
    page = Path(out) / "compare.html"
    return Outcome(0, folder=page.parent, details=Comparison(cands, page))


def _write_page(cands, staging: Path, bench) -> None:
    """The page and its figures; a library's warnings while drawing them (matplotlib's "tight layout not applied" of
    a legend of 60 candidates) go to warnings.log beside the page, not the terminal, as check's and solve's do."""
    with captured_warnings() as said:
        write_comparison_files(cands, staging, bench)
    if said():
        atomic_write_text(staging / "warnings.log", said())
