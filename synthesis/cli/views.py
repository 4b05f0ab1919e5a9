"""What the command line prints: the rule tables, the summaries of a written result, and the run's events drawn
as they come (a progress bar on a terminal, a line per finished start when piped).

The runs (:mod:`synthesis.runs`) hand their events to :class:`Terminal`; a result's summary is drawn when its
``ResultWritten`` arrives, inside the run's deferral, so a Ctrl-C while it prints is noted, not obeyed.
"""

from __future__ import annotations

import contextlib
import math
import shlex
import sys

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from synthesis.constraints.base import limit_text
from synthesis.cli.terminal import PIPED_WIDTH, add_columns, design_table, print_table
from synthesis.core import interrupt
from synthesis.report.tables import GIVEN_HEADING, auto_said, candidates, design_rows, objective_text, said, solved_heading
from synthesis.runs import events
from synthesis.runs.requests import CheckWritten, SolveWritten, Stopped
from synthesis.tolerance.output import monte_carlo_lines

#: as wide as the terminal; piped, wide enough that no line of text is wrapped (tables: terminal.table_width)
console = Console(highlight=False, width=None if sys.stdout.isatty() else PIPED_WIDTH)
err_console = Console(stderr=True, highlight=False)


def _verdict(r: dict) -> str:
    return "[green]pass[/]" if r["satisfied"] else "[bold red]FAIL[/]"


def rule_table(rules: list[dict], title: str) -> Table:
    table = Table(title=escape(title), title_justify="left")
    add_columns(table, (("rule", "left"), ("value", "right"), ("limit", "right"), ("unit", "left"),
                        ("margin", "right"), ("", "left"), ("where / why", "left")))
    for r in rules:
        value = "-" if r["value"] is None else f"{r['value']:.4g}"
        margin = "-" if r["margin"] is None else f"{r['margin']:.4g}"
        table.add_row(escape(r["name"]), value, limit_text(r["limit"]), escape(r["unit"]), margin, _verdict(r),
                      escape(r.get("note") or r.get("where", "")))
    return table


def comparison_table(best: list[dict], baseline: list[dict] | None, title: str, solved: str = "solved") -> Table:
    """A solve's rule table: each rule at the given design (start 0) and at the solved one (heading ``solved``)."""
    table = Table(title=escape(title), title_justify="left")
    add_columns(table, (("rule", "left"), ("limit", "right"), (GIVEN_HEADING, "right"), ("", "left"),
                        (solved, "right"), ("", "left"), ("unit", "left")))
    base = {r["name"]: r for r in baseline or []}

    def cell(r):
        if r is None:
            return "", ""
        return ("-" if r["value"] is None else f"{r['value']:.4g}"), _verdict(r)

    for r in best:
        table.add_row(escape(r["name"]), limit_text(r["limit"]), *cell(base.get(r["name"])), *cell(r),
                      escape(r["unit"]))
    return table


def _figure(value, spec: str) -> str:
    """A bench figure as bench.md writes it: "–" where none was measured (no run met every rule: no best known,
    so no gap) -- never "-inf" or "nan"."""
    return format(value, spec) if isinstance(value, (int, float)) and math.isfinite(value) else "–"


def bench_table(results: list[dict], repeats: int) -> Table:
    table = Table(title=f"bench: objective reached, median wall time and time to target (IPOPT methods: {repeats} "
                        f"runs)", title_justify="left")
    add_columns(table, (("problem", "left"), ("method", "left"), ("objective", "right"), ("gap to best", "right"),
                        ("worst violation", "right"), ("median s", "right"), ("time to target s", "right"),
                        ("iterations", "right"), ("time-to-target ratio", "right")))
    for res in results:
        for row in res["rows"]:
            details = row.get("details") if isinstance(row.get("details"), dict) else {}
            iters = details.get("median_iterations")
            table.add_row(escape(row["problem"]), escape(row["method"]), _figure(row["objective"], ".4g"),
                          _figure(row["objective_gap"], ".3g"), _figure(row["worst_violation"], ".3g"),
                          f"{row['median_s']:.3f}",
                          escape(row.get("time_to_target_text") or "–"),
                          "" if iters is None else f"{iters:g}", escape(row["time_ratio_text"]))
    return table


def published_figures_line(facts: dict | None) -> str | None:
    """"published figures: 3 of 6 reproduced; not: <label> (published 117, ours 104.2 deg), ..." for a result whose
    facts compare it with a paper's printed figures (``facts.published``: rows with ``reproduced``); None otherwise."""
    rows = [r for r in ((facts or {}).get("published") or []) if isinstance(r, dict) and "reproduced" in r]
    if not rows:
        return None
    missed = [r for r in rows if not r["reproduced"]]
    text = f"published figures: {len(rows) - len(missed)} of {len(rows)} reproduced (facts.published)"
    if missed:
        def figure(r: dict) -> str:
            ours = r.get("ours")
            ours_text = f"{ours:.4g}" if isinstance(ours, (int, float)) else "-"
            return f"{r.get('label', '?')} (published {r.get('published')}, ours {ours_text} {r.get('unit', '')})"
        text += "; not: " + "; ".join(figure(r) for r in missed)
    return text


def _headline(lines: list[str]) -> None:
    """The kind's headline (Kind.headline): the figures an engineer looks at first, right after the rule table."""
    for line in lines:
        console.print(escape(line), soft_wrap=True)


def _written(folder, replaced: bool) -> None:
    if replaced:
        console.print(f"replaced the previous run in {escape(str(folder))}/")
    console.print(f"wrote {escape(str(folder))}/: {escape(', '.join(sorted(f.name for f in folder.iterdir())))}")


def _violated(bad: list[dict], at: str = "") -> None:
    console.print(f"[bold red]{len(bad)} rule(s) violated{at}:[/] {', '.join(escape(r['name']) for r in bad)}")


def check_summary(result, folder, replaced: bool, details: CheckWritten) -> None:
    """What check prints once its result is written (its exit code is the outcome's: 1 a rule violated)."""
    print_table(console, rule_table(result.rules, f"{result.name} ({result.kind}): {details.spec_path}"))
    _headline(details.headline)
    _written(folder, replaced)
    at = " at the nominal operating point" if details.ranged else ""
    if details.ranged:     # check evaluates a range's nominal value only: say so rather than imply the range holds
        console.print(f"note: {', '.join(details.ranged)} given as a range: check evaluates the nominal value only; "
                      f"`agrisynth solve` re-checks every rule over the range (<rule>@envelope rows)")
    published = published_figures_line(result.extra)
    if published:        # the rules are the design's; the paper's figures are the reading's, said apart
        console.print(escape(published))
    note = result.extra.get("note") if isinstance(result.extra, dict) else None
    if isinstance(note, str) and note:      # the kind's word on the design beyond its rules (targets that are one)
        console.print(f"[yellow]note:[/] {escape(note)}", soft_wrap=True)
    bad = result.violated()
    if bad:
        _violated(bad, at)
    else:
        console.print(f"[green]every rule satisfied{at}[/]")


def _starts_said(s: dict) -> str:
    """"8 starts", "8 starts and one from the elastic re-solve", or "the 4 starts run of 8 (stopped early: [solver]
    stop_at_objective was reached)" -- as result.json's starts_run and stopped_early say."""
    ran = s.get("starts_run", s["starts"])
    if ran > s["starts"]:
        return f"{s['starts']} starts and one from the elastic re-solve"
    if s.get("stopped_early") and ran < s["starts"]:
        return f"the {ran} starts run of {s['starts']} (stopped early: [solver] stop_at_objective was reached)"
    return f"{s['starts']} starts"


def _solver_line(result, details: SolveWritten) -> str:
    s = result.solver
    return (f"objective {objective_text(result.objective)}; IPOPT "
            f"{s['return_status']} in {s['iterations']} iterations; best of {_starts_said(s)} "
            f"(seed {s['seed']}) is start {s['best_start']}; {s['wall_s']:.2f} s on "
            f"{f'the cluster at {escape(details.scheduler)}' if details.scheduler else f'{details.workers} worker(s)'}"
            f"; "
            f"status {result.status}")




def solve_summary(result, folder, replaced: bool, details: SolveWritten) -> None:
    """What a finished solve prints once its result is written (infeasible or failed: the outcome's error, exit 3,
    follows it)."""
    answer = solved_heading(result)
    print_table(console, comparison_table(result.rules, details.baseline, f"{result.name}: rules at the given design "
                                          f"(start 0) and at the {'solved one' if answer == 'solved' else answer}",
                                          answer))
    _headline(details.headline)
    rows = design_rows(candidates([result]))
    if rows:
        print_table(console, design_table(rows, f"design: {GIVEN_HEADING} vs {answer}", answer))
    console.print(_solver_line(result, details))
    if isinstance(result.solver.get("confidence"), dict):
        console.print(escape(f"confidence: {said(result.solver['confidence'], result.solver.get('starts_reaching_best'))}{auto_said(result.solver)}"))
    mc = ((result.extra or {}).get("tolerance") or {}).get("monte_carlo")
    if isinstance(mc, dict):        # a tolerance-robust solve: the Monte-Carlo check of the answer
        console.print(escape("\n".join(monte_carlo_lines(mc))))
    if details.resumed:
        console.print(f"resumed: {details.resumed} finished start(s) read from {escape(str(details.resumed_from))}"
                      f"/starts.jsonl")
    _written(folder, replaced)
    if result.solver["status_note"]:
        console.print(f"[yellow]note:[/] {escape(result.solver['status_note'])}")
    if result.status in ("infeasible", "failed"):
        return
    bad = result.violated()
    if bad:
        _violated(bad)
    else:
        console.print("[green]every rule satisfied on the fine grid[/]")


def stopped_message(stopped: Stopped) -> None:
    """How a signal ended a solve: nothing written, or where its finished starts are kept and how to finish it."""
    if stopped.kept is None:
        err_console.print(f"interrupted by {stopped.signal_name} before any start finished; nothing written")
        return
    begun = ""
    if stopped.begun is not None:       # --starts auto: the batch in progress did no better than the one kept
        total, done = stopped.begun
        begun = (f" (the batch of {total} starts it had begun, {done} of them finished, did no better: its starts "
                 f"are kept too)")
    err_console.print(f"interrupted by {stopped.signal_name} after {stopped.finished} of {stopped.total} starts{begun}: "
                      f"kept them and their best (status interrupted) in {escape(str(stopped.kept))}/; finish the run "
                      f"with\n"
                      # quoted for the shell: a path with a space pasted as printed was two arguments
                      f"  agrisynth solve {escape(shlex.quote(str(stopped.spec)))} --resume "
                      f"{escape(shlex.quote(str(stopped.kept)))}",
                      soft_wrap=True)


class Terminal:
    """The command line's subscriber: each event of a run drawn as it comes.  ``ends_process``: the process ends
    with this command, so once a result's summary is printed nothing is left for a signal to stop (ignored)."""

    def __init__(self, ends_process: bool = False):
        self.ends_process = ends_process
        self._bar = contextlib.ExitStack()
        self._progress: Progress | None = None
        self._task = None
        self._solving = False       # a solve's bar is shown (between SolveStarted and StartsDone)

    def __enter__(self) -> "Terminal":
        return self

    def __exit__(self, *exc) -> None:
        self._bar.close()

    def __call__(self, event) -> None:
        draw = getattr(self, f"_on_{type(event).__name__}", None)
        if draw is not None:
            draw(event)

    def _bar_of(self, description: str, total: int, *columns) -> None:
        self._progress = Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), *columns,
                                  TimeElapsedColumn(), console=console, transient=not sys.stdout.isatty())
        self._bar.enter_context(self._progress)
        self._task = self._progress.add_task(description, total=total, best="")

    def _on_SpecFromLibrary(self, e: events.SpecFromLibrary) -> None:
        console.print(f"note: no file {escape(str(e.given))} here: using the library's {escape(e.relative)} "
                      f"({escape(str(e.path))})", soft_wrap=True)

    def _on_Note(self, e: events.Note) -> None:
        console.print(f"[yellow]note:[/] {escape(e.text)}", soft_wrap=True)

    def _on_RunWarning(self, e: events.RunWarning) -> None:
        err_console.print(f"[yellow]{escape(e.text)}[/]")

    def _on_SolveStarted(self, e: events.SolveStarted) -> None:
        if self._solving:           # --starts auto began another batch: the same bar, its total grown
            self._progress.update(self._task, total=e.total)
            return
        self._solving = True
        self._bar_of(f"solving {e.name}", e.total, TextColumn("{task.fields[best]}"))

    def _on_StartFinished(self, e: events.StartFinished) -> None:
        self._progress.update(self._task, advance=1, best=f"best: start {e.best_start}, objective "
                                                          f"{e.best_objective:.6g} ({e.best_verdict})")
        if not sys.stdout.isatty():         # piped: no live bar, so a line per finished start
            console.print(e.line(), markup=False, highlight=False)
            console.file.flush()

    def _on_StartsDone(self, e: events.StartsDone) -> None:
        self._solving = False
        self._bar.close()

    def _on_SolverLog(self, e: events.SolverLog) -> None:
        console.print(e.text, markup=False)

    def _on_ResultWritten(self, e: events.ResultWritten) -> None:
        try:
            summary = check_summary if isinstance(e.details, CheckWritten) else solve_summary
            summary(e.result, e.folder, e.replaced, e.details)
        finally:
            if self.ends_process:     # the process ends with this command: nothing is left for a signal to stop
                interrupt.ignore()

    def _on_SignalAfterResult(self, e: events.SignalAfterResult) -> None:
        err_console.print(f"{e.signal_name} arrived once the result was complete: {escape(str(e.folder))}/ holds it; "
                          f"the exit code is the result's")

    def _on_MonteCarloPlan(self, e: events.MonteCarloPlan) -> None:
        err_console.print(f"Monte-Carlo: {e.samples} samples, each re-checked at the nominal operating point and at "
                          f"{e.points} points of the operating range ({e.samples * (e.points + 1)} re-checks)")

    def _on_BenchStarted(self, e: events.BenchStarted) -> None:
        self._bar_of("bench", e.total)

    def _on_BenchStep(self, e: events.BenchStep) -> None:
        if e.what is None:
            self._progress.advance(self._task)
        else:
            self._progress.update(self._task, description=escape(e.what))
