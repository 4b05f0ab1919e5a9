"""agrisynth command line: parse, call, map the outcome to an exit code. No maths here.

Exit codes (DESIGN.md): 0 every rule satisfied; 1 some rule violated; 2 bad input; 3 solver
failure or infeasible rule set; 130 interrupted.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click
from rich.console import Console
from rich.table import Table

from synthesis.errors import AgrisynthError

LIBRARY = Path(__file__).resolve().parent.parent / "problems"
console = Console(highlight=False, width=None if sys.stdout.isatty() else 132)
err_console = Console(stderr=True, highlight=False)


def rule_table(rules: list[dict], title: str) -> Table:
    table = Table(title=title, title_justify="left")
    for col, just in (("rule", "left"), ("value", "right"), ("limit", "right"), ("unit", "left"),
                      ("margin", "right"), ("", "left"), ("where / why", "left")):
        table.add_column(col, justify=just, no_wrap=col != "where / why")
    for r in rules:
        lo, hi = r["limit"]
        limit = (f"[{lo:g}, {hi:g}]" if lo is not None and hi is not None else
                 "-" if lo is None and hi is None else f">= {lo:g}" if lo is not None else f"<= {hi:g}")
        value = "-" if r["value"] is None else f"{r['value']:.4g}"
        margin = "-" if r["margin"] is None else f"{r['margin']:.4g}"
        verdict = "[green]pass[/]" if r["satisfied"] else "[bold red]FAIL[/]"
        table.add_row(r["name"], value, limit, r["unit"], margin, verdict, r.get("note") or r.get("where", ""))
    return table


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="agrisynth")
def cli() -> None:
    """Design transplanting and harvesting mechanisms by optimisation.

    \b
    Write a spec file (TOML; see problems/ for examples), then:
      agrisynth check SPEC    evaluate the spec's design against every rule
      agrisynth problems      list the problem library
    Results go to results/<spec name>/ (result.json, report.html, plots).
    Exit codes: 0 all rules satisfied, 1 a rule violated, 2 bad input,
    3 solver failure / infeasible, 130 interrupted.
    """


@cli.command()
@click.option("--dir", "library", type=click.Path(file_okay=False, path_type=Path), default=LIBRARY,
              show_default=True, help="problem library folder")
def problems(library: Path) -> None:
    """List the problem library: kind, name, source of every spec file."""
    from synthesis.spec.common import read_toml

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
    from synthesis.report import write_report
    from synthesis.result import write_run
    from synthesis.spec import load_spec

    loaded = load_spec(spec)
    result = kinds.checker(loaded.kind)(loaded)
    figures = kinds.figure_writers(result)
    artifacts = dict(figures)
    artifacts["report.html"] = lambda path: write_report(result, path, list(figures))
    folder, replaced = write_run(out, result, artifacts)
    console.print(rule_table(result.rules, f"{result.name} ({result.kind}): {loaded.path}"))
    if replaced:
        console.print(f"replaced the previous run in {folder}/")
    console.print(f"wrote {folder}/result.json, report.html, {', '.join(figures)}")
    bad = result.violated()
    if bad:
        console.print(f"[bold red]{len(bad)} rule(s) violated:[/] {', '.join(r['name'] for r in bad)}")
        sys.exit(1)
    console.print("[green]every rule satisfied[/]")


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
        err_console.print(f"[bold red]error:[/] {exc}", markup=True, soft_wrap=True)
        sys.exit(exc.exit_code)


if __name__ == "__main__":
    main()
