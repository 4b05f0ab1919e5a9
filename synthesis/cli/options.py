"""The option types and help texts the commands share: whole numbers, half-widths, scheduler addresses."""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import click

FORCE_HELP = ("replace OUT/<name>/ when it holds an earlier agrisynth run (without --force such a run is kept and "
              "the command exits 2 before doing anything; a file or folder agrisynth did not write, also one put "
              "inside such a run, is never replaced or deleted, with or without --force)")

#: a scheduler address agrisynth accepts: tcp://host:port (dask's default protocol) or host:port
SCHEDULER = re.compile(r"^(tcp://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):[0-9]{1,5}$")
MAX_STARTS = 10000
MAX_WORKERS = 256


class WholeNumber(click.IntRange):
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


class StartsCount(WholeNumber):
    """--starts: a whole number of starts, or "auto" (grow until sure: synthesis.core.solve.AutoStarts)."""

    name = "whole number or auto"

    def convert(self, value, param, ctx):
        if isinstance(value, str) and value.strip().lower() == "auto":
            return "auto"
        if isinstance(value, str):
            try:
                int(value)
            except ValueError:
                self.fail(f"{value!r} is neither a whole number ({self._describe_range()}) nor auto", param, ctx)
        return super().convert(value, param, ctx)


class Seconds(click.FloatRange):
    """A time budget in seconds: a finite number > 0."""

    name = "seconds"

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number of seconds", param, ctx)
        return number


class HalfWidth(click.FloatRange):
    """A tolerance half-width: a finite number >= 0 (click's FloatRange lets nan and inf through)."""

    name = "half-width"

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


#: the spec's [tolerance] limits (spec.common.ToleranceSpec): the options take what a spec may say
class NamedPath(click.Path):
    """A path the user names (--out): an empty one is refused, not read as the working folder."""

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not value.strip():
            self.fail("an empty path: give a folder or file name (\".\" for the working folder)", param, ctx)
        return super().convert(value, param, ctx)


class FileTarget(NamedPath):
    """A file the user names to write (--out of `problems --copy` and `spec --template`): a name ending in a path
    separator names a folder, which must exist (``Path`` drops the separator: ``newd/`` would be written as a file
    ``newd``)."""

    def convert(self, value, param, ctx):
        if isinstance(value, str) and value.rstrip() and value.endswith(tuple(s for s in (os.sep, os.altsep) if s)):
            folder = value.rstrip("/" + os.sep + (os.altsep or ""))
            if not Path(folder or value).is_dir():
                self.fail(f"{value}: names a folder (it ends in {value[-1]}) and there is no folder {folder or value}; "
                          f"give a file name (e.g. {value}my_spec.toml) in a folder that exists", param, ctx)
        return super().convert(value, param, ctx)


LENGTH_HALF_WIDTH = HalfWidth(min=0, max=1e3)
ANGLE_HALF_WIDTH = HalfWidth(min=0, max=90)


def scheduler_address(ctx, param, value: str | None) -> str | None:
    """--scheduler: tcp://host:port or host:port, said as tcp://host:port."""
    if value is None:
        return None
    if len(value) > 300 or not SCHEDULER.match(value) or not 0 < int(value.rsplit(":", 1)[1]) < 65536:
        raise click.BadParameter(f"{value[:80]!r} is not a scheduler address: give tcp://host:port "
                                 f"(e.g. tcp://10.0.0.5:8786)")
    return value if value.startswith("tcp://") else f"tcp://{value}"


def objectives_help() -> str:
    """The objectives of every kind that solves, from the registry (one line each, wrapped by hand)."""
    from synthesis import kinds      # the registry: read only when solve's help is asked for

    lines = []
    for kind in kinds.all_kinds():
        if kind.solves:
            lines.append(f"  {kind.name}:")
            lines += [f"    {name}  {meaning}" for name, meaning in kind.objectives.items()]
    return "\n    ".join(lines)
