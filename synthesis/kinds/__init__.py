"""The registry of problem kinds: one folder each under ``synthesis/kinds/``, and any other package's kinds.

A built-in kind is a folder here whose package exports ``KIND`` (or ``KINDS``, a folder holding two): instances of
:class:`synthesis.core.kind.Kind`; a kind's name starts with its folder's name (``planting_fourbar`` in
``planting/``), so that asking for one kind imports no other's package.  The folders are the list -- adding a kind adds a folder and touches nothing else.
Another installed package adds kinds through the ``agrisynth.kinds`` entry-point group (each entry a Kind instance,
named by its kind).  Listing kinds imports each kind's package ``__init__`` (its class and names) and nothing more:
a kind's check, NLP and figures are imported by its methods when called.  Tests may add kinds at run time with
:func:`register`.
"""

from __future__ import annotations

import copy
import difflib
import functools
import importlib
import pkgutil
import warnings
from importlib.metadata import entry_points
from pathlib import Path
from typing import Callable

from synthesis.core.kind import Kind
from synthesis.errors import SpecError
from synthesis.result import Result

#: the entry-point group through which other packages add kinds
ENTRY_POINT_GROUP = "agrisynth.kinds"
_RUNTIME: dict[str, Kind] = {}


def _exported(module) -> tuple[Kind, ...]:
    kinds = getattr(module, "KINDS", None) or (getattr(module, "KIND", None),)
    if not all(isinstance(k, Kind) for k in kinds):
        raise TypeError(f"{module.__name__} exports no Kind instance as KIND or KINDS")
    return tuple(kinds)


def _folders() -> list[str]:
    """The kind folders under synthesis/kinds/, by name (nothing imported)."""
    return sorted(info.name for info in pkgutil.iter_modules(__path__) if info.ispkg)


@functools.cache
def _folder(folder: str) -> dict[str, Kind]:
    """The kinds one folder's package exports."""
    return {kind.name: kind for kind in _exported(importlib.import_module(f"{__name__}.{folder}"))}


@functools.cache
def _built_in() -> dict[str, Kind]:
    """The kinds of every folder under synthesis/kinds/, in folder order."""
    found: dict[str, Kind] = {}
    for folder in _folders():
        for name, kind in _folder(folder).items():
            assert name not in found, f"two built-in kinds named {name!r}"
            found[name] = kind
    return found


def _own_folder(name: str) -> Kind | None:
    """The kind from the folder its name starts with (planting_fourbar in planting/), importing no other kind's
    package: a run of one kind imports nothing of another.  None when no such folder holds it."""
    for folder in sorted((f for f in _folders() if name == f or name.startswith(f + "_")), key=len, reverse=True):
        kind = _folder(folder).get(name)
        if kind is not None:
            return kind
    return None


@functools.cache
def _installed() -> dict[str, Kind]:
    """The kinds other installed packages add through the entry-point group.  A plugin that cannot be loaded or that
    reuses a built-in kind's name is left out with a warning naming it: one broken plugin does not stop the tool."""
    found: dict[str, Kind] = {}
    for point in entry_points(group=ENTRY_POINT_GROUP):
        try:
            kind = point.load()
            kind = kind() if isinstance(kind, type) and issubclass(kind, Kind) else kind
            if not isinstance(kind, Kind) or kind.name != point.name:
                raise TypeError(f"{point.value} is not a Kind named {point.name!r}")
        except Exception as exc:            # a plugin's own error, whatever it is: reported, not raised
            warnings.warn(f"agrisynth kind plugin {point.name!r} ({point.value}) not loaded: {exc}", stacklevel=2)
            continue
        if kind.name in _built_in():
            warnings.warn(f"agrisynth kind plugin {point.value} not loaded: {kind.name!r} is a built-in kind",
                          stacklevel=2)
            continue
        found[kind.name] = kind
    return found


def names() -> list[str]:
    everything = {**_built_in(), **_installed()}
    return [*everything, *(n for n in _RUNTIME if n not in everything)]


def get(name: str) -> Kind:
    """The kind; SpecError (exit 2) for a name that is not a kind."""
    kind = _RUNTIME.get(name) or _own_folder(str(name)) or _built_in().get(name) or _installed().get(name)
    if kind is None:
        near = difflib.get_close_matches(str(name), names(), n=1)
        hint = f"did you mean {near[0]}? " if near else ""
        raise SpecError(f"unknown kind {name!r} ({hint}known kinds: {', '.join(names())})")
    return kind


def all_kinds() -> list[Kind]:
    return [get(n) for n in names()]


def register(kind: Kind) -> None:
    """Add a kind at run time (e.g. a test's toy kind), through the same contract as the built-in ones."""
    _RUNTIME[kind.name] = kind


def unregister(name: str) -> None:
    _RUNTIME.pop(name, None)


def checker(kind: str) -> Callable:
    return get(kind).check


def figure_writers(result: Result) -> dict[str, Callable[[Path], None]]:
    """filename -> writer(path) for the kind's figures and exports of one run."""
    return {fn: functools.partial(writer, result) for fn, writer in get(result.kind).figures().items()}


def compare_figures(kind: str) -> Callable | None:
    """The kind's overlay-figure writer for ``agrisynth compare``, or None if it has none."""
    return get(kind).compare_figures()


def solving_kind(name: str) -> Kind:
    """The kind, if it solves; SpecError (exit 2) naming the kinds that do otherwise."""
    kind = get(name)
    if not kind.solves:
        solvable = [k.name for k in all_kinds() if k.solves]
        raise SpecError(f"kind {name!r} has nothing to optimise (`agrisynth check` evaluates it); "
                        f"kinds that solve: {', '.join(solvable)}")
    return kind


def solving_kind_for(loaded) -> Kind:
    """The kind that solves a loaded spec: its own, or -- when the spec has a ``[tolerance]`` table -- the
    same kind holding every rule at its linearised worst case in the box (synthesis.tolerance.robust)."""
    kind = solving_kind(loaded.kind)
    from synthesis.spec.operating import ranges_of

    if ranges_of(loaded.model):
        from synthesis.tolerance.envelope import envelope_kind

        kind = envelope_kind(kind, loaded.model)
    if getattr(loaded.model, "tolerance", None) is None:
        return kind
    from synthesis.tolerance.robust import robust_kind

    return robust_kind(kind, loaded.model)


def solve_spec(loaded, starts: int | None = None, seed: int | None = None, workers: int = 1,
               on_start: Callable = lambda report, best: None, scheduler: str | None = None) -> tuple:
    """:func:`synthesis.core.solve.run_solve` of the loaded spec's own kind, as :func:`solving_kind_for` gives it
    (SpecError, exit 2, for a check-only kind): (result, every start's report, IPOPT log)."""
    from synthesis.core.solve import run_solve      # listing kinds imports no solve core

    return run_solve(solving_kind_for(loaded), loaded, starts, seed, workers, on_start, scheduler)


def explicit_design(loaded, data: dict | None = None) -> tuple:
    """(loaded spec, spec file data) with every design variable written out (see ``Kind.explicit_design``) and
    the spec validated again from that data; both as given for a kind whose specs always hold their whole design.
    ``data``: the spec's data, by default the file's as the run read it (``LoadedSpec.file_data``)."""
    if data is None:
        data = loaded.file_data()
    written = get(loaded.kind).explicit_design(loaded, data)
    if written is data:
        return loaded, data
    from synthesis.spec.common import validate      # synthesis.spec imports this registry

    return (type(loaded)(validate(type(loaded.model), written, prefix=loaded.kind), loaded.path, loaded.sha256,
                         copy.deepcopy(written)), written)
