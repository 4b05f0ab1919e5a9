"""agrisynth command line: parse, call, map the outcome to an exit code. No maths here.

Exit codes (DESIGN.md): 0 every rule satisfied; 1 some rule violated; 2 bad input; 3 solver
failure or infeasible rule set; 130 interrupted.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from constraints.base import limit_text
from synthesis.errors import AgrisynthError

LIBRARY = Path(__file__).resolve().parent.parent / "problems"
console = Console(highlight=False, width=None if sys.stdout.isatty() else 132)
err_console = Console(stderr=True, highlight=False)


def rule_table(rules: list[dict], title: str) -> Table:
    table = Table(title=escape(title), title_justify="left")
    for col, just in (("rule", "left"), ("value", "right"), ("limit", "right"), ("unit", "left"),
                      ("margin", "right"), ("", "left"), ("where / why", "left")):
        table.add_column(col, justify=just, no_wrap=col != "where / why")
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
    Write a spec file (TOML; see problems/ for examples), then:
      agrisynth check SPEC    evaluate the spec's design against every rule
      agrisynth solve SPEC    optimise the spec's free variables (multistart IPOPT)
      agrisynth compare RUN.. compare result folders side by side in one HTML page
      agrisynth bench KIND    compare methods: objective reached against wall time
      agrisynth problems      list the problem library
    Results go to results/<spec name>/ (result.json, report.html, plots).
    Exit codes: 0 all rules satisfied, 1 a rule violated, 2 bad input,
    3 solver failure / infeasible, 130 interrupted.
    """


@cli.command()
@click.option("--dir", "library", type=click.Path(file_okay=False, path_type=Path), default=LIBRARY,
              show_default=True, help="problem library folder")
def problems(library: Path) -> None:
    """List the problem kinds (what each designs, whether it solves) and the problem library:
    kind, name, source of every spec file."""
    from synthesis import kinds
    from synthesis.spec.common import read_toml

    kinds_table = Table(title="kinds", title_justify="left")
    for col in ("kind", "mechanism", "commands", "try"):
        kinds_table.add_column(col)
    for kind in kinds.all_kinds():
        kinds_table.add_row(kind.name, escape(kind.summary), "check, solve" if kind.solves else "check",
                            f"problems/{kind.example}" if kind.example else "")
    console.print(kinds_table)
    table = Table(title=f"problem library: {library}", title_justify="left")
    for col in ("kind", "name", "file", "source"):
        table.add_column(col)
    for path in sorted(library.rglob("*.toml")):
        data, _ = read_toml(path)
        table.add_row(str(data.get("kind", "?")), str(data.get("name", "?")),
                      str(path.relative_to(library)), str(data.get("source", "")))
    console.print(table)


@cli.command()
@click.argument("spec", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out", type=click.Path(file_okay=False, path_type=Path), default=Path("results"),
              show_default=True, help="output folder; the run writes OUT/<spec name>/")
def check(spec: Path, out: Path) -> None:
    """Evaluate SPEC's given design against its rules (no optimisation).

    Prints the rule table (value, limit, margin, pass/fail) and writes OUT/<name>/result.json,
    report.html and the trajectory plot. Exit 0 when every rule holds, 1 when one is violated.
    """
    from synthesis import kinds
    from synthesis.report import run_artifacts
    from synthesis.result import write_run
    from synthesis.spec import load_spec

    loaded = load_spec(spec)
    result = kinds.checker(loaded.kind)(loaded)
    artifacts = run_artifacts(result)
    folder, replaced = write_run(out, result, artifacts)
    console.print(rule_table(result.rules, f"{result.name} ({result.kind}): {loaded.path}"))
    if replaced:
        console.print(f"replaced the previous run in {folder}/")
    console.print(f"wrote {folder}/: {', '.join(sorted(f.name for f in folder.iterdir()))}")
    bad = result.violated()
    if bad:
        console.print(f"[bold red]{len(bad)} rule(s) violated:[/] {', '.join(r['name'] for r in bad)}")
        sys.exit(1)
    console.print("[green]every rule satisfied[/]")


def comparison_table(best: list[dict], baseline: list[dict] | None, title: str) -> Table:
    table = Table(title=escape(title), title_justify="left")
    for col, just in (("rule", "left"), ("limit", "right"), ("baseline", "right"), ("", "left"),
                      ("solution", "right"), ("", "left"), ("unit", "left")):
        table.add_column(col, justify=just, no_wrap=True)
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


class _SolveCommand(click.Command):
    """`solve --help` lists every kind's objectives from the registry, read only when help is asked for
    (so an ordinary run imports no other kind's package)."""

    def format_help(self, ctx, formatter):
        self.help = self.help.replace("{objectives}", _objectives_help())
        super().format_help(ctx, formatter)



@cli.command(cls=_SolveCommand)
@click.argument("spec", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=Path("results"), show_default=True,
              help="output folder; the run writes OUT/<spec name>/")
@click.option("--starts", type=click.IntRange(min=1), default=None,
              help="multistart starts (default: the spec's [solver] starts); start 0 is the spec's design")
@click.option("--seed", type=click.IntRange(min=0), default=None,
              help="seed of the Latin-hypercube starts (default: the spec's [solver] seed)")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="parallel worker processes (default: all cores)")
@click.option("--scheduler", default=None, metavar="ADDR",
              help="run the starts on a dask.distributed cluster (scheduler address, e.g. tcp://host:8786; "
                   "the workers need agrisynth installed) instead of local worker processes")
@click.option("--verbose", is_flag=True, help="print IPOPT's output (always kept in OUT/<name>/ipopt.log)")
def solve(spec: Path, out: Path, starts: int | None, seed: int | None, workers: int | None,
          scheduler: str | None, verbose: bool) -> None:
    """Optimise SPEC's free design variables so every rule holds (CasADi + IPOPT, exact derivatives).

    \b
    Every rule is a constraint; the objective is the spec's [objective] name, by kind
    (the first is the default):
    {objectives}
    Starts are a fixed-seed Latin hypercube (start 0 = the given design). Every start is
    re-checked on a 10x finer grid, independently of the solver; the best is the feasible one
    with the best objective (ties: the lower start). Status: optimal (every rule holds and
    IPOPT met its tolerances), feasible (every rule holds; IPOPT stopped otherwise: a note
    says how), infeasible (an elastic re-solve converged and names the rules that conflict),
    failed (anything else: the message says what to try). Writes OUT/<name>/result.json,
    report.html, ipopt.log and plots. Exit 0 all rules hold; 3 infeasible or failed; 2 bad
    input (also: nothing free to optimise, or a check-only kind).
    """
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from synthesis import kinds
    from synthesis.core import solve as core
    from synthesis.core.executor import default_workers
    from synthesis.report import run_artifacts
    from synthesis.report.tables import objective_text
    from synthesis.result import atomic_write_text, write_run
    from synthesis.spec import load_spec

    if scheduler is not None and workers is not None:
        raise click.BadParameter("give either --workers (local processes) or --scheduler (a dask cluster), "
                                 "not both", param_hint="--workers/--scheduler")
    loaded = load_spec(spec)
    kind = kinds.solving_kind(loaded.kind)
    workers = workers or default_workers()
    n = starts or loaded.model.solver.starts
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                  TextColumn("{task.fields[best]}"), TimeElapsedColumn(), console=console,
                  transient=not sys.stdout.isatty()) as progress:
        task = progress.add_task(f"solving {loaded.name}", total=n, best="")

        def on_start(report, best) -> None:
            tag = "feasible" if best.satisfied else f"worst violation {best.worst_violation:.3g}"
            progress.update(task, advance=1, best=f"best: start {best.outcome.start}, "
                                                  f"objective {best.outcome.objective:.6g} ({tag})")

        result, reports, log = core.run_solve(kind, loaded, starts, seed, workers, on_start, scheduler)
    if verbose:
        console.print(log, markup=False)
    artifacts = run_artifacts(result, {"ipopt.log": lambda path: atomic_write_text(path, log)})
    folder, replaced = write_run(out, result, artifacts)
    baseline = core.baseline_rules(kind, loaded)
    console.print(comparison_table(result.rules, baseline, f"{result.name}: baseline (given design) vs solution"))
    s = result.solver
    console.print(f"objective {objective_text(result.objective)}; IPOPT "
                  f"{s['return_status']} in {s['iterations']} iterations; best of {s['starts']} starts "
                  f"(seed {s['seed']}) is start {s['best_start']}; {s['wall_s']:.2f} s on "
                  f"{f'the cluster at {scheduler}' if scheduler else f'{workers} worker(s)'}; status {result.status}")
    if replaced:
        console.print(f"replaced the previous run in {folder}/")
    console.print(f"wrote {folder}/: {', '.join(sorted(f.name for f in folder.iterdir()))}")
    if s["status_note"]:
        console.print(f"[yellow]note:[/] {escape(s['status_note'])}")
    if result.status in ("infeasible", "failed"):
        raise core.exit_error(kind, result, reports)
    bad = result.violated()
    if bad:
        console.print(f"[bold red]{len(bad)} rule(s) violated:[/] {', '.join(r['name'] for r in bad)}")
        sys.exit(1)
    console.print("[green]every rule satisfied on the fine grid[/]")


@cli.command()
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=Path("results/compare"),
              show_default=True, help="folder for compare.html and its figures")
def compare(results: tuple[Path, ...], out: Path) -> None:
    """Compare RESULT... (run folders or result.json files of one kind) side by side.

    \b
    The first RESULT is the baseline.  Writes OUT/compare.html, one self-contained page that
    works offline, with its figures beside it:
      rules    value, limit and margin per candidate; violated rules in red; the tightest
               rule of each candidate on the first line
      design   every variable, one column per candidate, differences from the baseline marked
      figures  the kind's overlays (paths, speeds and accelerations, linkage, animation)
      run      solver status, iterations, wall time, starts, seed, versions, spec hash
    A RESULT that is an `agrisynth bench` output (OUT/bench or its bench.json) adds the
    error-against-run-time plot and table.  Nothing is re-solved: the page is built from
    the result files alone.
    \b
    Example:
      agrisynth check problems/planting_arm/taiwan_example1.toml
      agrisynth solve problems/planting_arm/redesign_from_example1.toml
      agrisynth compare results/taiwan_example1 results/redesign_from_example1
    """
    from synthesis.compare import is_bench, load_bench, load_candidates, write_comparison

    bench = [res for p in results if is_bench(p) for res in load_bench(p)]
    cands = load_candidates([p for p in results if not is_bench(p)])
    page = write_comparison(cands, out, bench)
    for c in cands:
        bad = c.result.violated()
        verdict = "[green]every rule satisfied[/]" if not bad else f"[red]{len(bad)} rule(s) violated[/]"
        console.print(f"{escape(c.label)}: {c.result.status}, {verdict}")
    console.print(f"wrote {page}")


@cli.command()
@click.argument("problems", nargs=-1, metavar="[PROBLEM]...")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=Path("results"), show_default=True,
              help="output folder; the bench writes OUT/bench/bench.json and OUT/bench/error_vs_time.png")
@click.option("--repeats", type=click.IntRange(min=1), default=5, show_default=True,
              help="runs of each method on each problem; the table shows the median wall time")
def bench(problems: tuple[str, ...], out: Path, repeats: int) -> None:
    """Compare methods on the same problems: objective reached and median wall time, side by side.

    \b
    PROBLEM is a kind name (its default bench set) or a spec file; none = every kind's default set.
    Kinds with a bench: fourbar_path (IPOPT multistart vs scipy differential_evolution).
    Both methods stop at the same target objective (best known + tolerance). Every result is
    re-checked on the fine grid (worst rule violation). Writes OUT/bench/bench.json and
    OUT/bench/error_vs_time.png (log-log: objective gap and violation against wall time).
    \b
    Examples:
      agrisynth bench fourbar_path
      agrisynth bench problems/fourbar_path/picking_arc.toml --repeats 3 --out /tmp/b
    """
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from synthesis import bench as benchmod
    from synthesis.spec import KINDS, load_spec

    known = benchmod.kinds_with_bench()
    by_kind: dict[str, list | None] = {}
    for item in problems or tuple(known):
        if item in known:
            by_kind[item] = None
        elif item in KINDS:
            raise click.BadParameter(f"kind {item!r} has no bench cases (kinds with a bench: {', '.join(known)})",
                                     param_hint="PROBLEM")
        elif item.endswith(".toml") or Path(item).exists():
            loaded = load_spec(item)
            if loaded.kind not in known:
                raise click.BadParameter(f"{item}: kind {loaded.kind!r} has no bench cases "
                                         f"(kinds with a bench: {', '.join(known)})", param_hint="PROBLEM")
            if by_kind.get(loaded.kind, []) is not None:
                by_kind.setdefault(loaded.kind, []).append(loaded)
        else:
            raise click.BadParameter(f"{item!r} is neither a kind with a bench ({', '.join(known)}) nor a spec file",
                                     param_hint="PROBLEM")
    cases = [case for kind, specs in by_kind.items() for case in benchmod.cases_for(kind, specs, 0)]
    total = sum(len(c.methods) * repeats + (1 if callable(c.best_known) else 0) for c in cases)
    results = []
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=console, transient=not sys.stdout.isatty()) as progress:
        task = progress.add_task("bench", total=total)
        for case in cases:
            def tick(what: str | None) -> None:
                if what is None:
                    progress.advance(task)
                else:
                    progress.update(task, description=what)

            results.append(benchmod.run_case(case, repeats, tick))
    settings = {"repeats": repeats, "problems": [c.problem for c in cases]}
    folder = benchmod.write_bench(out, results, settings)
    console.print(bench_table(results, repeats))
    console.print(f"wrote {folder}/bench.json, error_vs_time.png")


def bench_table(results: list[dict], repeats: int) -> Table:
    table = Table(title=f"bench: objective reached and median wall time of {repeats} runs", title_justify="left")
    for col, just in (("problem", "left"), ("method", "left"), ("objective", "right"), ("gap to best", "right"),
                      ("worst violation", "right"), ("median s", "right"), ("time ratio", "right")):
        table.add_column(col, justify=just, no_wrap=True)
    for res in results:
        for row in res["rows"]:
            table.add_row(escape(row["problem"]), escape(row["method"]), f"{row['objective']:.4g}",
                          f"{row['objective_gap']:.3g}", f"{row['worst_violation']:.3g}", f"{row['median_s']:.3f}",
                          escape(row["time_ratio_text"]))
    return table


def main() -> None:
    try:
        cli.main(standalone_mode=False)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.ClickException as exc:
        exc.show()
        sys.exit(2)
    except click.exceptions.Abort:
        err_console.print("interrupted")
        sys.exit(130)
    except KeyboardInterrupt:
        err_console.print("interrupted")
        sys.exit(130)
    except AgrisynthError as exc:
        err_console.print(f"[bold red]error:[/] {escape(str(exc))}", markup=True, soft_wrap=True)
        sys.exit(exc.exit_code)


if __name__ == "__main__":
    main()
