"""``problems`` and ``spec --template``: the kinds and the problem library listed, a library spec copied out to
edit, a kind's commented starting spec written."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from synthesis import kinds
from synthesis.errors import OutputError, SpecError
from synthesis.library import Copied, copy_out, library_spec, unknown_name_text, write_new_file
from synthesis.spec import reference
from synthesis.spec.common import read_toml


@dataclass(frozen=True)
class LibraryEntry:
    """One spec file of the library: its kind, name and source, or why it could not be read (``unread``)."""

    file: str
    kind: str = "?"
    name: str = "?"
    source: str = ""
    unread: str | None = None


def kind_rows() -> list[tuple[str, str, str, str]]:
    """(kind, mechanism, commands, example to try) of every kind, read from the registry."""
    return [(kind.name, kind.summary, "check, solve" if kind.solves else "check",
             f"problems/{kind.example}" if kind.example else "") for kind in kinds.all_kinds()]


def library_entries(library: Path) -> list[LibraryEntry]:
    """Every spec file under ``library``, sorted; one unreadable file is an entry saying so, not the end."""
    entries = []
    for path in sorted(library.rglob("*.toml")):
        if not path.is_file():          # a folder named x.toml is no spec
            continue
        file = str(path.relative_to(library))
        try:
            data, _ = read_toml(path)
        except SpecError as exc:
            entries.append(LibraryEntry(file, unread=f"not read: {str(exc).removeprefix(f'{path}: ')}"))
            continue
        entries.append(LibraryEntry(file, str(data.get("kind", "?")), str(data.get("name", "?")),
                                    str(data.get("source", ""))))
    return entries


def copy_spec(name: str, library: Path, target: Path | None, force: bool) -> tuple[Path, Copied]:
    """The library spec NAME copied (with the spec files it names) to ``target`` (default: its file name, here);
    returns (the library's file, what was written)."""
    source = library_spec(name, library)
    if source is None:
        raise SpecError(unknown_name_text(name, library))
    # a copy written under a name of the user's runs under that name (results/my_arm/ of my_arm.toml); the library's
    # own file name keeps the library spec's name
    return source, copy_out(source, Path(source.name) if target is None else target, force=force,
                            rename=target is not None)


def write_template(kind: str, target: Path) -> list[Path]:
    """A commented starting spec of ``kind`` written to the new file ``target`` (a template never replaces one), the
    spec files it names copied beside it (the library example's, to edit; one already there with the library's
    bytes is used as it is, another file of its name is never replaced); returns the files written, the template
    first.  Everything is checked before anything is written, and a write that fails takes back the copies made."""
    if target.exists():
        raise OutputError(f"{target}: already exists; give a new file name (a template never replaces a file)")
    if not target.parent.is_dir():
        raise OutputError(f"{target}: no folder {target.parent} to write it in")
    companions = []
    for source, name in reference.template_companions(kind):
        copy = target.parent / name
        # one file however its name is cased (a case-blind disk: macOS, Windows)
        if os.path.normcase(os.path.abspath(copy)).casefold() == os.path.normcase(os.path.abspath(target)).casefold():
            raise OutputError(f"{target}: the template names a spec file of this name beside it ({source.name}); "
                              f"give the template another name")
        if os.path.lexists(copy):
            if not (copy.is_file() and copy.read_bytes() == source.read_bytes()):
                raise OutputError(f"{copy}: already exists and is not the library's {source.name}, which the "
                                  f"template names there; write the template into another folder")
            continue
        if not copy.parent.is_dir():
            raise OutputError(f"{copy}: no folder {copy.parent} to copy the spec file the template names into")
        companions.append((source, copy))
    text = reference.template(kind, target.parent)
    written: list[Path] = []
    try:
        for source, copy in companions:
            _copy_bytes(source, copy)
            written.append(copy)
        write_new_file(target, lambda tmp: tmp.write_text(text))
    except BaseException:
        for copy in written:          # the copies this call made, not left behind by a template never written
            copy.unlink(missing_ok=True)
        raise
    return [target, *written]


def _copy_bytes(source: Path, copy: Path) -> None:
    """``source`` written to ``copy`` byte for byte, atomically."""
    data = source.read_bytes()

    def write(tmp: Path) -> None:
        tmp.write_bytes(data)
    write_new_file(copy, write)
