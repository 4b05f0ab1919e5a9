"""The registry: the one list of problem kinds.  Each entry points at the ``KIND`` object its package
exports (:class:`synthesis.core.kind.Kind`); nothing of a kind is imported until it is asked for, and
a kind's object holds only ``"module:attribute"`` strings, so listing kinds imports no kind's code.

Adding a kind: write its package (spec model, check, and for a kind that solves its
:class:`~synthesis.core.kind.Solving`), export ``KIND`` from the package, add one line here.
Tests and tools may add kinds at run time with :func:`register`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from synthesis.core.kind import Kind, resolve
from synthesis.errors import SpecError
from synthesis.result import Result

#: kind name -> "package:KIND"
_REGISTRY: dict[str, str] = {
    "planting_fourbar": "synthesis.kinds.planting:KIND",
    "fourbar_path": "synthesis.kinds.fourbar_path:KIND",
    "crank_rocker": "synthesis.kinds.crank_rocker:KIND",
    "picker_double_crank": "synthesis.kinds.picker:DOUBLE_CRANK",
    "picker": "synthesis.kinds.picker:PICKER",
    "clamp_cam": "synthesis.kinds.clamp_cam:KIND",
    "guide_tube": "synthesis.kinds.guide_tube:KIND",
    "combing_chain": "synthesis.kinds.combing_chain:KIND",
    "comb_finger": "synthesis.kinds.comb_finger:KIND",
    "guide_way": "synthesis.kinds.guide_way:KIND",
    "steering_linkage": "synthesis.kinds.steering_linkage:KIND",
    "tillage_linkage": "synthesis.kinds.tillage_linkage:KIND",
}
_RUNTIME: dict[str, Kind] = {}


def names() -> list[str]:
    return [*_REGISTRY, *(n for n in _RUNTIME if n not in _REGISTRY)]


def get(name: str) -> Kind:
    """The kind's description; SpecError (exit 2) for a name that is not a kind."""
    if name in _RUNTIME:
        return _RUNTIME[name]
    if name not in _REGISTRY:
        raise SpecError(f"unknown kind {name!r} (known kinds: {', '.join(names())})")
    kind = resolve(_REGISTRY[name])
    assert kind.name == name, f"{_REGISTRY[name]} describes {kind.name!r}, registered as {name!r}"
    return kind


def all_kinds() -> list[Kind]:
    return [get(n) for n in names()]


def register(kind: Kind) -> None:
    """Add a kind at run time (e.g. a test's toy kind), through the same contract as the built-in ones."""
    _RUNTIME[kind.name] = kind


def unregister(name: str) -> None:
    _RUNTIME.pop(name, None)


def checker(kind: str) -> Callable:
    return get(kind).checker()


def figure_writers(result: Result) -> dict[str, Callable[[Path], None]]:
    """filename -> writer(path) for the kind's figures and exports of one run."""
    return {fn: (lambda path, f=resolve(t): f(result, path)) for fn, t in get(result.kind).figures.items()}


def compare_figures(kind: str) -> Callable | None:
    """The kind's overlay-figure writer for ``agrisynth compare``, or None if it has none."""
    target = get(kind).compare
    return None if target is None else resolve(target)


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


def explicit_design(loaded, data: dict | None = None) -> tuple:
    """(loaded spec, spec file data) with every design variable written out (see ``Kind.explicit_design``) and
    the spec validated again from that data; both as given for a kind whose specs always hold their whole design.
    ``data``: the spec's data, by default the file's as the run read it (``LoadedSpec.file_data``)."""
    if data is None:
        data = loaded.file_data()
    target = get(loaded.kind).explicit_design
    written = data if target is None else resolve(target)(loaded, data)
    if written is data:
        return loaded, data
    import copy

    from synthesis.spec.common import validate

    return (type(loaded)(validate(type(loaded.model), written, prefix=loaded.kind), loaded.path, loaded.sha256,
                         copy.deepcopy(written)), written)
