"""Markers a spec model may attach to a field for the spec reference (:mod:`synthesis.spec.reference`).

They change nothing in validation; pydantic keeps them in ``FieldInfo.metadata``.
"""

from __future__ import annotations

import re

#: the units of specs (docs/ARCHITECTURE.md, "Units"), longest first so "m/s^2" is not read as "m/s"
UNITS = ("mm/s^2", "m/s^2", "deg/s^2", "mm/s", "m/s", "r/min", "mm^2", "1/mm", "mm", "deg", "s",
         # the [dynamics] tables': the longer unit first where one begins another (N m/rad before N m before N)
         "kg/m^3", "kg m^2", "kg", "N m/rad", "N m", "N/mm", "N", "MPa")
_UNIT = re.compile(r"(?<![\w/^.'-])(" + "|".join(re.escape(u) for u in UNITS) + r")(?![\w/^'-])")


def units_in(description: str | None) -> list[str]:
    """The spec units a field description names, in order, each once; units inside parentheses (asides
    such as "(90 deg counter-clockwise), mm") count only when the rest names none."""
    found: list[str] = []
    outside = re.sub(r"\([^()]*\)", " ", description or "")
    for u in _UNIT.findall(outside) or _UNIT.findall(description or ""):
        if u not in found:
            found.append(u)
    return found


class TomlType(str):
    """How a field is written in TOML, when its Python type says it badly, e.g. a validator that turns a
    number into ``(x, x)``: ``Annotated[tuple[float, float], BeforeValidator(...), TomlType("number or [lo, hi]")]``."""


class SpecFile(str):
    """The field names another spec file, relative to the spec that holds it (a template rewrites it)."""


SPEC_FILE = SpecFile("spec file")
