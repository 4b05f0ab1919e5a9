"""``solve``: the multistart solve of a spec, its run folder OUT/<name>/ (starts.jsonl as the starts finish), the
interrupted run's best-so-far kept, a ``--resume`` finishing it (docs/ARCHITECTURE.md, "Interrupts")."""

from __future__ import annotations

import signal
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from synthesis import kinds
from synthesis.core import interrupt, startlog
from synthesis.core import solve as core
from synthesis.core.compiled_code import CACHE_FOLDER, cache_folder, compile_seconds
from synthesis.core.executor import default_workers
from synthesis.core.ipopt import solved_with_method
from synthesis.core.library_log import captured_warnings
from synthesis.errors import AgrisynthError, AssemblyError, OutputError, SpecError
from synthesis.result import RUN_NAME, is_run_folder
from synthesis.runs.events import Note, SolverLog, SolveStarted, StartsDone, Subscriber, start_finished
from synthesis.runs.output import RunOutput, text_file
from synthesis.runs.requests import BadRequest, Outcome, SolveRequest, SolveWritten, Stopped
from synthesis.runs.specs import described, loaded_spec, refuse_robust_box_outside, zero_tolerance_box
from synthesis.spec.solved import ELASTIC_FILENAME as ELASTIC_SPEC, FILENAME as SOLVED_SPEC, elastic_said, elastic_toml, solved_toml

#: most worker processes a run starts
MAX_WORKERS = 256


@dataclass
class _Plan:
    """What the run does, settled before any solving: the starts, the seed, the folder, what it resumes."""

    starts: int                       # how many the run has
    asked: int | None                 # as asked (None: the spec's)
    seed: int | None                  # as asked (None: the spec's)
    settings: dict
    fingerprint: str
    out: Path
    folder_name: str
    finished: dict | None = None      # the resumed run's finished starts
    replaceable: Path | None = None
    auto: core.AutoStarts | None = None     # --starts auto (``starts`` is then its most starts)
    resumed_batch: int | None = None        # --starts auto resumed: the batch the interrupted run was solving
    resumed_nested: bool | None = None      # ... and whether it was in the kind's own order
    previous: list[tuple[int, dict]] | None = None  # ... and the batches it finished before that one (not nested)
    batch: int | None = None                # --starts auto: the batch being solved (an interrupted run's total)


def staging_hint(folder: Path) -> str:
    """A run killed outright (SIGKILL, power loss) leaves its starts in the staging folder beside the one it was to
    become (OUT/.<name>.run-XXXX/, starts.jsonl): name it, newest first, so --resume can be given it."""
    folder = Path(folder)
    staged = []
    for p in folder.parent.glob(f".{folder.name}.run-*"):
        try:                    # a solve's (a check's holds no starts); one may vanish as it is read
            if is_run_folder(p) and (p / "starts.jsonl").is_file():
                staged.append((p.stat().st_mtime, p))
        except OSError:
            continue
    if not staged:
        return ""
    staged.sort(reverse=True)
    return (f"; a solve that did not finish (killed, or still running) left its starts in {staged[0][1]}: give that "
            f"folder to --resume" + (f" ({len(staged) - 1} older one(s) beside it)" if len(staged) > 1 else ""))


def _probe(scheduler: str | None) -> None:
    """A peer that is no dask scheduler: exit 2 now, within the connect timeout."""
    if scheduler is None:
        return
    try:
        from synthesis.core.cluster import probe_scheduler      # the cluster extra: only when a scheduler is given
    except ImportError:
        raise AgrisynthError("--scheduler needs dask.distributed: pip install 'agrisynth[cluster]'") from None
    probe_scheduler(scheduler)


def _auto_of(request: SolveRequest, loaded, earlier: dict) -> core.AutoStarts | None:
    """--starts auto's settings: asked for, the interrupted run's (resumed without --starts), or the spec's [solver]
    starts = "auto"; None for fixed starts (then --max-starts and --time-limit are bad input)."""
    was = earlier.get("starts_auto") if isinstance(earlier.get("starts_auto"), dict) else None
    asked = (request.starts == "auto" or (request.starts is None and was is not None)
             or (request.starts is None and not earlier and getattr(loaded.model.solver, "starts_auto", False)))
    if not asked:
        if request.max_starts is not None or request.time_limit is not None:
            raise BadRequest("--max-starts and --time-limit are budgets of --starts auto; give --starts auto (or "
                             "[solver] starts = \"auto\") or leave them out", "--max-starts")
        return None
    base = core.AutoStarts(**{k: v for k, v in (was or {}).items() if k in core.AutoStarts.__dataclass_fields__})
    budgets: dict[str, Any] = {k: v for k, v in (("max_starts", request.max_starts),
                                                 ("time_limit_s", request.time_limit)) if v is not None}
    return replace(base, **budgets)


def _plan(request: SolveRequest, loaded, kind) -> _Plan:
    starts, seed, resume = request.starts, request.seed, request.resume
    earlier: dict = {}
    if resume is not None:
        if not is_run_folder(resume):
            raise OutputError(f"--resume {resume}: not an agrisynth run folder{staging_hint(resume)}")
        earlier = startlog.settings_of(resume)      # --starts and --seed default to the interrupted run's
        starts = earlier.get("starts") if starts is None and isinstance(earlier.get("starts"), int) else starts
        seed = earlier.get("seed") if seed is None and isinstance(earlier.get("seed"), int) else seed
    auto = _auto_of(request, loaded, earlier)
    fixed = None if auto is not None or isinstance(starts, str) else starts    # "auto" is ``auto`` by now
    n = auto.max_starts if auto is not None else fixed or loaded.model.solver.starts
    the_seed = loaded.model.solver.seed if seed is None else seed
    settings, fingerprint = startlog.fingerprint(loaded.kind, loaded.name, loaded.sha256, n, the_seed,
                                                 None if auto is None else auto.settings())
    out = Path("results") if request.out is None else request.out
    plan = _Plan(n, fixed, seed, settings, fingerprint, out, loaded.name, auto=auto)
    if resume is not None:
        log = startlog.read_resumed(resume, fingerprint)
        plan.finished = log.finished
        mark = log.last_batch if auto is not None else None
        plan.resumed_batch, plan.resumed_nested = mark if mark is not None else (None, None)
        plan.previous = log.previous if auto is not None else None
        if mark is not None:      # refused before any folder is made
            core.refuse_other_order(kind, mark[1], core.takes_auto_order(kind, loaded.model, the_seed))
        where = resume.resolve()
        plan.out = where.parent
        # the result replaces RUN_DIR itself, whatever its name (a renamed run too); a staging folder left by a
        # SIGKILL (.<name>.run-XXXX, README) is no folder name: its result goes to OUT/<spec name>, as before
        if RUN_NAME.match(where.name):
            plan.folder_name, plan.replaceable = where.name, resume
    return plan


def solve(request: SolveRequest, emit: Subscriber) -> Outcome:
    """Solve, write result.json, report.html, ipopt.log, solved.toml, starts.jsonl and the figures.  Exit code 0
    every rule holds, 1 a rule violated, 3 infeasible or failed (``error``), 128 + the signal when a signal stopped
    it (``stopped``: its finished starts kept).  The written result is handed over as ``ResultWritten`` (details:
    :class:`SolveWritten`); progress as ``SolveStarted``, ``StartFinished`` per start and ``StartsDone``."""
    interrupt.install(keep_ignored=True)     # a signal the process was started ignoring stays ignored
    if request.compiled and request.scheduler is not None:
        raise AgrisynthError("--compiled: the compiled functions are made on this machine and a cluster's workers "
                             "build their own: give --compiled for local workers only")
    loaded = loaded_spec(request.spec, emit)
    zeros = zero_tolerance_box(loaded)
    if zeros is not None:       # [tolerance] asks for a tolerance-robust solve: of an empty box, the nominal one
        raise SpecError(f"{loaded.path}: [tolerance] gives no half-width above 0 ({zeros}): a tolerance-robust solve "
                        f"needs one (length, angle or variables); leave the table out to solve the nominal design")
    kind = kinds.solving_kind_for(loaded)       # [tolerance]: every rule at its linearised worst case
    refuse_robust_box_outside(loaded)           # (after the kind has said whether it takes a [tolerance] at all)
    _probe(request.scheduler)
    workers = min(request.workers or default_workers(), MAX_WORKERS)
    plan = _plan(request, loaded, kind)
    folder = cache_folder(plan.out) if request.compiled else None     # no compiler: said before any folder is made
    if folder is not None:
        emit(Note(f"compiled derivatives: IPOPT's functions compiled to C in {plan.out / CACHE_FOLDER}/ (the first "
                  f"solve of an NLP compiles it: seconds to minutes, about two and a half for a planting arm; a later "
                  f"solve of the same NLP loads it)"))
        kind = solved_with_method(kind, compiled=str(folder))
    with RunOutput(plan.out, plan.folder_name, force=request.force, spec=loaded.path, replaceable=plan.replaceable,
                   resumed_from=request.resume) as output:     # a killed run's staging folder: removed once complete
        log_file = startlog.StartLog(output.staging / startlog.FILENAME, plan.settings, plan.fingerprint)
        compiled_before = compile_seconds()
        solved, said = _multistart(kind, loaded, request, plan, workers, log_file, emit)
        compiled = ({"folder": str(folder), "compile_s": round(compile_seconds() - compiled_before, 3)}
                    if folder is not None else None)
        if isinstance(solved, core.Interrupted):
            if solved.partial is not None:
                solved.partial[0].solver["compiled"] = compiled
            return _keep_interrupted(solved, output, kind, loaded, plan, request.resume, log_file.since_batch)
        # every start is done: a signal from here on is noted and the finished result written all the same
        with output.finishing(emit):
            emit(StartsDone())
            result, reports, log = solved
            result.solver["compiled"] = compiled
            if said():
                log += f"\n# library warnings outside the IPOPT runs\n{said()}"
            described(result, loaded)
            log_file.close()
            if request.verbose:
                emit(SolverLog(log))
            baseline = core.baseline_rules(kind, loaded)
            files = {"ipopt.log": text_file(log), SOLVED_SPEC: text_file(solved_toml(loaded, result))}
            elastic = elastic_toml(loaded, result) if result.status in ("infeasible", "failed") else None
            if elastic is not None:
                files[ELASTIC_SPEC] = text_file(elastic)
            details = SolveWritten(baseline, workers, request.scheduler, len(plan.finished or ()), request.resume,
                                   kind.headline(result))
            folder, _ = output.finish(emit, result, files, given_rules=baseline, details=details)
            error = core.exit_error(kind, result, reports) if result.status in ("infeasible", "failed") else None
            if error is not None and elastic is not None:
                # the message's figures are the relaxation's; the table beside it shows the least violated start
                its = "; the misses named above are its" if result.status == "infeasible" else ""
                error = type(error)(f"{error} The elastic re-solve's design ({elastic_said(result.elastic or {})}{its}; "
                                    f"not the least violated start the table shows) is written as {ELASTIC_SPEC}, the "
                                    f"spec started there: `agrisynth check` it, or `agrisynth solve` from it.")
    return Outcome(3 if error else 1 if result.violated() else 0, result, folder, error=error)


def _multistart(kind, loaded, request: SolveRequest, plan: _Plan, workers: int, log_file, emit: Subscriber):
    """Every start solved: ((result, reports, log), the library warnings said meanwhile), or (the Interrupted
    exception, ...) when a signal stopped the run."""
    batches = plan.auto.batches() if plan.auto is not None else [plan.starts]
    first = batches.index(plan.resumed_batch) if plan.resumed_batch in batches else 0
    done, total = 0, batches[first]
    emit(SolveStarted(loaded.name, total))

    def on_start(report, best) -> None:
        nonlocal done
        done += 1
        emit(start_finished(report, best, done, total, report.outcome.start in (plan.finished or {})))

    def on_batch(starts: int, nested: bool = False) -> None:
        """--starts auto: a batch begins (marked in starts.jsonl); the progress counts every start solved (a nested
        batch tells only its new starts: the earlier ones count as they were)."""
        nonlocal total
        plan.batch = starts
        log_file.batch(starts, nested)
        # a later batch than the one the run began with (a resumed run first logs again the batch before it)
        if starts in batches and batches.index(starts) > first:
            total = starts if nested else total + starts
            emit(SolveStarted(loaded.name, total))

    solved = None         # (result, reports, log) once every start has finished
    stderr = sys.stderr   # the warnings capture swaps it; an exit cut short by a signal may not swap it back
    said = lambda: ""     # noqa: E731 - nothing said until the capture has begun
    try:
        with captured_warnings() as said:   # scipy/CasADi warnings: into ipopt.log, not the terminal
            solved = core.run_solve(kind, loaded, plan.asked, plan.seed, workers, on_start, request.scheduler,
                                    record=log_file.append, finished=plan.finished, auto=plan.auto,
                                    on_batch=on_batch, resumed_batch=plan.resumed_batch,
                                    resumed_nested=plan.resumed_nested, previous=plan.previous,
                                    on_note=lambda text: emit(Note(text)))
    except (SpecError, AssemblyError) as exc:
        # a spec the run's set-up cannot use (e.g. a key point the arm cannot reach) is said as check says it:
        # the file first
        if str(loaded.path) in str(exc):
            raise
        raise type(exc)(f"{loaded.path}: {exc}") from None
    except core.Interrupted as exc:
        log_file.close()
        return exc, said
    except (KeyboardInterrupt, SystemError) as exc:
        # the signal came as the run returned (closing the warnings capture): the result is complete, so it is
        # kept like any later signal (noted, the exit code the result's)
        if solved is None or not interrupt.caused_by_signal(exc):
            raise
        with interrupt.deferred(reraise=False):
            sys.stderr = stderr
    return solved, said


def _keep_interrupted(exc: core.Interrupted, output: RunOutput, kind, loaded, plan: _Plan,
                      resumed: Path | None, in_batch: int = 0) -> Outcome:
    """The one place an interrupted run is kept: its best-so-far result (status interrupted), its report and
    starts.jsonl written, no figures (the run ends within seconds of the signal; --resume draws them), the rule
    table of the given design beside it as in a finished solve's report; nothing is written (and nothing
    replaced) when no start had finished, or a resumed run was stopped before it had counted its finished starts
    again (the run it resumed then stays as it was, to be resumed again)."""
    name, n = signal.Signals(exc.signum).name, plan.batch or plan.starts
    if exc.partial is None:
        output.folder.discard()
        if resumed is not None and plan.finished:
            return Outcome(exc.exit_code, stopped=Stopped(name, len(plan.finished), n, resumed, loaded.path))
        return Outcome(exc.exit_code, stopped=Stopped(name, 0, n, None, loaded.path))
    result, reports, log = exc.partial
    described(result, loaded)
    with interrupt.deferred(reraise=False):
        folder, _ = output.write(result, {"ipopt.log": text_file(log)}, given_rules=core.baseline_rules(kind, loaded),
                                 figures=False)
    # of the run kept: an auto run interrupted early in a batch may keep the whole batch before it
    of = (result.solver or {}).get("starts", n)
    begun = (n, in_batch) if plan.auto is not None and plan.batch is not None and of != plan.batch else None
    return Outcome(exc.exit_code, result, folder,
                   stopped=Stopped(name, len(reports), of, folder, loaded.path, begun))
