"""What the CLI prints besides the rule tables: the spec reference, the solved design, per-start lines.

Tables fit the terminal: on a terminal rich wraps the long columns to its width; piped, a run's tables are
folded to a readable width (:func:`table_width`: $COLUMNS, else 120 characters) and nothing is ever cut (a long
cell continues on the next line of its cell).  Text lines are never wrapped when piped.
"""

from __future__ import annotations

import math
import os
import sys
import textwrap

from rich.console import Console
from rich.markup import escape
from rich.table import Table

#: piped output: wide enough that no line of text is wrapped (lines are as long as their content)
PIPED_WIDTH = 10_000
#: piped output: the width a run's tables are folded to when $COLUMNS does not say one
PIPED_TABLE_WIDTH = 120


def table_width(stream=None) -> int | None:
    """The width a table is printed at: the terminal's (None: rich measures it); piped, $COLUMNS when it is a
    positive whole number, else :data:`PIPED_TABLE_WIDTH` (a table of notes was 300 characters wide and more)."""
    if (stream or sys.stdout).isatty():
        return None
    columns = os.environ.get("COLUMNS", "")
    return int(columns) if columns.isdigit() and int(columns) > 0 else PIPED_TABLE_WIDTH


def print_table(console: Console, table: Table) -> None:
    """``table`` on ``console`` at :func:`table_width` (a long cell folds within its column, never cut)."""
    console.print(table, width=table_width(console.file))


def wrapped(text: str, width: int, indent: int) -> str:
    """``text`` folded to ``width`` at spaces, every line indented by ``indent``; a word longer than a line (a file
    name) is kept whole on a line of its own, never cut."""
    pad = " " * indent
    return textwrap.fill(text, width=width, initial_indent=pad, subsequent_indent=pad, break_long_words=False,
                         break_on_hyphens=False)


def console_for(stream=None, *, stderr: bool = False) -> Console:
    """A console as wide as the terminal, or, when piped, wide enough never to cut or wrap a cell."""
    stream = stream or (sys.stderr if stderr else sys.stdout)
    tty = stream.isatty()
    return Console(file=stream if stream not in (sys.stdout, sys.stderr) else None, stderr=stderr,
                   highlight=False, width=None if tty else PIPED_WIDTH, soft_wrap=not tty)


def add_columns(table: Table, columns) -> Table:
    """Columns (heading, justify) that fold instead of cutting: on a terminal narrower than the table a
    long cell (a file name, a number) continues on the next line of its cell, never ends in "..."."""
    for heading, justify in columns:
        table.add_column(heading, justify=justify, overflow="fold")
    return table


def plain_table(title: str | None = None) -> Table:
    """A table that never cuts a cell: overflowing text folds onto the next line of its cell on a terminal,
    and a piped console is wide enough for every line."""
    return Table(title=escape(title) if title else None, title_justify="left")


def reference_table(kind_name: str, summary: str, rows) -> Table:
    """``agrisynth spec KIND``: every field with TOML path, type, unit, default (or required), range, meaning."""
    table = plain_table(f"{kind_name}: {summary}")
    add_columns(table, [(col, "left") for col in ("TOML path", "type", "unit", "default", "range", "description")])
    for e in rows:
        if e.section:
            table.add_row(f"[bold]{escape(e.heading)}[/]", "", "", "required" if e.required else escape(e.default),
                          escape(e.range), f"[bold]{escape(e.description)}[/]")
        else:
            table.add_row(escape(e.path), escape(e.type), escape(e.unit),
                          "required" if e.required else escape(e.default), escape(e.range), escape(e.description))
    return table


def _value(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:.6g}" if math.isfinite(v) else str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return str(v)


def design_table(rows, title: str, solved: str = "solved") -> Table:
    """The solved design beside the given one: value, unit, bounds, free/fixed and at-bound marks
    (rows: :func:`synthesis.report.tables.design_rows`); ``solved``: the answer's column heading.  The marks'
    column is there only when a variable is at a bound (it was an empty last column otherwise)."""
    table = plain_table(title)
    marks = [r.at_bound[0] if r.at_bound else "" for r in rows]
    add_columns(table, (("variable", "left"), ("given (start 0)", "right"), (solved, "right"), ("unit", "left"),
                        ("bounds", "right"), *((("", "left"),) if any(marks) else ())))
    for r, mark in zip(rows, marks):
        bounds = {None: "", False: "fixed"}.get(r.free, f"[{_value(r.bounds[0])}, {_value(r.bounds[1])}]"
                                                 if r.bounds else "free")
        table.add_row(escape(r.name), escape(_value(r.given)), escape(_value(r.values[0])), escape(r.unit),
                      escape(bounds), *((f"[yellow]at {mark} bound[/]" if mark else "",) if any(marks) else ()))
    return table
