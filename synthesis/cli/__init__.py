"""agrisynth command line: parse, call the run (:mod:`synthesis.runs`), draw its events and map the outcome to an
exit code.  No maths here.

Exit codes (docs/ARCHITECTURE.md, "Exit codes"): 0 every rule satisfied; 1 some rule violated; 2 bad input;
3 solver failure or infeasible rule set; 130 interrupted by Ctrl-C, 143 by SIGTERM.

Each command lives in its own module, imported only when that command runs or shows its help
(``agrisynth --help`` imports neither casadi nor matplotlib): :data:`COMMANDS`.
"""

from __future__ import annotations

import difflib
import importlib
import sys
from typing import NoReturn

import click

from synthesis.core import interrupt
from synthesis.errors import AgrisynthError

#: command -> (the module defining it, its one-line help for ``agrisynth --help``: tests/test_cli_check.py holds it
#: equal to the command's own)
COMMANDS = {
    "bench": ("synthesis.cli.study_commands", "Error against run time for every kind that solves, side by side in "
                                              "one run."),
    "check": ("synthesis.cli.run_commands", "Evaluate SPEC's given design against its rules (no optimisation)."),
    "compare": ("synthesis.cli.study_commands", "Compare RESULT..."),
    "problems": ("synthesis.cli.library_commands", "List the problem kinds (what each designs, whether it solves) "
                                                   "and the problem library: kind, name, source of every spec file."),
    "solve": ("synthesis.cli.run_commands", "Optimise SPEC's free design variables so every rule holds (CasADi + "
                                            "IPOPT, exact derivatives)."),
    "spec": ("synthesis.cli.library_commands", "The spec reference of KIND: every field with its TOML path, type, "
                                               "unit, default (or \"required\"), allowed range and meaning."),
    "studio": ("synthesis.cli.studio_command", "An interactive design page for SPEC, served on 127.0.0.1 only "
                                               "(needs the `studio` extra)."),
    "tolerance": ("synthesis.cli.study_commands", "Exact sensitivities, linear tolerance stack-up and a seeded "
                                                  "Monte-Carlo of a design."),
}
#: click's context object while :func:`main` runs agrisynth as a program that ends with the command (a caller of
#: main in process -- a test -- restores the signal handlers itself: :func:`interrupt.ignore` left them ignored)
PROGRAM = "agrisynth program"


class _LazyGroup(click.Group):
    """A group whose commands are imported when one is run or its help asked for (:data:`COMMANDS`)."""

    def list_commands(self, ctx) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx, name: str):
        if name not in COMMANDS:
            return None
        module = importlib.import_module(COMMANDS[name][0])
        return getattr(module, f"{name}_command")

    def resolve_command(self, ctx, args):
        # a misspelt command gets the nearest ones, as a misspelt spec field does
        if args and args[0] not in COMMANDS and not args[0].startswith("-") and not ctx.resilient_parsing:
            close = difflib.get_close_matches(args[0], sorted(COMMANDS), n=2, cutoff=0.6)
            if close:
                ctx.fail(f"No such command '{args[0]}'; did you mean {' or '.join(repr(c) for c in close)}?")
        return super().resolve_command(ctx, args)

    def format_commands(self, ctx, formatter) -> None:
        limit = formatter.width - 6 - max(len(name) for name in COMMANDS)
        rows = [(name, click.utils.make_default_short_help(COMMANDS[name][1], limit)) for name in sorted(COMMANDS)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


@click.group(cls=_LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
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
      agrisynth tolerance RESULT|SPEC  sensitivities, tolerance stack-up, Monte-Carlo check of a design
      agrisynth studio SPEC   an interactive design page on 127.0.0.1 (the studio extra)
    Results go to results/<spec name>/ for solve, results/<spec name>-check/ for check
    (result.json, report.html, plots): check, solve, compare, check solved.toml need no --force.
    Exit codes: 0 all rules satisfied, 1 a rule violated, 2 bad input,
    3 solver failure / infeasible, 130 interrupted (Ctrl-C), 143 stopped (SIGTERM).
    """


def ends_process() -> bool:
    """Whether the running command is the last thing its process does (run by :func:`main`)."""
    ctx = click.get_current_context(silent=True)
    return ctx is not None and ctx.find_root().obj == PROGRAM


def main() -> None:
    try:
        cli.main(standalone_mode=False, prog_name="agrisynth", obj=PROGRAM)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.UsageError as exc:
        if type(exc).__name__ != "NoArgsIsHelpError":       # click >= 8.2: a bare command asks for its help
            _usage_error(exc)
        # `agrisynth` (or a group) alone: its help, as --help prints it, not "error: Usage: ..."
        click.echo(exc.ctx.get_help() if exc.ctx is not None else exc.format_message())
        sys.exit(0)
    except click.ClickException as exc:
        _usage_error(exc)
    except (click.exceptions.Abort, KeyboardInterrupt) as exc:
        _interrupted(interrupt.signal_of(exc))
    except (SystemError, ImportError) as exc:
        # a signal that fired inside a C callback (SystemError) or a C extension's initialisation (an import the
        # command makes: ImportError "initialization failed"): an interruption
        if not (interrupt.caused_by_signal(exc) or isinstance(exc, ImportError) and interrupt.pending() is not None):
            raise
        _interrupted(interrupt.signal_of(exc))
    except AgrisynthError as exc:
        _say_error(str(exc))
        sys.exit(exc.exit_code)
    except Exception:
        # a signal's KeyboardInterrupt raised inside a CasADi call comes out as another exception (NotImplementedError:
        # "wrong number or type of arguments"): with a signal noted, the run was interrupted, not broken
        if interrupt.pending() is None:
            raise
        _interrupted(interrupt.pending())


def _usage_error(exc: click.ClickException) -> NoReturn:
    # one line, like every other bad input (click's own form is three: Usage, Try, Error)
    ctx = getattr(exc, "ctx", None)
    hint = f" (see `{ctx.command_path} --help`)" if isinstance(exc, click.UsageError) and ctx is not None else ""
    _say_error(f"{exc.format_message()}{hint}")
    sys.exit(2)


def _say_error(message: str) -> None:
    """"error: <message>" on standard error, one line (red on a terminal)."""
    # rich only now: `agrisynth --help` and a command's own output do not wait for it (a command's views import it)
    from rich.console import Console
    from rich.markup import escape

    Console(stderr=True, highlight=False).print(f"[bold red]error:[/] {escape(message)}", markup=True, soft_wrap=True)


def _interrupted(signum: int) -> None:
    sys.stderr.write("interrupted\n")
    sys.stderr.flush()
    sys.exit(128 + signum)
