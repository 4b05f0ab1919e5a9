"""``agrisynth check`` and ``agrisynth solve``: options to a request, the run's events to the terminal."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from synthesis import runs
from synthesis.cli import ends_process
from synthesis.cli.options import (FORCE_HELP, NamedPath, MAX_STARTS, MAX_WORKERS, Seconds, StartsCount, WholeNumber,
                                   objectives_help, scheduler_address)
from synthesis.cli.views import Terminal, stopped_message
from synthesis.runs.requests import CheckRequest, Outcome, SolveRequest


def finish(outcome: Outcome) -> None:
    """The command's end: a signal's stop said, a failed solve's error raised (exit 3), else the outcome's code."""
    if outcome.stopped is not None:
        stopped_message(outcome.stopped)
    if outcome.error is not None:
        raise outcome.error
    if outcome.exit_code:
        sys.exit(outcome.exit_code)


@click.command("check")
@click.argument("spec", type=click.Path(path_type=Path))
@click.option("--out", "out", type=NamedPath(file_okay=False, path_type=Path), default=Path("results"),
              show_default=True, help="output folder; the run writes OUT/<spec name>-check/")
@click.option("--force", is_flag=True, help=FORCE_HELP.replace("OUT/<name>/", "OUT/<name>-check/"))
def check_command(spec: Path, out: Path, force: bool) -> None:
    """Evaluate SPEC's given design against its rules (no optimisation).

    Prints the rule table (value, limit, margin, pass/fail) and writes OUT/<name>-check/result.json,
    report.html and the kind's figures (a trajectory or path plot where the kind has one). Exit 0
    when every rule holds, 1 when one is violated.  SPEC may be a library spec as `agrisynth problems`
    lists it (planting_arm/taiwan_example1.toml) where the working folder has no such file.
    OUT/<name>-check/ (a solve of the same spec writes OUT/<name>/) must not exist yet, or hold an
    earlier agrisynth run and --force be given.
    """
    with Terminal(ends_process()) as terminal:
        outcome = runs.check(CheckRequest(spec, out, force), terminal)
    finish(outcome)


class SolveCommand(click.Command):
    """`solve --help` lists every kind's objectives from the registry, read only when help is asked for
    (so an ordinary run imports no other kind's package)."""

    def format_help(self, ctx, formatter):
        self.help = self.help.replace("{objectives}", objectives_help())
        super().format_help(ctx, formatter)


@click.command("solve", cls=SolveCommand)
@click.argument("spec", type=click.Path(path_type=Path))
@click.option("--out", type=NamedPath(file_okay=False, path_type=Path), default=None,
              help="output folder; the run writes OUT/<spec name>/  [default: results]")
@click.option("--force", is_flag=True, help=FORCE_HELP)
@click.option("--resume", "resume", type=click.Path(file_okay=False, path_type=Path), default=None, metavar="RUN_DIR",
              help="finish an interrupted run: the starts in RUN_DIR/starts.jsonl are not solved again and the "
                   "result is exactly the uninterrupted one; SPEC must be the same file and --starts/--seed (default: "
                   "that run's) the same settings (checked by sha256); the result replaces RUN_DIR")
@click.option("--starts", type=StartsCount(min=1, max=MAX_STARTS), default=None,
              help=f"multistart starts, at most {MAX_STARTS}, or auto (default: the spec's [solver] starts); "
                   f"start 0 is the spec's design.  auto: batches of 16, 32, 64, ... starts, each the run --starts N "
                   f"would be, until fewer than half a local optimum is expected unseen (Boender & Rinnooy Kan) over "
                   f"at least 16 starts that converged with every rule held, or a budget is spent; the same seed "
                   f"gives the same answer and N for any workers; each batch solves its own starts (start 0 "
                   f"carried), about twice the last batch's in all -- except where the kind orders the starts itself "
                   f"(fourbar_path on 12 or more free-timing targets: its screened shapes first), whose batches "
                   f"append, each start solved once.  Where an earlier batch found a better design than the last, "
                   f"that batch is the answer (solver.auto.answer_batch).  Ctrl-C keeps the better of the batch in "
                   f"progress and the best finished one; --resume goes on from the batch it was in")
@click.option("--max-starts", type=WholeNumber(min=1, max=MAX_STARTS), default=None,
              help="--starts auto: the most starts (default 512)")
@click.option("--time-limit", type=Seconds(min=0, min_open=True), default=None, metavar="SECONDS",
              help="--starts auto: begin no batch that would end past this many seconds (default: none); the "
                   "first batch always runs (its time is what the next one's is projected from), so a run may end "
                   "past a limit shorter than it.  A "
                   "time-limited run is not deterministic in its count: how many starts it reaches depends on the "
                   "machine (result.json solver.auto.stopped_by says time_limit when it stopped it); a resumed run counts "
                   "its time afresh")
@click.option("--seed", type=WholeNumber(min=0, max=2**53), default=None,
              help="seed of the Latin-hypercube starts (default: the spec's [solver] seed)")
@click.option("--workers", type=WholeNumber(min=1, max=MAX_WORKERS), default=None,
              help=f"parallel worker processes, at most {MAX_WORKERS} (default: all cores)")
@click.option("--scheduler", default=None, metavar="ADDR", callback=scheduler_address,
              help="run the starts on a dask.distributed cluster at tcp://host:port (the workers need agrisynth "
                   "installed) instead of local worker processes.  A scheduler runs the code it is sent: "
                   "trust it as you trust this machine")
@click.option("--compiled", is_flag=True,
              help="evaluate the NLP and its exact derivatives as C compiled by this machine's compiler ($CC, else "
                   "cc) instead of CasADi's interpreter: the same answer to the bit, faster (measured: a planting "
                   "arm's multistart 2.4x, a path synthesis' 1.05-1.5x).  The first solve of an NLP compiles it "
                   "into OUT/.compiled/ (seconds to minutes: steering's 12 s, a crank-rocker's 45 s, a planting "
                   "arm's about two and a half minutes; in solver.wall_s); a later solve of the same NLP loads it "
                   "-- a change of bounds or rule limits keeps it, one of the spec's constants or sample counts "
                   "makes another.  Local workers only")
@click.option("--verbose", is_flag=True, help="print IPOPT's output (always kept in OUT/<name>/ipopt.log)")
def solve_command(spec: Path, out: Path | None, force: bool, resume: Path | None, starts: int | str | None,
                  max_starts: int | None, time_limit: float | None, seed: int | None, workers: int | None,
                  scheduler: str | None, compiled: bool, verbose: bool) -> None:
    """Optimise SPEC's free design variables so every rule holds (CasADi + IPOPT, exact derivatives).

    \b
    Every rule is a constraint; the objective is the spec's [objective] name, by kind
    (the first is the default):
    {objectives}
    Starts are a fixed-seed Latin hypercube (start 0 = the given design). Every start is
    re-checked on a 10x finer grid, independently of the solver; the best is the feasible one
    with the best objective (objectives within 1e-9 of max(1, |f|) tie: a start IPOPT finished at its
    full tolerances wins, then the lower start). Status: optimal (every rule holds and
    IPOPT met its tolerances), feasible (every rule holds; IPOPT stopped otherwise: a note
    says how), infeasible (an elastic re-solve converged and names the rules that conflict),
    failed (anything else: the message says what to try), interrupted (Ctrl-C or SIGTERM:
    the best of the finished starts). Writes OUT/<name>/result.json, report.html, ipopt.log,
    starts.jsonl (every finished start, appended as it finishes) and plots. OUT/<name>/ (a check
    of the same spec writes OUT/<name>-check/) must not exist yet, or hold an earlier agrisynth
    run and --force be given (checked before solving).  SPEC may be a library spec as `agrisynth
    problems` lists it where the working folder has no such file. Exit 0 all rules hold; 1 a rule violated; 3 infeasible or failed; 2 bad input
    (also: nothing free to optimise, or a check-only kind); 130 interrupted by Ctrl-C
    (SIGINT), 143 by SIGTERM: the finished starts are kept, --resume RUN_DIR finishes the run.
    """
    if scheduler is not None and workers is not None:
        raise click.BadParameter("give either --workers (local processes) or --scheduler (a dask cluster), "
                                 "not both", param_hint="--workers/--scheduler")
    if resume is not None and out is not None:
        raise click.BadParameter("a resumed run is written where RUN_DIR is; leave out --out", param_hint="--out")
    request = SolveRequest(spec, out, force, resume, starts, seed, workers, scheduler, verbose, max_starts, time_limit,
                           compiled)
    with Terminal(ends_process()) as terminal:
        outcome = runs.solve(request, terminal)
    finish(outcome)
