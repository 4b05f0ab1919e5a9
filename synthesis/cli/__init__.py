"""agrisynth command line: parse, call, map the outcome to an exit code. No maths here.

Exit codes (docs/ARCHITECTURE.md, "Exit codes"): 0 every rule satisfied; 1 some rule violated; 2 bad input;
3 solver failure or infeasible rule set; 130 interrupted by Ctrl-C, 143 by SIGTERM.
"""

from __future__ import annotations

import contextlib
import re
import sys
from pathlib import Path

import click
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from constraints.base import limit_text
from synthesis.errors import AgrisynthError, AssemblyError, SpecError
from synthesis.library import LIBRARY
from synthesis.cli.terminal import PIPED_WIDTH


#: as wide as the terminal; piped, wide enough that no table cell is ever cut (synthesis.cli.terminal)
console = Console(highlight=False, width=None if sys.stdout.isatty() else PIPED_WIDTH)
err_console = Console(stderr=True, highlight=False)


def rule_table(rules: list[dict], title: str) -> Table:
    from synthesis.cli.terminal import add_columns

    table = Table(title=escape(title), title_justify="left")
    add_columns(table, (("rule", "left"), ("value", "right"), ("limit", "right"), ("unit", "left"),
                        ("margin", "right"), ("", "left"), ("where / why", "left")))
    for r in rules:
        limit = limit_text(r["limit"])
        value = "-" if r["value"] is None else f"{r['value']:.4g}"
        margin = "-" if r["margin"] is None else f"{r['margin']:.4g}"
        verdict = "[green]pass[/]" if r["satisfied"] else "[bold red]FAIL[/]"
        table.add_row(escape(r["name"]), value, limit, escape(r["unit"]), margin, verdict,
                      escape(r.get("note") or r.get("where", "")))
    return table


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="agrisynth")
def cli() -> None:
    """Design transplanting and harvesting mechanisms by optimisation.

    \b
    Write a spec file (TOML; agrisynth problems lists the library, --copy NAME copies one), then:
      agrisynth check SPEC    evaluate the spec's design against every rule
      agrisynth solve SPEC    optimise the spec's free variables (multistart IPOPT)
      agrisynth compare RUN.. compare result folders side by side in one HTML page
      agrisynth bench KIND    compare methods: objective reached against wall time
      agrisynth problems      list the problem library
      agrisynth spec KIND     the spec reference of a kind (--template: a file to start from)
      agrisynth tolerance SPEC  sensitivities, tolerance stack-up, Monte-Carlo check of a design
      agrisynth studio SPEC   an interactive design page on 127.0.0.1 (the studio extra)
    Results go to results/<spec name>/ for solve, results/<spec name>-check/ for check
    (result.json, report.html, plots): check, solve, compare, check solved.toml need no --force.
    Exit codes: 0 all rules satisfied, 1 a rule violated, 2 bad input,
    3 solver failure / infeasible, 130 interrupted (Ctrl-C), 143 stopped (SIGTERM).
    """


@cli.command()
@click.option("--dir", "library", type=click.Path(exists=True, file_okay=False, path_type=Path), default=LIBRARY,
              show_default=True, help="problem library folder")
@click.option("--copy", "name", metavar="NAME", default=None,
              help="copy the library spec NAME (its file as listed, e.g. planting_arm/taiwan_example1.toml, or its "
                   "file name alone) into the working folder to edit it, with the spec files it names")
@click.option("--out", "target", type=click.Path(path_type=Path), default=None,
              help="with --copy: the file (or folder) to write [default: the spec's file name, here]")
@click.option("--force", is_flag=True, help="with --copy: replace a file of that name (without it an existing "
                                            "file is kept and the command exits 2)")
def problems(library: Path, name: str | None, target: Path | None, force: bool) -> None:
    """List the problem kinds (what each designs, whether it solves) and the problem library:
    kind, name, source of every spec file.  `check` and `solve` take a library spec by its file as
    listed (planting_arm/taiwan_example1.toml) where the working folder has no such file.

    \b
    Examples:
      agrisynth problems --copy planting_arm/redesign_from_example1.toml
      agrisynth problems --copy taiwan_example1 --out my_arm.toml && agrisynth check my_arm.toml
    """
    if name is None:
        for option, given in (("--out", target is not None), ("--force", force)):
            if given:
                raise click.UsageError(f"{option} goes with --copy NAME")
        _list_library(library)
        return
    from synthesis.library import copy_out, library_spec, unknown_name_text

    source = library_spec(name, library)
    if source is None:
        raise SpecError(unknown_name_text(name, library))
    written = copy_out(source, Path(source.name) if target is None else target, force=force)
    also = f" (and {', '.join(escape(str(p)) for p in written[1:])}, the spec files it names)" if written[1:] else ""
    console.print(f"wrote {escape(str(written[0]))}{also}: a copy of the library's "
                  f"{escape(source.relative_to(library).as_posix())} to edit; check it with  agrisynth check "
                  f"{escape(str(written[0]))}", soft_wrap=True)


def _list_library(library: Path) -> None:
    from synthesis import kinds
    from synthesis.spec.common import read_toml

    from synthesis.cli.terminal import add_columns

    kinds_table = add_columns(Table(title="kinds", title_justify="left"),
                              [(col, "left") for col in ("kind", "mechanism", "commands", "try")])
    for kind in kinds.all_kinds():
        kinds_table.add_row(kind.name, escape(kind.summary), "check, solve" if kind.solves else "check",
                            f"problems/{kind.example}" if kind.example else "")
    console.print(kinds_table)
    table = add_columns(Table(title=f"problem library: {library}", title_justify="left"),
                        [(col, "left") for col in ("kind", "name", "file", "source")])
    for path in sorted(library.rglob("*.toml")):
        if not path.is_file():          # a folder named x.toml is no spec
            continue
        try:
            data, _ = read_toml(path)
        except SpecError as exc:        # one unreadable file is a row saying so, not the end of the listing
            table.add_row("?", "?", escape(str(path.relative_to(library))),
                          escape(f"not read: {str(exc).removeprefix(f'{path}: ')}"))
            continue
        table.add_row(escape(str(data.get("kind", "?"))), escape(str(data.get("name", "?"))),
                      escape(str(path.relative_to(library))), escape(str(data.get("source", ""))))
    console.print(table)
    console.print("check or solve one by its file as listed (agrisynth check planting_arm/taiwan_example1.toml); "
                  "copy one to edit: agrisynth problems --copy FILE", soft_wrap=True)


def _spec_file(spec: Path) -> Path:
    """SPEC as given, when there is such a file (or the library has no spec of that name either: reading it says
    so); otherwise the library spec it names (planting_arm/taiwan_example1.toml, problems/... as the README
    writes it, or a file name the library has once), said on the terminal with its full path."""
    import os

    from synthesis.library import library_spec

    if os.path.lexists(spec):
        return spec
    found = library_spec(spec)
    if found is None:
        return spec
    console.print(f"note: no file {escape(str(spec))} here: using the library's "
                  f"{escape(found.relative_to(LIBRARY).as_posix())} ({escape(str(found))})", soft_wrap=True)
    return found


@cli.command("spec")
@click.argument("kind")
@click.option("--template", is_flag=True, help="write a commented starting spec of KIND (the library example's "
                                               "values, every field described) instead of the reference")
@click.option("--out", "target", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="with --template: write it to this new file (default: print it)")
def spec_command(kind: str, template: bool, target: Path | None) -> None:
    """The spec reference of KIND: every field with its TOML path, type, unit, default (or
    "required"), allowed range and meaning.  The same for every kind: docs/specs.md.

    \b
    Examples:
      agrisynth spec planting_fourbar
      agrisynth spec clamp_cam --template --out my_cam.toml && agrisynth check my_cam.toml
    """
    from synthesis import kinds
    from synthesis.cli import terminal
    from synthesis.spec import reference as specref

    description = kinds.get(kind)           # SpecError (exit 2) naming the known kinds
    if target is not None and not template:
        raise click.BadParameter("--out writes a template: give --template too", param_hint="--out")
    if not template:
        terminal.console_for().print(terminal.reference_table(kind, description.summary, specref.kind_entries(kind)))
        return
    if target is None:
        click.echo(specref.template(kind), nl=False)
        return
    from synthesis.errors import OutputError
    from synthesis.result import atomic_write_text

    if target.exists():
        raise OutputError(f"{target}: already exists; give a new file name (a template never replaces a file)")
    if not target.parent.is_dir():
        raise OutputError(f"{target}: no folder {target.parent} to write it in")
    atomic_write_text(target, specref.template(kind, target.parent))
    console.print(f"wrote {escape(str(target))}: a {kind} spec to edit; check it with  agrisynth check {escape(str(target))}",
                  soft_wrap=True)


FORCE_HELP = ("replace OUT/<name>/ when it holds an earlier agrisynth run (without --force such a run is kept and "
              "the command exits 2 before doing anything; a file or folder agrisynth did not write, also one put "
              "inside such a run, is never replaced or deleted, with or without --force)")


@cli.command()
@click.argument("spec", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out", type=click.Path(file_okay=False, path_type=Path), default=Path("results"),
              show_default=True, help="output folder; the run writes OUT/<spec name>-check/")
@click.option("--force", is_flag=True, help=FORCE_HELP.replace("OUT/<name>/", "OUT/<name>-check/"))
def check(spec: Path, out: Path, force: bool) -> None:
    """Evaluate SPEC's given design against its rules (no optimisation).

    Prints the rule table (value, limit, margin, pass/fail) and writes OUT/<name>-check/result.json,
    report.html and the kind's figures (a trajectory or path plot where the kind has one). Exit 0
    when every rule holds, 1 when one is violated.  SPEC may be a library spec as `agrisynth problems`
    lists it (planting_arm/taiwan_example1.toml) where the working folder has no such file.
    OUT/<name>-check/ (a solve of the same spec writes OUT/<name>/) must not exist yet, or hold an
    earlier agrisynth run and --force be given.
    """
    from synthesis import kinds
    from synthesis.core import interrupt
    from synthesis.report import run_artifacts
    from synthesis.result import CHECK_SUFFIX, open_run_folder, write_run
    from synthesis.spec import load_spec

    interrupt.install(keep_ignored=True)     # a signal the process was started ignoring stays ignored
    spec = _spec_file(spec)
    loaded = load_spec(spec)
    _tolerance_names_known(loaded)
    _unit_notes(loaded)
    run_folder = open_run_folder(out, loaded.name, force=force, spec=spec, suffix=CHECK_SUFFIX)
    written = False
    try:
        from synthesis.core.library_log import captured_warnings
        from synthesis.result import atomic_write_text

        with captured_warnings() as said:        # scipy/CasADi warnings: into warnings.log, not the terminal
            result = _described(_in_file(loaded, kinds.checker(loaded.kind)), loaded)
        files = {"warnings.log": lambda path: atomic_write_text(path, said())} if said() else {}
        # a signal CasADi swallowed inside a solve of the evaluation (a fit) cut it short: stop here, write nothing
        interrupt.check()
        # evaluated: from here a signal is noted, the result written and its summary printed (one deferral over
        # both, so no moment between them obeys it)
        with interrupt.deferred(reraise=False):
            folder, replaced = write_run(out, result, run_artifacts(result, files), folder=run_folder)
            written = True
            with _after_the_result(folder):
                _check_summary(loaded, result, folder, replaced)
    except BaseException as exc:
        from synthesis.errors import OutputError

        if not written and not isinstance(exc, OutputError):
            run_folder.discard()
        raise


def _staging_hint(folder: Path) -> str:
    """A run killed outright (SIGKILL, power loss) leaves its starts in the staging folder beside the one it was to
    become (OUT/.<name>.run-XXXX/, starts.jsonl): name it, newest first, so --resume can be given it."""
    from synthesis.result import is_run_folder

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


def _unknown_design_variables(model, names: list[str], where: str) -> None:
    """SpecError naming those of ``names`` that are no design variable of the spec (a variable's name in the kind's
    NLP is taken too, as the analysis maps it: spec_keys); nothing is said of a kind that declares none."""
    from synthesis.spec.design_info import describe
    from synthesis.tolerance.design import spec_keys

    info = describe(model)
    unknown = [n for n, key in zip(names, spec_keys(names, info)) if key not in info]
    if info and unknown:
        raise SpecError(f"{where}: unknown design variable {', '.join(unknown)} (known: {', '.join(info)})")


def _tolerance_names_known(loaded) -> None:
    """A [tolerance] variables entry naming no design variable is bad input in check too (solve and tolerance
    refuse it; check ignored it)."""
    tol = getattr(loaded.model, "tolerance", None)
    if tol is not None and tol.variables:
        _unknown_design_variables(loaded.model, list(tol.variables), f"{loaded.path}: tolerance.variables")


def _check_summary(loaded, result, folder: Path, replaced: bool) -> None:
    """What check prints once its result is written, and its exit code (1: a rule violated)."""
    console.print(rule_table(result.rules, f"{result.name} ({result.kind}): {loaded.path}"))
    if replaced:
        console.print(f"replaced the previous run in {escape(str(folder))}/")
    console.print(f"wrote {escape(str(folder))}/: {escape(', '.join(sorted(f.name for f in folder.iterdir())))}")
    from synthesis.spec.operating import ranges_of

    ranged = sorted(ranges_of(loaded.model))
    at = " at the nominal operating point" if ranged else ""
    if ranged:     # check evaluates a range's nominal value only: say so rather than imply the range holds
        console.print(f"note: {', '.join(ranged)} given as a range: check evaluates the nominal value only; "
                      f"`agrisynth solve` re-checks every rule over the range (<rule>@envelope rows)")
    published = published_figures_line(result.extra)
    if published:        # the rules are the design's; the paper's figures are the reading's, said apart
        console.print(escape(published))
    note = result.extra.get("note") if isinstance(result.extra, dict) else None
    if isinstance(note, str) and note:      # the kind's word on the design beyond its rules (targets that are one)
        console.print(f"[yellow]note:[/] {escape(note)}", soft_wrap=True)
    bad = result.violated()
    if bad:
        console.print(f"[bold red]{len(bad)} rule(s) violated{at}:[/] {', '.join(escape(r['name']) for r in bad)}")
        sys.exit(1)
    console.print(f"[green]every rule satisfied{at}[/]")


@contextlib.contextmanager
def _after_the_result(folder: Path):
    """The summary printed after a run's result is written.  The result is complete, so a Ctrl-C or SIGTERM from
    here on is noted, not obeyed: the exit code stays the result's (0, 1 or 3) rather than 130 over a finished run
    (the printing takes a moment, there is nothing left to stop)."""
    from synthesis.core import interrupt

    try:
        with interrupt.deferred(reraise=False):
            try:
                yield
            finally:
                if _as_program:     # the process ends with this command: nothing is left for a signal to stop
                    interrupt.ignore()
    finally:
        signum = interrupt.pending()
        if signum is not None:
            import signal as _signal

            err_console.print(f"{_signal.Signals(signum).name} arrived once the result was complete: "
                              f"{escape(str(folder))}/ holds it; the exit code is the result's")


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


def _unit_notes(loaded) -> None:
    """Numbers that look like metres for mm or radians for degrees: a note each, before the run (valid input)."""
    from synthesis.spec.plausibility import unit_notes

    for note in unit_notes(loaded.model):
        console.print(f"[yellow]note:[/] {escape(note)}", soft_wrap=True)


def _violation_text(report) -> str:
    """"worst violation 0.93", or for a design whose rules could not all be evaluated (an infinite violation) what
    stands in the way: "no design: <why>" or "entry_angle not evaluated: <note>"."""
    import math

    if math.isfinite(report.worst_violation):
        return f"worst violation {report.worst_violation:.3g}"
    if report.why:
        return f"no design: {report.why.rstrip('.')}"
    missing = next((r for r in report.records if r.value is None), None)
    if missing is not None:
        return f"{missing.name} not evaluated" + (f": {missing.note.rstrip('.')}" if missing.note else "")
    return "not evaluated"


def _start_line(report, best, done: int, total: int) -> None:
    """One line for a finished start (piped runs): its outcome and the best so far."""
    o = report.outcome
    own = "feasible" if report.satisfied else _violation_text(report)
    console.print(f"start {o.start} finished ({done}/{total}): objective {o.objective:.6g}, {own}, IPOPT "
                  f"{o.return_status} in {o.iterations} iterations, {o.wall_s:.2f} s; best so far: start "
                  f"{best.outcome.start}", markup=False, highlight=False)
    console.file.flush()


def _print_design(result) -> None:
    """The solved design beside the given one: value, unit, bounds, at-bound marks."""
    from synthesis.cli import terminal
    from synthesis.report.tables import GIVEN_HEADING, candidates, design_rows, solved_heading

    rows = design_rows(candidates([result]))
    if rows:
        console.print(terminal.design_table(rows, f"design: {GIVEN_HEADING} vs {solved_heading(result)}",
                                            solved_heading(result)))


def _solved_spec(loaded, result) -> dict:
    """solved.toml: the solved design as a spec with everything fixed (``agrisynth check`` reproduces it)."""
    from synthesis.result import atomic_write_text
    from synthesis.spec.solved import FILENAME, solved_toml

    return {FILENAME: lambda path: atomic_write_text(path, solved_toml(loaded, result))}


def _described(result, loaded):
    """The result, told what the spec says of each design variable (unit, bounds, free): reports show it.  A spec
    that leaves part of its design to the kind (a convex fit of its path's control points) is described with
    that part written out (``Kind.explicit_design``), as solved.toml and the studio write it: every variable the
    solve moved is listed, free, with the box it moved in."""
    from synthesis import kinds
    from synthesis.spec import design_info
    from synthesis.errors import AgrisynthError

    if kinds.get(loaded.kind).writes_explicit_design:
        try:
            loaded, _ = kinds.explicit_design(loaded)       # the file as the run read it
        except (AgrisynthError, OSError):    # a description is not worth a run: described as loaded
            pass
    return design_info.attach(result, loaded.model)


def _in_file(loaded, evaluate):
    """``evaluate(loaded)``; a design that cannot be evaluated (AssemblyError) is named with its spec file."""
    try:
        return evaluate(loaded)
    except AssemblyError as exc:
        if str(exc).startswith(str(loaded.path)):
            raise
        raise AssemblyError(f"{loaded.path}: {loaded.kind}: {exc}") from None


def comparison_table(best: list[dict], baseline: list[dict] | None, title: str, solved: str = "solved") -> Table:
    """A solve's rule table: each rule at the given design (start 0) and at the solved one (heading ``solved``)."""
    from synthesis.report.tables import GIVEN_HEADING
    from synthesis.cli.terminal import add_columns

    table = Table(title=escape(title), title_justify="left")
    add_columns(table, (("rule", "left"), ("limit", "right"), (GIVEN_HEADING, "right"), ("", "left"),
                        (solved, "right"), ("", "left"), ("unit", "left")))
    base = {r["name"]: r for r in baseline or []}

    def cell(r):
        if r is None:
            return "", ""
        value = "-" if r["value"] is None else f"{r['value']:.4g}"
        return value, ("[green]pass[/]" if r["satisfied"] else "[bold red]FAIL[/]")

    for r in best:
        table.add_row(escape(r["name"]), limit_text(r["limit"]), *cell(base.get(r["name"])), *cell(r), escape(r["unit"]))
    return table


def _objectives_help() -> str:
    """The objectives of every kind that solves, from the registry (one line each, wrapped by hand)."""
    from synthesis import kinds

    lines = []
    for kind in kinds.all_kinds():
        if kind.solves:
            lines.append(f"  {kind.name}:")
            lines += [f"    {name}  {meaning}" for name, meaning in kind.objectives.items()]
    return "\n    ".join(lines)


class _WholeNumber(click.IntRange):
    """An integer option: click's IntRange calls '1e9' "not a valid integer range", which reads as if a range were
    asked for; this says what is wanted and within which limits."""

    name = "whole number"

    def convert(self, value, param, ctx):
        if isinstance(value, str):
            try:
                int(value)
            except ValueError:
                self.fail(f"{value!r} is not a whole number ({self._describe_range()})", param, ctx)
        return super().convert(value, param, ctx)


class _SolveCommand(click.Command):
    """`solve --help` lists every kind's objectives from the registry, read only when help is asked for
    (so an ordinary run imports no other kind's package)."""

    def format_help(self, ctx, formatter):
        self.help = self.help.replace("{objectives}", _objectives_help())
        super().format_help(ctx, formatter)



#: a scheduler address agrisynth accepts: tcp://host:port (dask's default protocol) or host:port
SCHEDULER = re.compile(r"^(tcp://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):[0-9]{1,5}$")
MAX_STARTS = 10000
MAX_WORKERS = 256


def _scheduler(ctx, param, value: str | None) -> str | None:
    if value is None:
        return None
    if len(value) > 300 or not SCHEDULER.match(value) or not 0 < int(value.rsplit(":", 1)[1]) < 65536:
        raise click.BadParameter(f"{value[:80]!r} is not a scheduler address: give tcp://host:port "
                                 f"(e.g. tcp://10.0.0.5:8786)")
    return value if value.startswith("tcp://") else f"tcp://{value}"


@cli.command(cls=_SolveCommand)
@click.argument("spec", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="output folder; the run writes OUT/<spec name>/  [default: results]")
@click.option("--force", is_flag=True, help=FORCE_HELP)
@click.option("--resume", "resume", type=click.Path(file_okay=False, path_type=Path), default=None, metavar="RUN_DIR",
              help="finish an interrupted run: the starts in RUN_DIR/starts.jsonl are not solved again and the "
                   "result is exactly the uninterrupted one; SPEC must be the same file and --starts/--seed (default: "
                   "that run's) the same settings (checked by sha256); the result replaces RUN_DIR")
@click.option("--starts", type=_WholeNumber(min=1, max=MAX_STARTS), default=None,
              help=f"multistart starts, at most {MAX_STARTS} (default: the spec's [solver] starts); "
                   f"start 0 is the spec's design")
@click.option("--seed", type=_WholeNumber(min=0, max=2**53), default=None,
              help="seed of the Latin-hypercube starts (default: the spec's [solver] seed)")
@click.option("--workers", type=_WholeNumber(min=1, max=MAX_WORKERS), default=None,
              help=f"parallel worker processes, at most {MAX_WORKERS} (default: all cores)")
@click.option("--scheduler", default=None, metavar="ADDR", callback=_scheduler,
              help="run the starts on a dask.distributed cluster at tcp://host:port (the workers need agrisynth "
                   "installed) instead of local worker processes.  A scheduler runs the code it is sent: "
                   "trust it as you trust this machine")
@click.option("--verbose", is_flag=True, help="print IPOPT's output (always kept in OUT/<name>/ipopt.log)")
def solve(spec: Path, out: Path | None, force: bool, resume: Path | None, starts: int | None, seed: int | None,
          workers: int | None, scheduler: str | None, verbose: bool) -> None:
    """Optimise SPEC's free design variables so every rule holds (CasADi + IPOPT, exact derivatives).

    \b
    Every rule is a constraint; the objective is the spec's [objective] name, by kind
    (the first is the default):
    {objectives}
    Starts are a fixed-seed Latin hypercube (start 0 = the given design). Every start is
    re-checked on a 10x finer grid, independently of the solver; the best is the feasible one
    with the best objective (objectives within 1e-9 relative tie: a start IPOPT finished at its
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
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from synthesis import kinds
    from synthesis.core import interrupt, startlog
    from synthesis.core import solve as core
    from synthesis.core.executor import default_workers
    from synthesis.errors import OutputError
    from synthesis.report import run_artifacts
    from synthesis.result import RUN_NAME, atomic_write_text, is_run_folder, open_run_folder, write_run
    from synthesis.spec import load_spec

    if scheduler is not None and workers is not None:
        raise click.BadParameter("give either --workers (local processes) or --scheduler (a dask cluster), "
                                 "not both", param_hint="--workers/--scheduler")
    if resume is not None and out is not None:
        raise click.BadParameter("a resumed run is written where RUN_DIR is; leave out --out", param_hint="--out")
    interrupt.install(keep_ignored=True)     # a signal the process was started ignoring stays ignored
    spec = _spec_file(spec)
    loaded = load_spec(spec)
    _tolerance_names_known(loaded)
    _unit_notes(loaded)
    kind = kinds.solving_kind_for(loaded)       # [tolerance]: every rule at its linearised worst case
    if scheduler is not None:       # a peer that is no dask scheduler: exit 2 now, within the connect timeout
        try:
            from synthesis.core.cluster import probe_scheduler
        except ImportError:
            raise AgrisynthError("--scheduler needs dask.distributed: pip install 'agrisynth[cluster]'") from None
        probe_scheduler(scheduler)
    workers = min(workers or default_workers(), MAX_WORKERS)
    if resume is not None:
        if not is_run_folder(resume):
            raise OutputError(f"--resume {resume}: not an agrisynth run folder{_staging_hint(resume)}")
        earlier = startlog.settings_of(resume)      # --starts and --seed default to the interrupted run's
        starts = earlier.get("starts") if starts is None and isinstance(earlier.get("starts"), int) else starts
        seed = earlier.get("seed") if seed is None and isinstance(earlier.get("seed"), int) else seed
    n = starts or loaded.model.solver.starts
    the_seed = loaded.model.solver.seed if seed is None else seed
    settings, fingerprint = startlog.fingerprint(loaded.kind, loaded.name, loaded.sha256, n, the_seed)
    finished = None
    replaceable = None
    folder_name = loaded.name
    if resume is not None:
        finished = startlog.read(resume, fingerprint)
        where = resume.resolve()
        out = where.parent
        # the result replaces RUN_DIR itself, whatever its name (a renamed run too); a staging folder left by a
        # SIGKILL (.<name>.run-XXXX, README) is no folder name: its result goes to OUT/<spec name>, as before
        if RUN_NAME.match(where.name):
            folder_name, replaceable = where.name, resume
    out = Path("results") if out is None else out
    run_folder = open_run_folder(out, folder_name, force=force, spec=spec, replaceable=replaceable,
                                 resumed_from=resume)      # a killed run's staging folder: removed once complete
    committed = False
    try:
        log_file = startlog.StartLog(run_folder.staging / startlog.FILENAME, settings, fingerprint)
        from synthesis.core.library_log import captured_warnings

        solved = None         # (result, reports, log) once every start has finished
        stderr = sys.stderr   # the warnings capture swaps it; an exit cut short by a signal may not swap it back
        try:
            with Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                          TextColumn("{task.fields[best]}"), TimeElapsedColumn(), console=console,
                          transient=not sys.stdout.isatty()) as progress:
                task = progress.add_task(f"solving {loaded.name}", total=n, best="")

                def on_start(report, best) -> None:
                    tag = "feasible" if best.satisfied else _violation_text(best)
                    progress.update(task, advance=1, best=f"best: start {best.outcome.start}, "
                                                          f"objective {best.outcome.objective:.6g} ({tag})")
                    if not sys.stdout.isatty():         # piped: no live bar, so a line per finished start
                        _start_line(report, best, progress.tasks[task].completed, n)

                try:
                    with captured_warnings() as said:   # scipy/CasADi warnings: into ipopt.log, not the terminal
                        solved = core.run_solve(kind, loaded, starts, seed, workers, on_start, scheduler,
                                                record=log_file.append, finished=finished)
                except (SpecError, AssemblyError) as exc:
                    # a spec the run's set-up cannot use (e.g. a key point the arm cannot reach) is
                    # said as check says it: the file first
                    if str(loaded.path) in str(exc):
                        raise
                    raise type(exc)(f"{loaded.path}: {exc}") from None
                except core.Interrupted as exc:
                    log_file.close()
                    if exc.partial is not None:
                        _described(exc.partial[0], loaded)
                    committed = _keep_interrupted(exc, run_folder, spec, n,
                                                  lambda: core.baseline_rules(kind, loaded))
                    sys.exit(exc.exit_code)
        except (KeyboardInterrupt, SystemError) as exc:
            # the signal came as the run returned (closing the warnings capture or the progress bar): the result
            # is complete, so it is kept like any later signal (noted, the exit code the result's)
            if solved is None or not interrupt.caused_by_signal(exc):
                raise
            with interrupt.deferred(reraise=False):
                sys.stderr = stderr
                progress.stop()
        # every start is done: a signal from here on is noted and the finished result written all the same
        with interrupt.deferred(reraise=False):
            result, reports, log = solved
            if said():
                log += f"\n# library warnings outside the IPOPT runs\n{said()}"
            _described(result, loaded)
            log_file.close()
            if verbose:
                console.print(log, markup=False)
            baseline = core.baseline_rules(kind, loaded)
            artifacts = run_artifacts(result, {"ipopt.log": lambda path: atomic_write_text(path, log),
                                               **_solved_spec(loaded, result)}, given_rules=baseline)
            folder, replaced = write_run(out, result, artifacts, folder=run_folder)
            committed = True
            with _after_the_result(folder):     # inside the same deferral: no moment between them obeys a signal
                _solve_summary(kind, result, reports, baseline, workers, scheduler, finished, resume, replaced,
                               folder)
    except BaseException as exc:
        if not committed and not isinstance(exc, OutputError):
            run_folder.discard()
        raise


def _solve_summary(kind, result, reports, baseline, workers: int, scheduler: str | None, finished, resume,
                   replaced: bool, folder: Path) -> None:
    """What a finished solve prints once its result is written, and its exit code (1: a rule violated; 3:
    infeasible or failed, the diagnosis in the message)."""
    from synthesis.core import solve as core
    from synthesis.report.tables import objective_text, solved_heading

    answer = solved_heading(result)
    console.print(comparison_table(result.rules, baseline, f"{result.name}: rules at the given design (start 0) "
                                                           f"and at the {'solved one' if answer == 'solved' else answer}",
                                   answer))
    _print_design(result)
    s = result.solver
    console.print(f"objective {objective_text(result.objective)}; IPOPT "
                  f"{s['return_status']} in {s['iterations']} iterations; best of {s['starts']} starts "
                  f"{'and one from the elastic re-solve ' if s.get('starts_run', 0) > s['starts'] else ''}"
                  f"(seed {s['seed']}) is start {s['best_start']}; {s['wall_s']:.2f} s on "
                  f"{f'the cluster at {escape(scheduler)}' if scheduler else f'{workers} worker(s)'}; "
                  f"status {result.status}")
    mc = ((result.extra or {}).get("tolerance") or {}).get("monte_carlo")
    if isinstance(mc, dict):        # a tolerance-robust solve: the Monte-Carlo check of the answer
        from synthesis.tolerance.output import monte_carlo_lines

        console.print(escape("\n".join(monte_carlo_lines(mc))))
    if finished:
        console.print(f"resumed: {len(finished)} finished start(s) read from {escape(str(resume))}/starts.jsonl")
    if replaced:
        console.print(f"replaced the previous run in {escape(str(folder))}/")
    console.print(f"wrote {escape(str(folder))}/: {escape(', '.join(sorted(f.name for f in folder.iterdir())))}")
    if s["status_note"]:
        console.print(f"[yellow]note:[/] {escape(s['status_note'])}")
    if result.status in ("infeasible", "failed"):
        raise core.exit_error(kind, result, reports)
    bad = result.violated()
    if bad:
        console.print(f"[bold red]{len(bad)} rule(s) violated:[/] {', '.join(escape(r['name']) for r in bad)}")
        sys.exit(1)
    console.print("[green]every rule satisfied on the fine grid[/]")


@cli.command("studio")
@click.argument("spec", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=Path("results/studio"),
              show_default=True, help="the one folder the page writes into (saved specs, solve runs)")
@click.option("--port", type=_WholeNumber(min=0, max=65535), default=0, show_default=True,
              help="port on 127.0.0.1 (0: any free one)")
@click.option("--open", "open_browser", is_flag=True, help="open the page in the default browser")
def studio(spec: Path, out: Path, port: int, open_browser: bool) -> None:
    """An interactive design page for SPEC, served on 127.0.0.1 only (needs the `studio` extra).

    A slider per design variable; the mechanism, its path and every rule of `agrisynth check` redrawn as
    you drag (a coarse grid while dragging, the check's grid on release); solve from here (`agrisynth
    solve` with the page's values as start 0, in a worker process), save spec, reset, compare with the
    baseline. Prints the page's address (with its random token); Ctrl-C stops the server.
    """
    try:
        from synthesis.studio.server import Studio
    except ImportError as exc:
        raise AgrisynthError(f"agrisynth studio needs the studio extra ({exc.name} is missing): "
                             f"pip install -e '.[studio]'") from None
    spec = _spec_file(spec)
    try:
        app = Studio(spec, out, port)
    except OSError as exc:
        raise AgrisynthError(f"--port {port}: cannot listen on 127.0.0.1 ({exc.strerror})") from None
    console.print(f"agrisynth studio for {escape(str(spec))}: open\n  {app.url}\n"
                  f"writing into {escape(str(app.out))}/; Ctrl-C stops", soft_wrap=True)
    if open_browser:
        import webbrowser

        webbrowser.open(app.url)
    app.serve()


class _HalfWidth(click.FloatRange):
    """A tolerance half-width: a finite number >= 0 (click's FloatRange lets nan and inf through)."""

    name = "half-width"

    def convert(self, value, param, ctx):
        import math

        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


#: the spec's [tolerance] limits (spec.common.ToleranceSpec): the options take what a spec may say
LENGTH_HALF_WIDTH = _HalfWidth(min=0, max=1e3)
ANGLE_HALF_WIDTH = _HalfWidth(min=0, max=90)


@cli.command("tolerance")
@click.argument("target", metavar="RESULT|SPEC", type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=Path("results"), show_default=True,
              help="writes OUT/<name>-tolerance/")
@click.option("--length", type=LENGTH_HALF_WIDTH, default=None, help="half-width for every length, mm (0 to 1000)")
@click.option("--angle", type=ANGLE_HALF_WIDTH, default=None, help="half-width for every angle, deg (0 to 90)")
@click.option("--tol", "tols", multiple=True, metavar="NAME=VALUE",
              help="half-width for one design variable, in its own unit (repeatable; over --length/--angle and the "
                   "spec's [tolerance] entry of that variable)")
@click.option("--samples", type=_WholeNumber(min=0, max=1_000_000), default=None,
              help="Monte-Carlo samples (default the spec's [tolerance] samples, else 1000)")
@click.option("--seed", type=_WholeNumber(min=0, max=2**53), default=None, help="Monte-Carlo seed (default 0)")
@click.option("--force", is_flag=True, help=FORCE_HELP.replace("OUT/<name>/", "OUT/<name>-tolerance/"))
def tolerance(target: Path, out: Path, length: float | None, angle: float | None, tols: tuple[str, ...],
              samples: int | None, seed: int | None, force: bool) -> None:
    """Exact sensitivities, linear tolerance stack-up and a seeded Monte-Carlo of a design.

    RESULT: a run folder (its solved.toml is the design); SPEC: the spec's given design.  Tolerances
    from --length/--angle (every length / angle) and --tol NAME=VALUE (one variable), else the spec's
    [tolerance] table.  Writes OUT/<name>-tolerance/ (result.json, report.md, tornado.png).
    Derivatives w.r.t. the operating conditions (forward speed, crank speed, friction, ...) are always
    listed; with an operating range each Monte-Carlo sample is re-checked at every point of the range's
    re-check grid and passes only if every rule holds at all of them.
    Exit 0 when the design and every Monte-Carlo sample pass every rule, 1 otherwise; with --samples 0
    (sensitivities and the linear stack-up only) exit 0 when the design passes every rule and every linear worst
    case holds, 1 otherwise.  Either way each rule is re-checked at its linear worst corner, a design in the box:
    missed there, it fails.
    result.json holds these verdicts as rule rows (<rule>@monte_carlo: the share of samples holding the rule;
    <rule>@tolerance: the linear worst margin; <rule>@linear_worst_corner: the rule missed at that corner), so
    `agrisynth compare` shows them; a failed run prints the rows that failed.
    """
    from synthesis import kinds
    from synthesis.errors import SpecError
    from synthesis.result import write_folder
    from synthesis.spec import load_spec
    from synthesis.tolerance.analysis import analyse
    from synthesis.tolerance.output import artifacts, table

    given = _per_variable_tolerances(tols)
    target = _spec_file(target)
    if target.is_file() and target.suffix == ".json":      # a run's result.json: its folder's solved design
        target = target.parent
    if target.is_dir():
        if not (target / "solved.toml").is_file():
            raise SpecError(_no_solved_design(target))
        target = target / "solved.toml"
    loaded = load_spec(target)
    _tolerance_names_known(loaded)
    kind = kinds.solving_kind(loaded.kind)
    spec = loaded.model
    tol = spec.tolerance
    length = length if length is not None else (tol.length if tol else None)
    angle = angle if angle is not None else (tol.angle if tol else None)
    per_variable = {**(dict(tol.variables) if tol else {}), **given}
    if given:               # an unknown name is bad input, said before any analysis
        _unknown_design_variables(spec, list(given), "--tol")
    if not (length or angle or any(per_variable.values())) and samples != 0:
        raise SpecError("tolerance: give --length and/or --angle (or a [tolerance] table in the spec)")
    samples = samples if samples is not None else (tol.samples if tol else 1000)
    seed = seed if seed is not None else (tol.seed if tol else 0)
    design = kinds.checker(loaded.kind)(loaded).design
    from synthesis.tolerance.envelope import grid_of

    points = len(grid_of(spec))
    if points > 1:        # an envelope: every sample is re-checked at every point of the range's grid
        err_console.print(f"Monte-Carlo: {samples} samples, each re-checked at the nominal operating point and at "
                          f"{points} points of the operating range ({samples * (points + 1)} re-checks)")
    facts = analyse(kind, spec, design, length=length, angle=angle, per_variable=per_variable, samples=samples,
                    seed=seed)
    name = spec.name.removesuffix("_solved")
    folder, _ = write_folder(out / f"{name}-tolerance", artifacts(kind.name, name, loaded.sha256, facts), force=force)
    console.print(escape(table(facts)))
    console.print(f"wrote {escape(str(folder))}/")
    # the rows result.json holds decide, so a reader of it sees why: the design's own rules and, per rule, every
    # Monte-Carlo sample holding it (--samples 0: its linearised worst case in the box)
    from synthesis.tolerance.output import verdict_rows

    failed = [r for r in facts["nominal_rules"] + verdict_rows(facts) if not r["satisfied"]]
    if failed:      # say which rows decide it: a table of 100 % passes may still hold a corner that breaks a rule
        console.print("failed: " + "; ".join(escape(f"{r['name']} ({r['note']})" if r.get("note") else r["name"])
                                             for r in failed), soft_wrap=True)
        sys.exit(1)


def _no_solved_design(folder: Path) -> str:
    """Why a folder given to `tolerance` has no solved design, from its result.json where it has one (read as
    `compare` reads one: a FIFO, a device or a hostile file there is no status, never a hang or a traceback)."""
    from synthesis.errors import ResultError
    from synthesis.files import read_json
    from synthesis.result import MAX_RESULT_BYTES

    try:
        data = read_json(folder / "result.json", MAX_RESULT_BYTES, "result.json", ResultError)
    except ResultError:
        data = None
    status = data.get("status") if isinstance(data, dict) else None
    if status == "interrupted":
        return (f"{folder}: an interrupted run, with no solved design (solved.toml) yet: finish it with "
                f"`agrisynth solve SPEC --resume {folder}`, then give this folder again")
    if status == "evaluated":
        return f"{folder}: a check's folder, with no solved design: give the spec file it checked"
    return f"{folder}: no solved.toml in this folder (give a solve's run folder or a spec file)"


def _per_variable_tolerances(tols: tuple[str, ...]) -> dict[str, float]:
    """--tol NAME=VALUE ... as {name: half-width}; a malformed, non-finite or non-positive value is bad input."""
    import math

    from synthesis.errors import SpecError

    out: dict[str, float] = {}
    for item in tols:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise SpecError(f"--tol {item!r}: give NAME=VALUE (a design variable and its half-width in its own unit)")
        try:
            value = float(text)
        except ValueError:
            raise SpecError(f"--tol {item}: {text!r} is not a number") from None
        if not math.isfinite(value) or value <= 0:
            raise SpecError(f"--tol {item}: the half-width must be a finite number > 0")
        if name in out:
            raise SpecError(f"--tol {name}: given twice ({out[name]:g} and {value:g}); give each variable once")
        out[name] = value
    return out


def _keep_interrupted(exc, run_folder, spec: Path, n: int, given_rules) -> bool:
    """Write an interrupted run's best-so-far result (status interrupted), its report and starts.jsonl,
    and say how to finish it; nothing is written (and nothing replaced) when no start had finished.
    ``given_rules()``: the rule table of the spec's given design, shown beside the best-so-far as in a
    finished solve's report."""
    import signal as _signal

    from synthesis.core import interrupt
    from synthesis.report import run_artifacts
    from synthesis.result import atomic_write_text, write_run

    name = _signal.Signals(exc.signum).name
    if exc.partial is None:
        run_folder.discard()
        err_console.print(f"interrupted by {name} before any start finished; nothing written")
        return False
    result, reports, log = exc.partial
    with interrupt.deferred(reraise=False):
        # no figures: the run ends within seconds of the signal (--resume draws them)
        artifacts = run_artifacts(result, {"ipopt.log": lambda path: atomic_write_text(path, log)},
                                  given_rules=given_rules(), figures=False)
        folder, _ = write_run(run_folder.final.parent, result, artifacts, folder=run_folder)
    err_console.print(f"interrupted by {name} after {len(reports)} of {n} starts: kept them and their best "
                      f"(status interrupted) in {escape(str(folder))}/; finish the run with\n"
                      f"  agrisynth solve {escape(str(spec))} --resume {escape(str(folder))}", soft_wrap=True)
    return True


@cli.command()
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=Path("results/compare"),
              show_default=True, help="folder for compare.html and its figures (an agrisynth output folder)")
@click.option("--force", is_flag=True, help="replace OUT when it holds an earlier agrisynth output (without --force "
                                            "it is kept and the command exits 2; a folder agrisynth did not write "
                                            "is never replaced)")
def compare(results: tuple[Path, ...], out: Path, force: bool) -> None:
    """Compare RESULT... (run folders or result.json files of one kind) side by side.

    \b
    The first RESULT is the baseline.  Writes OUT/compare.html, one self-contained page that
    works offline, with its figures beside it:
      rules    value, limit and margin per candidate; violated rules in red; the tightest
               rule of each candidate on the first line
      design   every variable, one column per candidate, differences from the baseline marked
      figures  the kind's overlays (paths, speeds and accelerations, linkage, animation)
      run      solver status, iterations, wall time (NLP build and starts), workers, starts,
               seed, versions, spec hash
    A RESULT that is an `agrisynth bench` output (OUT/bench or its bench.json) adds the
    error-against-run-time plot and table of its problems of the results' kind (a bench of
    another kind only is refused).  Nothing is re-solved: the page is built from
    the result files alone.
    \b
    Example:
      agrisynth check problems/planting_arm/taiwan_example1.toml
      agrisynth solve problems/planting_arm/redesign_from_example1.toml
      agrisynth compare results/taiwan_example1-check results/redesign_from_example1
    """
    import os

    from synthesis.report.compare import (bench_of_kind, is_bench, load_bench, load_candidates, open_output_folder,
                                   write_comparison)
    from synthesis.errors import OutputError
    from synthesis.result import is_run_folder

    target = Path(os.path.realpath(out))              # realpath, not resolve(): a symlink loop is the loader's to name
    for given in results:                             # --force would replace a result being compared
        read = Path(os.path.realpath(given))
        if read.name == "result.json" and is_run_folder(read.parent):
            read = read.parent                        # a run given as its result.json: the run folder is the result
        if read == target or target in read.parents or read in target.parents:
            raise OutputError(f"--out {out} holds or is inside RESULT {given}: the page would replace what it "
                              f"compares; write it to another folder")
    folder = open_output_folder(out, force)          # refused (exit 2) before anything is read
    try:
        cands = load_candidates([p for p in results if not is_bench(p)])
        bench = [res for p in results if is_bench(p) for res in bench_of_kind(p, load_bench(p), cands[0].result.kind)]
    except BaseException:
        folder.discard()
        raise
    page = write_comparison(cands, out, bench, folder=folder)
    for c in cands:
        bad = c.result.violated()
        verdict = "[green]every rule satisfied[/]" if not bad else f"[red]{len(bad)} rule(s) violated[/]"
        console.print(f"{escape(c.label)}: {c.result.status}, {verdict}")
    console.print(f"wrote {escape(str(page))}")


@cli.command()
@click.argument("problems", nargs=-1, metavar="[PROBLEM]...")
@click.option("--problems", "spec_files", multiple=True, type=click.Path(dir_okay=False, path_type=Path),
              metavar="SPEC", help="a spec file to bench (repeatable; instead of its kind's default set)")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=Path("results"), show_default=True,
              help="output folder; the bench writes OUT/bench/ (bench.json, bench.md, plots)")
@click.option("--repeats", type=_WholeNumber(min=1), default=None,
              help="runs of each IPOPT method per problem (median wall time) [default: 3; --quick: 1]")
@click.option("--quick", is_flag=True, help="1 start, 1 run, sample counts x 0.5 and x 1, no peers, no reference "
                                            "solve, no extreme matrix, the first problem of each kind (a kind with "
                                            "its own bench set: the generic studies only); about 1 minute on 2 cores")
@click.option("--no-extreme", is_flag=True, help="leave out the extreme-case matrix (tests/extreme/)")
@click.option("--force", is_flag=True, help="replace OUT/bench/ when it holds an earlier agrisynth bench (without "
                                            "--force it is kept and the command exits 2 before benching; a folder "
                                            "agrisynth did not write is never replaced)")
def bench(problems: tuple[str, ...], spec_files: tuple[Path, ...], out: Path, repeats: int | None, quick: bool,
          no_extreme: bool, force: bool) -> None:
    """Error against run time for every kind that solves, side by side in one run.

    \b
    PROBLEM is a kind name (its default bench set: library redesigns) or a spec file; none: every
    kind that solves.
    Per problem: IPOPT multistart with exact (CasADi) derivatives against the same NLP with
    finite differences and a limited-memory Hessian, scipy SLSQP and differential_evolution
    (each timed to the first moment it reaches the target: best known + tolerance, every rule on the
    fine grid; "target not reached" otherwise, and ratios only of those times); the sample-count sweep (time, iterations, fine-grid violation, objective gap);
    build against solve time; kind studies (planting: seed 000's difference scheme); and the
    extreme-case matrix of tests/extreme/.  Writes OUT/bench/bench.json, bench.md,
    error_vs_time.png (log-log: objective gap and violation against wall time) and
    samples_<problem>.png (`agrisynth compare ... OUT/bench` shows them).
    \b
    Examples:
      agrisynth bench --quick
      agrisynth bench clamp_cam guide_tube
      agrisynth bench --problems problems/planting_arm/redesign_from_example1.toml
    """
    import time

    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from synthesis import bench as benchmod
    from synthesis.spec import KINDS, load_spec

    repeats = repeats if repeats is not None else (1 if quick else 3)
    known = benchmod.kinds_with_bench()
    by_kind: dict[str, list | None] = {}
    items = [*problems, *(str(f) for f in spec_files)]
    for item in items or tuple(known):
        if item in known:
            by_kind.setdefault(item, None)
        elif item in KINDS:
            raise click.BadParameter(f"kind {item!r} has no bench cases (kinds with a bench: {', '.join(known)})",
                                     param_hint="PROBLEM")
        elif item.endswith(".toml") or Path(item).exists():
            loaded = load_spec(item)
            if loaded.kind not in known:
                raise click.BadParameter(f"{item}: kind {loaded.kind!r} has no bench cases "
                                         f"(kinds with a bench: {', '.join(known)})", param_hint="PROBLEM")
            # a spec file replaces its kind's default set, also when the kind is named too (before or after it)
            by_kind[loaded.kind] = (by_kind.get(loaded.kind) or []) + [loaded]
        else:
            raise click.BadParameter(f"{item!r} is neither a kind with a bench ({', '.join(known)}) nor a spec file",
                                     param_hint="PROBLEM")
    cases = []
    from synthesis.result import open_run_folder

    run_folder = open_run_folder(out, "bench", force=force)       # refused (exit 2) before any benching
    click.get_current_context().call_on_close(run_folder.discard)  # the staging folder, if the bench stops
    with benchmod.quick_mode(quick):
        for kind, specs in by_kind.items():
            try:
                cases += benchmod.cases_for(kind, specs, 0,
                                            None if items else benchmod.OWN_CASES_IN_EVERY_KIND_RUN)
            except Exception as exc:      # noqa: BLE001 - one kind's broken bench set must not stop the others
                if items:
                    raise
                err_console.print(f"[yellow]bench: kind {kind} left out: its bench cases could not be made "
                                  f"({type(exc).__name__}: {escape(str(exc))})[/]")
    extreme_on = not no_extreme and not items and not quick
    total = sum(c.runs(repeats) for c in cases) + (1 if extreme_on else 0)
    results = []
    extreme = None
    t0 = time.perf_counter()
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=console, transient=not sys.stdout.isatty()) as progress:
        task = progress.add_task("bench", total=total)

        def tick(what: str | None) -> None:
            if what is None:
                progress.advance(task)
            else:
                progress.update(task, description=escape(what))

        for case in cases:
            results.append(benchmod.run_case(case, repeats, tick))
        if extreme_on:
            from synthesis.bench.extreme import extreme_matrix

            tick("extreme-case matrix (tests/extreme/)")
            extreme = extreme_matrix()
            tick(None)
    with benchmod.quick_mode(quick):
        import dataclasses

        study = dataclasses.asdict(benchmod.current_settings())
    settings = {"repeats": repeats, "quick": quick, "study": study, "problems": [c.problem for c in cases],
                "wall_s": round(time.perf_counter() - t0, 1)}
    folder = benchmod.write_bench(out, results, settings, extreme, run_folder=run_folder)
    console.print(bench_table(results, repeats))
    console.print(f"wrote {escape(str(folder))}/bench.json, bench.md and plots ({settings['wall_s']:.0f} s)")


def bench_table(results: list[dict], repeats: int) -> Table:
    from synthesis.cli.terminal import add_columns

    table = Table(title=f"bench: objective reached, median wall time and time to target (IPOPT methods: {repeats} runs)",
                  title_justify="left")
    add_columns(table, (("problem", "left"), ("method", "left"), ("objective", "right"), ("gap to best", "right"),
                        ("worst violation", "right"), ("median s", "right"), ("time to target s", "right"),
                        ("iterations", "right"), ("time-to-target ratio", "right")))
    for res in results:
        for row in res["rows"]:
            details = row.get("details") if isinstance(row.get("details"), dict) else {}
            iters = details.get("median_iterations")
            table.add_row(escape(row["problem"]), escape(row["method"]), f"{row['objective']:.4g}",
                          f"{row['objective_gap']:.3g}", f"{row['worst_violation']:.3g}", f"{row['median_s']:.3f}",
                          escape(row.get("time_to_target_text") or "–"),
                          "" if iters is None else f"{iters:g}", escape(row["time_ratio_text"]))
    return table


#: set by :func:`main` while it runs: agrisynth runs as a program that ends with the command (a caller of main in
#: process -- a test -- restores the signal handlers itself: :func:`interrupt.ignore` left them ignored)
_as_program = False


def main() -> None:
    global _as_program
    _as_program = True
    try:
        _main()
    finally:       # main called in-process (a test) returns to code that may need signals: only this run ignored them
        _as_program = False


def _main() -> None:
    try:
        cli.main(standalone_mode=False, prog_name="agrisynth")
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.ClickException as exc:
        # one line, like every other bad input (click's own form is three: Usage, Try, Error)
        ctx = getattr(exc, "ctx", None)
        hint = f" (see `{ctx.command_path} --help`)" if isinstance(exc, click.UsageError) and ctx is not None else ""
        err_console.print(f"[bold red]error:[/] {escape(exc.format_message())}{escape(hint)}", markup=True,
                          soft_wrap=True)
        sys.exit(2)
    except (click.exceptions.Abort, KeyboardInterrupt) as exc:
        from synthesis.core import interrupt

        err_console.print("interrupted")
        sys.exit(128 + interrupt.signal_of(exc))
    except (SystemError, ImportError) as exc:
        from synthesis.core import interrupt

        # a signal that fired inside a C callback (SystemError) or a C extension's initialisation (an import the
        # command makes: ImportError "initialization failed"): an interruption
        if not (interrupt.caused_by_signal(exc) or isinstance(exc, ImportError) and interrupt.pending() is not None):
            raise
        err_console.print("interrupted")
        sys.exit(128 + interrupt.signal_of(exc))
    except AgrisynthError as exc:
        err_console.print(f"[bold red]error:[/] {escape(str(exc))}", markup=True, soft_wrap=True)
        sys.exit(exc.exit_code)
    except Exception:
        from synthesis.core import interrupt

        # a signal's KeyboardInterrupt raised inside a CasADi call comes out as another exception (NotImplementedError:
        # "wrong number or type of arguments"): with a signal noted, the run was interrupted, not broken
        if interrupt.pending() is None:
            raise
        err_console.print("interrupted")
        sys.exit(128 + interrupt.pending())

