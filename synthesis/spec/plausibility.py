"""Notes on numbers that look like the wrong unit: a spec in metres where mm are meant, an angle's bounds in
radians where degrees are meant.  They are valid input (a 0.2 mm linkage is a linkage), so they are notes printed
beside the result, never errors: the unit of every field is fixed (mm, deg, ...) and written without a unit."""

from __future__ import annotations

import math
from typing import Any, Iterator

from pydantic import BaseModel

from synthesis.spec.common import FreeVariable
from synthesis.spec.docmeta import units_in

#: every length of a spec under this (mm) reads as metres: no mechanism of the library is smaller than 10 mm
TINY_LENGTHS = 1.0
#: a design length under TINY_LENGTHS beside one this many times larger reads as metres among mm
OUT_OF_SCALE = 10.0
#: a free angle whose bounds span less than this (deg), all within one radian turn, reads as radians
NARROW_ANGLE_SPAN = 2.0


def _numbers(value: Any) -> Iterator[float]:
    """The numbers in a field's value: itself, a free variable's init and bounds, the items of lists and pairs."""
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        yield float(value)
    elif isinstance(value, FreeVariable):
        yield from (value.init, *value.bounds)
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _numbers(item)


def fields_with_units(model: BaseModel, prefix: str = "") -> Iterator[tuple[str, str, Any]]:
    """(dotted path, unit, value) of every field of ``model`` whose description names exactly one unit and that the
    spec gives: a default the user never wrote says nothing of the unit they wrote in (a cam in metres kept its
    3 mm default working radius, which hid the note)."""
    for name, field in type(model).model_fields.items():
        value = getattr(model, name, None)
        path = f"{prefix}{name}"
        if isinstance(value, BaseModel) and not isinstance(value, FreeVariable):
            yield from fields_with_units(value, path + ".")
        elif isinstance(value, dict):
            for key, item in value.items():
                if isinstance(item, BaseModel) and not isinstance(item, FreeVariable):
                    yield from fields_with_units(item, f"{path}.{key}.")
        elif isinstance(value, list) and value and all(isinstance(v, BaseModel) for v in value):
            for k, item in enumerate(value):
                yield from fields_with_units(item, f"{path}.{k}.")
        elif name in model.model_fields_set:
            units = units_in(field.description)
            if len(units) == 1:
                yield path, units[0], value


def unit_notes(model: BaseModel) -> list[str]:
    """Notes on the spec's numbers that look like metres for mm or radians for degrees (empty when none do)."""
    notes = []
    fields = list(fields_with_units(model))
    lengths = [(path, v) for path, unit, value in fields if unit == "mm" for v in _numbers(value) if v != 0]
    if len(lengths) >= 2 and max(abs(v) for _, v in lengths) < TINY_LENGTHS:
        path, v = max(lengths, key=lambda pv: abs(pv[1]))
        notes.append(f"every length is under {TINY_LENGTHS:g} mm (the largest, {path}, is {v:g} mm): lengths are in "
                     f"mm; were they given in metres?")
    elif lengths:
        # one link given in metres among lengths in mm (l5 = 0.191): a design's length under 1 mm beside lengths of
        # tens of mm and more is no link of a machine (a tolerance or a back-off of 0.2 mm is no design variable)
        names = set(model.variables()) if hasattr(model, "variables") else set()
        largest = max(abs(v) for _, v in lengths)
        # the value given (a free variable's init): a bound of 0.5 mm is a designer's limit, not a link
        given = [(path, value.init if isinstance(value, FreeVariable) else value) for path, unit, value in fields
                 if unit == "mm" and path.rsplit(".", 1)[-1] in names]
        tiny = [(path, v) for path, v in given
                if isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < abs(v) < TINY_LENGTHS]
        if tiny and largest >= OUT_OF_SCALE * TINY_LENGTHS:
            shown = ", ".join(f"{path} = {v:g}" for path, v in tiny[:3]) + (" ..." if len(tiny) > 3 else "")
            notes.append(f"{shown} mm beside lengths up to {largest:g} mm: lengths are in mm; "
                         f"{'was it' if len(tiny) == 1 else 'were they'} given in metres?")
    for path, unit, value in fields:
        if unit == "deg" and isinstance(value, FreeVariable):
            lo, hi = value.bounds
            if 0 < hi - lo < NARROW_ANGLE_SPAN and max(abs(lo), abs(hi)) <= 2 * math.pi:
                notes.append(f"{path} bounds [{lo:g}, {hi:g}] deg span under {NARROW_ANGLE_SPAN:g} deg: angles are in "
                             f"degrees ([{math.degrees(lo):.4g}, {math.degrees(hi):.4g}] if those were radians)")
    return notes
