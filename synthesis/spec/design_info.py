"""What a spec says of each design variable: where it is written (TOML path), its unit, its bounds, free or fixed.

Read from the spec model alone, for every kind the same way: a spec model lists its variables by their
result.json names (``variables()``: name -> a number or a free variable ``{init, bounds}``).  The TOML
path of a variable is found by walking the model to the very object ``variables()`` returned.

Reports and the terminal show units, bounds, free/fixed and at-bound marks from it; ``solved.toml``
writes the solved value of each free variable at its path.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel

from synthesis.spec.common import ACUTE, NON_NEGATIVE, POSITIVE, FreeVariable
from synthesis.spec.docmeta import units_in

#: a value within this fraction of its bounds' width (at least this absolute, mm or deg) is "at the bound"
AT_BOUND = 1e-6


def walk_fields(model: BaseModel, prefix: str = ""):
    """(TOML path, FieldInfo, value) of every value in the model, depth first (list items as path[i])."""
    for name, field in type(model).model_fields.items():
        key = field.alias or name
        value = getattr(model, name)
        path = f"{prefix}{key}"
        yield path, field, value
        if isinstance(value, BaseModel) and not isinstance(value, FreeVariable):
            yield from walk_fields(value, f"{path}.")
        elif isinstance(value, (list, tuple)):
            yield from _walk_items(value, path, field)


def _walk_items(items, path: str, field):
    """The items of a list (and of lists in it, e.g. a path's control points ``spline.control[3][0]``)."""
    for i, item in enumerate(items):
        yield f"{path}[{i}]", field, item
        if isinstance(item, BaseModel) and not isinstance(item, FreeVariable):
            yield from walk_fields(item, f"{path}[{i}].")
        elif isinstance(item, (list, tuple)):
            yield from _walk_items(item, f"{path}[{i}]", field)


def _entry(path: str | None, field, bounds, free: bool) -> dict[str, Any]:
    units = units_in(field.description) if field is not None else []
    return {"path": path, "unit": " or ".join(units), "bounds": None if bounds is None else [float(b) for b in bounds],
            "free": free}


def describe(spec: BaseModel) -> dict[str, dict[str, Any]]:
    """design name -> {path, unit, bounds, free}; empty when the model declares no variables."""
    out: dict[str, dict[str, Any]] = {}
    variables = getattr(spec, "variables", None)
    if callable(variables):
        where = {id(value): (path, field) for path, field, value in walk_fields(spec)}
        for name, v in variables().items():
            path, field = where.get(id(v), (None, None))
            if isinstance(v, FreeVariable):
                out[name] = _entry(path, field, v.bounds, True)
            elif isinstance(v, (int, float)) and not isinstance(v, bool):
                out[name] = _entry(path, field, None, False)
    return out


def _positive(field) -> bool:
    """A field the spec takes only > 0: marked :data:`~synthesis.spec.common.POSITIVE` (a number or a free variable,
    checked by a validator) or a number with a bound gt >= 0 (pydantic's ``Field(gt=0)``)."""
    return field.json_schema_extra == POSITIVE or any(
        getattr(m, "gt", None) is not None and m.gt >= 0 for m in field.metadata)


def positive_variables(spec: BaseModel) -> set[str]:
    """The design variables whose spec field takes only values > 0 (a link length, a radius, a speed): no design of
    the kind has one at or below zero."""
    return _marked(spec, _positive)


def acute_variables(spec: BaseModel) -> set[str]:
    """The design variables whose spec field is marked 0 < angle < 90 deg (:data:`~synthesis.spec.common.ACUTE`)."""
    return _marked(spec, lambda field: field.json_schema_extra == ACUTE)


def non_negative_variables(spec: BaseModel) -> set[str]:
    """The design variables whose spec field is marked >= 0 (:data:`~synthesis.spec.common.NON_NEGATIVE`: a cam's
    dwell, which may be none but never less)."""
    return _marked(spec, lambda field: field.json_schema_extra == NON_NEGATIVE)


def _marked(spec: BaseModel, test) -> set[str]:
    variables = getattr(spec, "variables", None)
    if not callable(variables):
        return set()
    field_of = {id(value): field for _, field, value in walk_fields(spec)}
    return {name for name, v in variables().items() if (field := field_of.get(id(v))) is not None and test(field)}


def _fields_by_path(spec: BaseModel) -> dict:
    """TOML path -> FieldInfo of every value in the model (:func:`walk_fields`)."""
    return {path: field for path, field, _ in walk_fields(spec)}


def describe_lists(spec: BaseModel) -> dict[str, dict[str, Any]]:
    """design name -> {path, unit, bounds (None), free} of the list-valued design values a spec declares
    (``list_variables()``: name -> (TOML path, free); the crank angle of each target).  Apart from describe(): a
    list has no single value for solved.toml's or the envelope's walk."""
    lists = getattr(spec, "list_variables", None)
    if not callable(lists):
        return {}
    fields = _fields_by_path(spec)
    return {name: _entry(path, fields.get(path), None, free) for name, (path, free) in lists().items()}


def describe_choices(spec: BaseModel) -> dict[str, dict[str, Any]]:
    """design name -> {path, unit "-", bounds None, free False} of the discrete choices a spec's design holds beside
    its variables (``choice_variables()``: name -> TOML path; an assembly branch +1 / -1): result.json's design
    writes them, so a reader finds each design value's path and unit here.  Never a variable to move or tolerance."""
    choices = getattr(spec, "choice_variables", None)
    if not callable(choices):
        return {}
    return {name: {"path": path, "unit": "-", "bounds": None, "free": False} for name, path in choices().items()}


def describe_part(prefix: str, spec: BaseModel, file: str) -> dict[str, dict[str, Any]]:
    """describe() of a spec another spec names (the combined picker's drive and linkage): each name prefixed
    (``<prefix>.l7``), each path one in that part's file, named under ``file``."""
    return {f"{prefix}.{name}": {**entry, "file": file}
            for name, entry in {**describe(spec), **describe_choices(spec)}.items()}


def describe_fixed(spec: BaseModel, paths: dict[str, str]) -> dict[str, dict[str, Any]]:
    """design name -> entry of a fixed number the spec holds at a TOML path (the picker's installation angles),
    its unit from that field's description."""
    fields = _fields_by_path(spec)
    return {name: _entry(path, fields.get(path), None, False) for name, path in paths.items()}


def attach(result, spec: BaseModel):
    """``result`` told what its spec says of each design variable (result.json ``design_variables``); a kind
    whose spec declares none may have described its design itself (the combined picker, from its parts' specs)."""
    result.design_variables = ({**describe(spec), **describe_lists(spec), **describe_choices(spec)}
                               or result.design_variables or None)
    return result


def at_bound(value, info: dict | None) -> str:
    """"lower" or "upper" when a free variable's value sits on that bound, else ""."""
    if not info or not info.get("free") or not info.get("bounds") or not isinstance(value, (int, float)):
        return ""
    lo, hi = info["bounds"]
    tol = AT_BOUND * max(1.0, abs(hi - lo))
    if abs(value - lo) <= tol:
        return "lower"
    if abs(value - hi) <= tol:
        return "upper"
    return ""


def units_of(spec: BaseModel, names) -> list[str]:
    """The declared unit of each design variable in ``names`` (a kind's NLP declares its x with them)."""
    info = describe(spec)
    return [info[n]["unit"] for n in names]
