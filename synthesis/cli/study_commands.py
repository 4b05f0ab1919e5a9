"""``agrisynth tolerance``, ``bench`` and ``compare``: options to a request, the run's events and answer printed."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import click
from rich.markup import escape

from synthesis import runs
from synthesis.cli.options import ANGLE_HALF_WIDTH, FORCE_HELP, LENGTH_HALF_WIDTH, NamedPath, WholeNumber
from synthesis.cli.terminal import print_table
from synthesis.cli.views import Terminal, bench_table, console
from synthesis.errors import SpecError
from synthesis.runs.requests import BadRequest, BenchRequest, CompareRequest, ToleranceRequest
from synthesis.tolerance.output import table as tolerance_table


def per_variable_tolerances(tols: tuple[str, ...]) -> dict[str, float]:
    """--tol NAME=VALUE ... as {name: half-width}; a malformed, non-finite or non-positive value is bad input."""
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


@click.command("tolerance")
@click.argument("target", metavar="RESULT|SPEC", type=click.Path(path_type=Path))
@click.option("--out", type=NamedPath(file_okay=False, path_type=Path), default=Path("results"), show_default=True,
              help="writes OUT/<name>-tolerance/")
@click.option("--length", type=LENGTH_HALF_WIDTH, default=None, help="half-width for every length, mm (0 to 1000)")
@click.option("--angle", type=ANGLE_HALF_WIDTH, default=None, help="half-width for every angle, deg (0 to 90)")
@click.option("--tol", "tols", multiple=True, metavar="NAME=VALUE",
              help="half-width for one design variable, in its own unit (repeatable; over --length/--angle and the "
                   "spec's [tolerance] entry of that variable)")
@click.option("--samples", type=WholeNumber(min=0, max=1_000_000), default=None,
              help="Monte-Carlo samples (default the spec's [tolerance] samples, else 1000)")
@click.option("--seed", type=WholeNumber(min=0, max=2**53), default=None, help="Monte-Carlo seed (default 0)")
@click.option("--force", is_flag=True, help=FORCE_HELP.replace("OUT/<name>/", "OUT/<name>-tolerance/"))
def tolerance_command(target: Path, out: Path, length: float | None, angle: float | None, tols: tuple[str, ...],
                      samples: int | None, seed: int | None, force: bool) -> None:
    """Exact sensitivities, linear tolerance stack-up and a seeded Monte-Carlo of a design.

    RESULT: a run folder (its solved.toml is the design); SPEC: the spec's given design.  Tolerances
    from the spec's [tolerance] table, each value of which --length/--angle (every length / angle) and
    --tol NAME=VALUE (one variable) replace.  Writes OUT/<name>-tolerance/ (result.json, report.md, tornado.png).
    Derivatives w.r.t. the operating conditions (forward speed, crank speed, friction, ...) are always
    listed; with an operating range each Monte-Carlo sample is re-checked at every point of the range's
    re-check grid and passes only if every rule holds at all of them.
    Exit 0 when the design and every Monte-Carlo sample pass every rule, 1 otherwise; with --samples 0
    (sensitivities and the linear stack-up only) exit 0 when the design passes every rule and every linear worst
    case holds, 1 otherwise; with --samples 0 and no half-width (the sensitivities alone: report.md tables each
    rule's derivatives) exit 0 when the design passes every rule.  With a box each rule is re-checked at its linear
    worst corner, a design in the box: missed there, it fails.
    result.json holds these verdicts as rule rows (<rule>@monte_carlo: the share of samples holding the rule;
    <rule>@tolerance: the linear worst margin; <rule>@linear_worst_corner: the rule missed at that corner), so
    `agrisynth compare` shows them; a failed run prints the rows that failed.
    """
    request = ToleranceRequest(target, out, length, angle, per_variable_tolerances(tols), samples, seed, force)
    with Terminal() as terminal:
        outcome = runs.tolerance(request, terminal)
    facts, failed = outcome.details.facts, outcome.details.failed
    console.print(escape(tolerance_table(facts)))
    console.print(f"wrote {escape(str(outcome.folder))}/")
    if failed:      # say which rows decide it: a table of 100 % passes may still hold a corner that breaks a rule
        console.print("failed: " + "; ".join(escape(f"{r['name']} ({r['note']})" if r.get("note") else r["name"])
                                             for r in failed), soft_wrap=True)
    if outcome.exit_code:
        sys.exit(outcome.exit_code)


@click.command("compare")
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=False, path_type=Path))
@click.option("--out", type=NamedPath(file_okay=False, path_type=Path), default=None,
              help="folder for compare.html and its figures (an agrisynth output folder) [default: "
                   "results/compare/<RESULT folder names joined by _vs_>, one per comparison]")
@click.option("--force", is_flag=True, help="replace OUT when it holds an earlier agrisynth output (without --force "
                                            "it is kept and the command exits 2; a folder agrisynth did not write "
                                            "is never replaced)")
def compare_command(results: tuple[Path, ...], out: Path | None, force: bool) -> None:
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
    with Terminal() as terminal:
        compared = runs.compare(CompareRequest(results, out, force), terminal).details
    for c in compared.candidates:
        bad = c.result.violated()
        verdict = "[green]every rule satisfied[/]" if not bad else f"[red]{len(bad)} rule(s) violated[/]"
        console.print(f"{escape(c.label)}: {c.result.status}, {verdict}")
    console.print(f"wrote {escape(str(compared.page))}")


@click.command("bench")
@click.argument("problems", nargs=-1, metavar="[PROBLEM]...")
@click.option("--problems", "spec_files", multiple=True, type=click.Path(dir_okay=False, path_type=Path),
              metavar="SPEC", help="a spec file to bench, or a library spec by name (repeatable; instead of its "
                                   "kind's default set)")
@click.option("--out", type=NamedPath(file_okay=False, path_type=Path), default=Path("results"), show_default=True,
              help="output folder; the bench writes OUT/bench/ (bench.json, bench.md, plots)")
@click.option("--repeats", type=WholeNumber(min=1), default=None,
              help="runs of each IPOPT method per problem (median wall time) [default: 3; --quick: 1]")
@click.option("--quick", is_flag=True, help="1 start, 1 run, sample counts x 0.5 and x 1, no peers, no reference "
                                            "solve, no extreme matrix, the first problem of each kind (a kind with "
                                            "its own bench set: the generic studies only); about 1 minute on 2 cores")
@click.option("--no-extreme", is_flag=True, help="leave out the extreme-case matrix (tests/extreme/)")
@click.option("--force", is_flag=True, help="replace OUT/bench/ when it holds an earlier agrisynth bench (without "
                                            "--force it is kept and the command exits 2 before benching; a folder "
                                            "agrisynth did not write is never replaced)")
@click.option("--compiled", is_flag=True,
              help="add the method ipopt_compiled to every problem's generic studies: the IPOPT multistart with the "
                   "NLP's functions and exact derivatives compiled to C (as `solve --compiled`: libraries in "
                   "OUT/.compiled/, compiled in the untimed warm-up, which then takes seconds to minutes), timed "
                   "against the interpreted one")
def bench_command(problems: tuple[str, ...], spec_files: tuple[Path, ...], out: Path, repeats: int | None,
                  quick: bool, no_extreme: bool, force: bool, compiled: bool) -> None:
    """Error against run time for every kind that solves, side by side in one run.

    \b
    PROBLEM is a kind name (its default bench set: library redesigns) or a spec file (a library
    spec as `agrisynth problems` lists it, where no such file is here); none: every kind that solves.
    Per problem: IPOPT multistart with exact (CasADi) derivatives against the same NLP with
    finite differences and a limited-memory Hessian, scipy SLSQP and differential_evolution
    (each timed to the first moment it reaches the target: best known + tolerance, every rule on the
    fine grid; "target not reached" otherwise, and ratios only of those times); the sample-count sweep (time, iterations, fine-grid violation, objective gap);
    build against solve time; kind studies (planting: seed 000's difference scheme); and the
    extreme-case matrix of tests/extreme/ (a source tree's; with no PROBLEM and without --quick).  Writes OUT/bench/bench.json, bench.md,
    error_vs_time.png (log-log: objective gap and violation against wall time; `agrisynth compare ... OUT/bench`
    shows it beside runs) and samples_<problem>.png (bench.md shows them).
    \b
    Examples:
      agrisynth bench --quick
      agrisynth bench KIND [KIND ...]       (the kinds `agrisynth problems` lists)
      agrisynth bench --problems problems/planting_arm/redesign_from_example1.toml
    """
    request = BenchRequest(problems, spec_files, out, repeats, quick, no_extreme, force, compiled)
    try:
        with Terminal() as terminal:
            outcome = runs.bench(request, terminal)
    except BadRequest as exc:
        raise click.BadParameter(str(exc), param_hint=exc.field) from None
    except KeyboardInterrupt:
        # a bench is written whole or not at all: its finished problems are not kept (unlike a solve's starts)
        sys.stderr.write("bench: nothing written (a bench keeps no partial result; bench fewer problems at a time "
                         "with --problems SPEC)\n")
        raise
    rows = outcome.details
    print_table(console, bench_table(rows.results, rows.repeats))
    console.print(f"wrote {escape(str(outcome.folder))}/bench.json, bench.md and plots ({rows.settings['wall_s']:.0f} s)")
