"""``agrisynth problems`` and ``agrisynth spec``: the kinds and the problem library listed or copied out, a kind's
spec reference or a starting spec of it."""

from __future__ import annotations

from pathlib import Path

import click
from rich.markup import escape
from rich.table import Table

from synthesis import kinds
from synthesis.cli.options import FileTarget
from synthesis.cli import terminal
from synthesis.cli.views import console
from synthesis.library import LIBRARY
from synthesis.runs import library
from synthesis.spec import reference as specref
from synthesis.spec.common import usable_name


@click.command("problems")
@click.option("--dir", "library_dir", type=click.Path(exists=True, file_okay=False, path_type=Path), default=LIBRARY,
              show_default=True, help="problem library folder")
@click.option("--copy", "name", metavar="NAME", default=None,
              help="copy the library spec NAME (its file as listed, e.g. planting_arm/taiwan_example1.toml, or its "
                   "file name alone) into the working folder to edit it, with the spec files it names")
@click.option("--out", "target", type=FileTarget(path_type=Path), default=None,
              help="with --copy: the file (or folder) to write [default: the spec's file name, here]")
@click.option("--force", is_flag=True, help="with --copy: replace a file of that name (without it an existing "
                                            "file is kept and the command exits 2)")
def problems_command(library_dir: Path, name: str | None, target: Path | None, force: bool) -> None:
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
        list_library(library_dir)
        return
    source, copied = library.copy_spec(name, library_dir, target, force)
    written, original = copied.files, copied.library_name
    also = f" (and {', '.join(escape(str(p)) for p in written[1:])}, the spec files it names)" if written[1:] else ""
    renamed = (f", named {escape(copied.name)} (its runs: results/{escape(copied.name)}/ and "
               f"results/{escape(copied.name)}-check/)" if copied.name != original else "")
    if target is not None and copied.name == original and written[0].stem != original and not usable_name(written[0].stem):
        # the file's name is no spec name: the copy's runs would be the library spec's own folders
        renamed = (f"; its name stays {escape(str(original))} ({escape(written[0].stem)!r} is no spec name: letters, "
                   f"digits, _ . -, not compare, bench or studio, not ending in -check or -tolerance): edit its name "
                   f"line to give its runs their own folders")
    console.print(f"wrote {escape(str(written[0]))}{also}: a copy of the library's "
                  f"{escape(source.relative_to(library_dir).as_posix())} to edit{renamed}; check it with "
                  f"agrisynth check {escape(str(written[0]))}", soft_wrap=True)



def list_library(library_dir: Path) -> None:
    width = terminal.table_width(console.file)
    if width is not None:           # piped: a line per entry, folded at the width, every file name whole
        _list_piped(library_dir, width)
        return
    kinds_table = terminal.add_columns(Table(title="kinds", title_justify="left"),
                                       [(col, "left") for col in ("kind", "mechanism", "commands", "try")])
    for kind, summary, commands, example in library.kind_rows():
        kinds_table.add_row(kind, escape(summary), commands, example)
    console.print(kinds_table)
    table = terminal.add_columns(Table(title=f"problem library: {library_dir}", title_justify="left"),
                                 [(col, "left") for col in ("kind", "name", "file", "source")])
    for entry in library.library_entries(library_dir):
        table.add_row(escape(entry.kind), escape(entry.name), escape(entry.file), escape(entry.unread or entry.source))
    console.print(table)
    console.print(escape(_how_to_use(library_dir)), soft_wrap=True)


def _how_to_use(library_dir: Path) -> str:
    """The listing's last line: a spec named as listed is looked up in the built-in library only, so a listing of
    another folder (``--dir``) names its specs by their path."""
    if library_dir.resolve() == LIBRARY.resolve():
        return ("check or solve one by its file as listed (agrisynth check planting_arm/taiwan_example1.toml); "
                "copy one to edit: agrisynth problems --copy FILE")
    return (f"check or solve one by its path (agrisynth check {library_dir / 'FILE'}); copy one to edit: "
            f"agrisynth problems --dir {library_dir} --copy FILE")


def _list_piped(library_dir: Path, width: int) -> None:
    lines = ["kinds"]
    for kind, summary, commands, example in library.kind_rows():
        lines += [terminal.wrapped(f"{kind} ({commands}): {summary}", width, 2),
                  terminal.wrapped(f"try: {example}", width, 6)]
    lines += ["", f"problem library: {library_dir}"]
    for entry in library.library_entries(library_dir):
        lines += [terminal.wrapped(f"{entry.file}  [{entry.kind}] {entry.name}", width, 2),
                  terminal.wrapped(entry.unread or entry.source, width, 6)]
    lines += ["", terminal.wrapped(_how_to_use(library_dir), width, 0)]
    click.echo("\n".join(lines))


def _reference_piped(kind: str, summary: str, entries, width: int) -> None:
    lines = [terminal.wrapped(f"{kind}: {summary}", width, 0),
             "  TOML path | type | unit | default | range, then what it means"]
    for e in entries:
        default = "required" if e.required else e.default
        head = e.heading if e.section else e.path
        # a type's alternatives read "or" here: " | " separates the columns (integer | "auto" shifted them)
        kind_of = "" if e.section else e.type.replace(" | ", " or ")
        fields = " | ".join(x for x in (head, kind_of, e.unit, default, e.range))
        lines += [terminal.wrapped(fields, width, 2), terminal.wrapped(e.description, width, 6)]
    click.echo("\n".join(lines))


@click.command("spec")
@click.argument("kind")
@click.option("--template", is_flag=True, help="write a commented starting spec of KIND (the library example's "
                                               "values, every field described) instead of the reference")
@click.option("--out", "target", type=FileTarget(dir_okay=False, path_type=Path), default=None,
              help="with --template: write it to this new file, the spec files it names (the picker's two "
                   "linkages) copied beside it (default: print it, naming the library's own spec files)")
def spec_command(kind: str, template: bool, target: Path | None) -> None:
    """The spec reference of KIND: every field with its TOML path, type, unit, default (or
    "required"), allowed range and meaning.  Every kind's in one file: docs/specs.md in the source tree.

    \b
    Examples (KIND: a name `agrisynth problems` lists):
      agrisynth spec KIND
      agrisynth spec KIND --template --out my_design.toml && agrisynth check my_design.toml
    """
    description = kinds.get(kind)           # SpecError (exit 2) naming the known kinds
    if target is not None and not template:
        raise click.BadParameter("--out writes a template: give --template too", param_hint="--out")
    if not template:
        width = terminal.table_width()
        if width is not None:       # piped: a field per entry, folded at the width, nothing cut
            _reference_piped(kind, description.summary, specref.kind_entries(kind), width)
            return
        terminal.console_for().print(terminal.reference_table(kind, description.summary, specref.kind_entries(kind)))
        return
    if target is None:
        click.echo(specref.template(kind), nl=False)
        return
    written = library.write_template(kind, target)
    beside = (f" (and the spec files it names beside it: {', '.join(escape(str(p)) for p in written[1:])})"
              if written[1:] else "")
    console.print(f"wrote {escape(str(target))}{beside}: a {kind} spec to edit; check it with  agrisynth check "
                  f"{escape(str(target))}", soft_wrap=True)
