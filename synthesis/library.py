"""Where the problem library is: the folder of published designs and redesigns (``agrisynth problems``).

The library is package data of ``synthesis`` (``synthesis/problems/``) and is found through
``importlib.resources``, so an installed wheel and a source checkout (editable or on PYTHONPATH) find it the
same way.  In a checkout the folder itself stays at the top, ``problems/`` (the paths the README, the docs
and the tests name), and ``synthesis/problems`` is a relative symbolic link to it; building a wheel copies
the files the link reaches into the package (pyproject.toml: ``[tool.setuptools.package-data]``).

This module is the one place that says where agrisynth's own files are: the library, the folder the
running package was imported from, and the source checkout when there is one (its tests, its docs).
"""

from __future__ import annotations

import difflib
import glob
import os
import re
import tomllib
from importlib.resources import files
from pathlib import Path, PurePosixPath
from typing import NamedTuple

from synthesis.errors import OutputError, SpecError
from synthesis.result import atomic_write_drawn
from synthesis.spec import load_spec
from synthesis.spec.common import usable_name
from synthesis.spec.design_info import walk_fields
from synthesis.spec.docmeta import SpecFile

#: the folder the running ``synthesis`` package was imported from: site-packages for an installed copy, the
#: checkout's root for an editable install or a checkout on PYTHONPATH
IMPORT_ROOT = Path(str(files("synthesis"))).resolve().parent


def _library_root() -> Path:
    packaged = Path(str(files("synthesis") / "problems"))
    if packaged.is_dir():                   # a wheel's copy, or the checkout's link to problems/
        return packaged.resolve()           # resolved: a checkout's paths read problems/..., as the README's do
    # a checkout on a file system that keeps no symbolic links (git on Windows without core.symlinks writes the
    # link as a small text file): the folder the link names
    return IMPORT_ROOT / "problems"


#: the problem library's root folder: one folder per mechanism, one TOML spec per problem, and our reading of
#: each paper (the markdown file beside the specs)
LIBRARY = _library_root()

#: how the README and the docs name a library spec: problems/<mechanism>/<spec>.toml
PREFIX = "problems/"


def checkout() -> Path | None:
    """The source checkout this agrisynth runs from (the root holding ``pyproject.toml`` and ``tests/``), or None
    for an installed copy (a wheel ships neither its tests nor its docs)."""
    pyproject = IMPORT_ROOT / "pyproject.toml"
    try:
        if (IMPORT_ROOT / "tests").is_dir() and 'name = "agrisynth"' in pyproject.read_text(encoding="utf-8"):
            return IMPORT_ROOT
    except (OSError, UnicodeDecodeError):
        pass
    return None


def library_names(library: Path = LIBRARY) -> list[str]:
    """Every spec of the library by its library name (``planting_arm/taiwan_example1.toml``), sorted."""
    return sorted(p.relative_to(library).as_posix() for p in library.rglob("*.toml") if p.is_file())


def library_spec(name: str | Path, library: Path = LIBRARY) -> Path | None:
    """The library spec ``name`` names, or None.  A name is the spec's path inside the library
    (``planting_arm/taiwan_example1.toml``), with or without ``.toml``, with or without the leading
    ``problems/`` the README writes, or the file's bare stem where one library spec alone has it
    (``taiwan_example1``).  A name that would leave the library (``..``, an absolute path) names nothing."""
    text = str(name).replace("\\", "/")
    if not text or len(text) > 300:
        return None
    text = text.removeprefix("./").removeprefix(PREFIX)
    relative = PurePosixPath(text if text.endswith(".toml") else f"{text}.toml")
    if relative.is_absolute() or ".." in relative.parts:
        return None
    candidate = library / relative
    if candidate.is_file():
        return candidate
    if len(relative.parts) == 1:            # a bare name: the one spec of that file name anywhere in the library
        found = [p for p in library.rglob(glob.escape(relative.name)) if p.is_file()]
        if len(found) == 1:
            return found[0]
    return None


def unknown_name_text(name: str | Path, library: Path = LIBRARY) -> str:
    """The one-line message for a name no library spec has: the closest library names, and where to list them."""
    text = str(name).replace("\\", "/").removeprefix("./").removeprefix(PREFIX)
    names = library_names(library)
    stems = {n: n.removesuffix(".toml") for n in names}
    close = difflib.get_close_matches(text.removesuffix(".toml"), list(stems.values()), n=3, cutoff=0.6)
    close += [s for s in stems.values() if s.rsplit("/", 1)[-1] == text.removesuffix(".toml") and s not in close]
    hint = f"; did you mean {', '.join(f'{c}.toml' for c in close[:3])}?" if close else ""
    return f"{str(name)[:120]}: no such library spec{hint} (`agrisynth problems` lists all {len(names)})"


class Copied(NamedTuple):
    """What :func:`copy_out` wrote: the files (the spec first), the copy's ``name`` and the library spec's."""

    files: list[Path]
    name: str
    library_name: str


def copy_out(source: Path, target: Path, *, force: bool = False, rename: bool = False) -> Copied:
    """Copy the library spec ``source`` to the file ``target`` (a folder: the spec's own file name in it), to be
    edited there, with the spec files it names (the combined picker's two linkages) beside it at the same relative
    paths, so the copy checks as the library spec does.  The files are copied byte for byte (comments kept), but for
    the ``name`` line of a copy the user named anew (``rename``).

    OutputError (exit 2, before anything is written) when a file to write exists and ``force`` is not given, when
    it is a library file itself, or when the folder to write in does not exist.  ``rename``: the copy's ``name`` is
    its file name's stem (:func:`with_name`)."""
    target = Path(target)
    if target.is_dir():
        target = target / source.name
    plan = [(source, target)]
    names = []
    for spec, copy in plan:                 # grows as it goes: a named spec file may name others
        model = load_spec(spec).model
        names.append(str(getattr(model, "name", "")))
        for _, info, value in walk_fields(model):
            if not (isinstance(value, str) and any(isinstance(m, SpecFile) for m in info.metadata)):
                continue
            relative = PurePosixPath(value.replace("\\", "/"))
            if relative.is_absolute() or ".." in relative.parts:
                raise SpecError(f"{spec}: names the spec file {value!r} outside its own folder: copy it by hand")
            named = spec.parent / relative
            if named not in [s for s, _ in plan]:
                plan.append((named, copy.parent / relative))
    if not target.parent.is_dir():
        raise OutputError(f"{target}: no folder {target.parent} to write it in")
    # one file however its name is cased (a case-blind disk: macOS, Windows)
    written = [os.path.normcase(os.path.abspath(copy)).casefold() for _, copy in plan]
    for k, ((spec, copy), where) in enumerate(zip(plan, written)):
        if where in written[:k]:            # the copy named as a file it names: one would replace the other
            other = plan[written.index(where)][0]
            raise OutputError(f"{copy}: {other.name} and the spec file it names, {spec.name}, would be copied to this "
                              f"one file; give --out another file name")
    for spec, copy in plan:
        if os.path.lexists(copy):
            if copy.exists() and os.path.samefile(copy, spec):
                raise OutputError(f"{copy} is the library's own file: copy it to another folder")
            if not force:
                raise OutputError(f"{copy}: already exists; give --force to replace it, or --out another file")
            if copy.is_dir() or copy.is_symlink():
                raise OutputError(f"{copy}: is a {'folder' if copy.is_dir() else 'link'}; agrisynth replaces only "
                                  f"a file")
    name = names[0]
    for k, (spec, copy) in enumerate(plan):
        copy.parent.mkdir(parents=True, exist_ok=True)      # a named spec file in a subfolder of the copy's
        data = spec.read_bytes()
        if k == 0 and rename and copy.stem != source.stem:      # the user named the copy anew
            renamed = with_name(data, copy.stem)
            name = copy.stem if renamed != data else name
            data = renamed
        write_new_file(copy, lambda tmp, data=data: tmp.write_bytes(data))
    return Copied([copy for _, copy in plan], name, names[0])


def write_new_file(path: Path, draw) -> None:
    """``atomic_write_drawn`` of a file the user named (a copy, a template): a folder the system will not let us write
    in (/proc, a read-only disk) is an OutputError in one line (exit 2), not the temporary file's traceback."""
    try:
        atomic_write_drawn(path, draw)
    except OSError as exc:
        raise OutputError(f"{path}: cannot be written there ({exc.strerror or exc})") from None


#: a spec's top-level ``name = "..."`` line (before any table)
_NAME_LINE = re.compile(rb'^(?P<key>[ \t]*name[ \t]*=[ \t]*)"(?P<value>[^"\\\n]*)"', re.MULTILINE)


def with_name(data: bytes, name: str) -> bytes:
    """The spec file's bytes with its ``name`` set to ``name`` (a copy written as my_arm.toml runs as my_arm: its
    run folders are the copy's own, not the library spec's), every other byte kept; unchanged when ``name`` is no
    run name or the file does not say its name in one plain line before its first table."""
    if not usable_name(name):
        return data
    first_table = re.search(rb"^[ \t]*\[", data, re.MULTILINE)
    match = _NAME_LINE.search(data, 0, first_table.start() if first_table else len(data))
    if match is None:
        return data
    out = data[:match.start("value")] + name.encode() + data[match.end("value"):]
    try:
        before, after = tomllib.loads(data.decode("utf-8")), tomllib.loads(out.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError):
        return data
    return out if after == {**before, "name": name} else data
