"""Reading the spec a run is asked for: the file (or the library's spec of that name), its notes, the design
variables it may name, and the description reports show of each variable."""

from __future__ import annotations

import os
from pathlib import Path

from synthesis import kinds
from synthesis.core.kind import own_half_width_refused
from synthesis.errors import AgrisynthError, AssemblyError, SpecError
from synthesis.library import LIBRARY, library_spec
from synthesis.runs.events import Note, SpecFromLibrary, Subscriber
from synthesis.spec import design_info, load_spec
from synthesis.spec.plausibility import unit_notes


def spec_file(spec: Path, emit: Subscriber) -> Path:
    """SPEC as given, when there is such a file (or the library has no spec of that name either: reading it says
    so); otherwise the library spec it names (planting_arm/taiwan_example1.toml, problems/... as the README
    writes it, or a file name the library has once), told as :class:`SpecFromLibrary`."""
    if os.path.lexists(spec):
        return spec
    found = library_spec(spec)
    if found is None:
        return spec
    emit(SpecFromLibrary(spec, found.relative_to(LIBRARY).as_posix(), found))
    return found


def followers_named(kind_name: str, names: list[str], where: str) -> None:
    """SpecError for a half-width given to a variable the kind holds to others (:attr:`Kind.follows`: a cam's near
    dwell closes the turn): the box moves it with them, so it takes none of its own."""
    follows = kinds.get(kind_name).follows
    named = [n for n in names if n in follows]
    if named:
        raise SpecError(f"{where}: {own_half_width_refused(named[0], follows[named[0]])}")


def unknown_design_variables(model, names: list[str], where: str) -> None:
    """SpecError naming those of ``names`` that are no design variable of the spec by its result.json name (not a
    suffix of one, as the kind's NLP may name it: ``I`` for ``delta_I``, ``x`` for ``seedbed_x`` -- the robust
    solve's box takes the full names alone, so every command takes those alone); nothing is said of a kind that
    declares none."""
    info = design_info.describe(model)
    unknown = [n for n in names if n not in info]
    if info and unknown:
        raise SpecError(f"{where}: unknown design variable {', '.join(unknown)} (known: {', '.join(info)})")


#: the largest half-width --tol takes by the variable's unit: as --length and --angle take it
TOL_MAX = {"mm": 1e3, "deg": 90.0}


def within_option_ranges(spec, per_variable: dict[str, float], where: str = "--tol {name}={value:g}") -> None:
    """SpecError for a half-width of one variable (--tol, or ``where`` names the spec's field) beyond what --length
    or --angle takes for a variable of its unit (an angle of 100 deg either way spans more than a half turn)."""
    info = design_info.describe(spec)
    for name in per_variable:
        unit = (info.get(name) or {}).get("unit")
        top = TOL_MAX.get(unit) if isinstance(unit, str) else None
        if top is not None and per_variable[name] > top:
            option = "--length" if unit == "mm" else "--angle"
            raise SpecError(f"{where.format(name=name, value=per_variable[name])}: a half-width in {unit} is at "
                            f"most {top:g} (as {option} takes it)")


def tolerance_names_known(loaded, model=None) -> None:
    """A [tolerance] variables entry naming no design variable, or wider than --length / --angle take for its unit,
    is bad input in every command (solve and tolerance refuse it; check ignored it).  ``model``: the spec's
    :func:`named_model` where the caller has it already (a convex fit's seconds, once)."""
    tol = getattr(loaded.model, "tolerance", None)
    if tol is not None and tol.variables:
        model = named_model(loaded) if model is None else model
        unknown_design_variables(model, list(tol.variables), f"{loaded.path}: tolerance.variables")
        followers_named(loaded.kind, list(tol.variables), f"{loaded.path}: tolerance.variables")
        within_option_ranges(model, dict(tol.variables), f"{loaded.path}: tolerance.variables.{{name}} = {{value:g}}")


def named_model(loaded):
    """The spec model whose design variables are result.json's: with the part a kind leaves to itself written out
    (guide_way's control points of the convex fit, ``Kind.explicit_design``), as a run's design_variables list
    them; the loaded model where it cannot be (the error is the run's to say)."""
    if kinds.get(loaded.kind).writes_explicit_design:
        try:
            return kinds.explicit_design(loaded)[0].model
        except (AgrisynthError, OSError):
            pass
    return loaded.model


def zero_tolerance_box(loaded) -> str | None:
    """The spec's [tolerance] fields when it gives no half-width above 0 (``tolerance.length = 0, tolerance.angle =
    0``), else None (no table, or one with a width)."""
    tol = getattr(loaded.model, "tolerance", None)
    if tol is None or tol.length or tol.angle or any(tol.variables.values()):
        return None
    given = [f"tolerance.{what} = 0" for what in ("length", "angle") if getattr(tol, what) == 0]
    return ", ".join(given) if given else "no length, angle or variables"


def refuse_robust_box_outside(loaded) -> None:
    """SpecError when no design a tolerance-robust solve of the spec may try keeps its box inside the range the spec
    holds a variable to (:func:`synthesis.tolerance.design.refuse_box_outside_bounds`)."""
    from synthesis.tolerance.design import refuse_box_outside_bounds   # with casadi: not for the commands that list
    kind = kinds.get(loaded.kind)
    refuse_box_outside_bounds(loaded.model, kind.design_unit, loaded.path, kind.follows)


def not_a_result(spec: Path) -> None:
    """SpecError when SPEC is a run's folder or its result.json (check and solve read a spec file, TOML): said with
    the file that holds a run's design, its solved.toml, where there is one."""
    path = Path(spec)
    folder = path if path.is_dir() else path.parent if path.suffix.lower() == ".json" and path.is_file() else None
    if folder is None:
        return
    solved = folder / "solved.toml"
    what = "a folder" if path.is_dir() else "a JSON file (a run's result?)"
    hint = (f": a solve's design is its solved.toml, `agrisynth check {solved}`" if solved.is_file()
            else ": give a spec file (TOML)")
    raise SpecError(f"{spec}: {what}, not a spec file{hint}")


def loaded_spec(spec: Path, emit: Subscriber):
    """The spec a check or solve runs on: read, its tolerance names checked, its unit notes told."""
    not_a_result(spec)
    loaded = load_spec(spec_file(spec, emit))
    tolerance_names_known(loaded)
    for note in unit_notes(loaded.model):
        emit(Note(note))
    return loaded


def described(result, loaded):
    """The result, told what the spec says of each design variable (unit, bounds, free): reports show it.  A spec
    that leaves part of its design to the kind (a convex fit of its path's control points) is described with
    that part written out (``Kind.explicit_design``), as solved.toml and the studio write it: every variable the
    solve moved is listed, free, with the box it moved in."""
    return design_info.attach(result, named_model(loaded))


def in_file(loaded, evaluate):
    """``evaluate(loaded)``; a design that cannot be evaluated (AssemblyError) is named with its spec file."""
    try:
        return evaluate(loaded)
    except AssemblyError as exc:
        if str(exc).startswith(str(loaded.path)):
            raise
        raise AssemblyError(f"{loaded.path}: {loaded.kind}: {exc}") from None
