"""``bench``: error against run time of every method on each problem, the sample-count sweep, the extreme-case
matrix; written to OUT/bench/ (bench.json, bench.md, plots)."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

from synthesis import bench as benchmod
from synthesis.bench.extreme import EXTREME, extreme_matrix
from synthesis.core.compiled_code import cache_folder
from synthesis.runs.events import BenchStarted, BenchStep, Note, RunWarning, Subscriber
from synthesis.runs.output import RunOutput
from synthesis.runs.requests import BadRequest, BenchRequest, BenchRows, Outcome
from synthesis.errors import AssemblyError, SpecError
from synthesis.library import library_spec
from synthesis.runs.specs import spec_file
from synthesis.spec import KINDS, load_spec


def problems_by_kind(request: BenchRequest, emit: Subscriber = lambda event: None) -> dict[str, list | None]:
    """{kind: its spec files to bench, or None for its default set} of the request's problems (none: every kind
    with a bench); a spec is a file, or the library's spec of that name where no such file is here (as check and
    solve take it, told as ``SpecFromLibrary``); a kind without bench cases or a name that is neither is a
    :class:`BadRequest` of PROBLEM."""
    known = benchmod.kinds_with_bench()
    by_kind: dict[str, list | None] = {}
    items = [*request.problems, *(str(f) for f in request.spec_files)]
    for item in items or tuple(known):
        if item in known:
            by_kind.setdefault(item, None)
        elif item in KINDS:
            raise BadRequest(f"kind {item!r} has no bench cases (kinds with a bench: {', '.join(known)})", "PROBLEM")
        elif item.endswith(".toml") or Path(item).exists() or library_spec(item) is not None:
            loaded = load_spec(spec_file(Path(item), emit))
            if loaded.kind not in known:
                raise BadRequest(f"{item}: kind {loaded.kind!r} has no bench cases "
                                 f"(kinds with a bench: {', '.join(known)})", "PROBLEM")
            # a spec file replaces its kind's default set, also when the kind is named too (before or after it)
            by_kind[loaded.kind] = (by_kind.get(loaded.kind) or []) + [loaded]
        else:
            raise BadRequest(f"{item!r} is neither a kind with a bench ({', '.join(known)}) nor a spec file",
                             "PROBLEM")
    return by_kind


def _refuse_one_name_twice(cases: list) -> None:
    """Two cases of one problem name (a named spec beside a kind's default set holding its name): bench.json's rows,
    bench.md's sections and samples_<problem>.png are named by it, so one would hide the other."""
    seen: dict[str, str] = {}
    for case in cases:
        where = str(case.loaded.path) if case.loaded is not None else f"kind {case.kind}'s bench set"
        if case.problem in seen:
            raise BadRequest(f"two problems named {case.problem!r} ({seen[case.problem]} and {where}); bench names its "
                             f"rows and figures by the problem's name: give each its own name", "PROBLEM")
        seen[case.problem] = where


def _cases(request: BenchRequest, by_kind: dict, emit: Subscriber, compiled: str | None = None) -> list:
    named = bool(request.problems or request.spec_files)
    cases = []
    for kind, specs in by_kind.items():
        try:
            cases += benchmod.cases_for(kind, specs, 0, None if named else benchmod.OWN_CASES_IN_EVERY_KIND_RUN,
                                        quick=request.quick, compiled=compiled)
        except Exception as exc:      # noqa: BLE001 - one kind's broken bench set must not stop the others
            if named:
                raise
            emit(RunWarning(f"bench: kind {kind} left out: its bench cases could not be made "
                            f"({type(exc).__name__}: {exc})"))
    _refuse_one_name_twice(cases)
    return cases


def _run_case(case, repeats: int, emit: Subscriber):
    """One case benched; a named spec the solve refuses (nothing free, a rule no variable moves) is said with its file
    first, as solve says it."""
    try:
        return benchmod.run_case(case, repeats, lambda what: emit(BenchStep(what)))
    except (SpecError, AssemblyError) as exc:
        if case.loaded is None or str(case.loaded.path) in str(exc):
            raise
        raise type(exc)(f"{case.loaded.path}: {exc}") from None


def bench(request: BenchRequest, emit: Subscriber) -> Outcome:
    """Bench, write OUT/bench/; ``details``: :class:`BenchRows`.  Progress as
    ``BenchStarted`` then ``BenchStep`` (what is measured now, or a step done)."""
    repeats = request.repeats if request.repeats is not None else (1 if request.quick else 3)
    by_kind = problems_by_kind(request, emit)
    compiled = str(cache_folder(request.out)) if request.compiled else None     # no compiler: said now
    # refused (exit 2) before any benching; the staging folder is discarded if the bench stops
    with RunOutput(request.out, "bench", force=request.force) as output:
        cases = _cases(request, by_kind, emit, compiled)
        why_not = ("--no-extreme" if request.no_extreme else "problems were named (it runs with none)"
                   if request.problems or request.spec_files else "--quick" if request.quick
                   else None if EXTREME is not None and EXTREME.is_dir()
                   else "no tests/extreme/ here: the matrix is the source tree's tests, run from a clone")
        extreme_on = why_not is None
        if why_not is not None and not request.no_extreme:     # the user asked for nothing: say why it is missing
            emit(Note(f"the extreme-case matrix is left out: {why_not}"))
        emit(BenchStarted(sum(c.runs(repeats) for c in cases) + (1 if extreme_on else 0)))
        t0 = time.perf_counter()
        results = [_run_case(case, repeats, emit) for case in cases]
        extreme = None
        if extreme_on:
            emit(BenchStep("extreme-case matrix (tests/extreme/)"))
            extreme = extreme_matrix()
            emit(BenchStep(None))
        study = dataclasses.asdict(benchmod.study_settings(request.quick, compiled))
        settings = {"repeats": repeats, "quick": request.quick, "study": study, "problems": [c.problem for c in cases],
                    "wall_s": round(time.perf_counter() - t0, 1), "extreme_not_run": why_not}
        folder, _ = output.fill(lambda staging: benchmod.write_bench_files(staging, results, settings, extreme))
    return Outcome(0, folder=folder, details=BenchRows(results, repeats, settings))
