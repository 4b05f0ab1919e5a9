"""One studio session: a spec, its design variables, and the evaluation of any values of them.

The page sends design values by name only; the session writes them into a copy of the spec file's
data where :mod:`synthesis.spec.design_info` says each variable lives (a free variable's ``init``, or the
``[design]`` table of a kind whose free variables are a ``[bounds]`` table), validates that data with
the kind's spec model and runs the kind's own ``check`` on it: the rule table the page shows is the
one ``agrisynth check`` prints for a spec holding those values.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from synthesis import kinds
from synthesis.spec.design_info import describe, walk_fields
from synthesis.errors import AgrisynthError, SpecError
from synthesis.spec.solved import path_parts, set_at_path     # TOML paths as solved.toml writes them
from synthesis.spec import LoadedSpec, load_spec
from synthesis.spec.common import comment_text, validate
from synthesis.spec.docmeta import SpecFile
from synthesis.spec.operating import ranges_of
from synthesis.spec.reference import write_toml
from synthesis.studio import drawing, grids

def _node(data: Any, path: str) -> Any:
    for part in path_parts(path):
        data = data[part]
    return data


def _finite_number(value: int | float) -> bool:
    """Whether ``value`` is a finite float: JSON's integers have any number of digits, and one beyond a
    float's range (about 309 digits) makes math.isfinite raise OverflowError."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def finite(value: Any) -> Any:
    """``value`` with every NaN or infinity replaced by None (JSON has neither)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    if hasattr(value, "tolist"):            # numpy scalars and arrays
        return finite(value.tolist())
    return value


@dataclass
class Variable:
    """One slider: a design variable the page may move (free) or only show (fixed)."""

    name: str
    value: float
    unit: str
    bounds: tuple[float, float] | None
    free: bool
    path: str | None
    note: str | None = None               # what the page says under a fixed row (default: fixed in the spec)

    @property
    def group(self) -> str | None:
        """The list item holding this variable with others (``spline.control[3]`` for ``spline.control[3][0]``):
        the page shows such variables together, and the items of one list in one scrolling box."""
        if self.path is None or not self.path.endswith("]"):
            return None
        head = self.path[: self.path.rindex("[")]
        return head if head.endswith("]") else None

    def to_json(self) -> dict:
        return finite({"name": self.name, "value": self.value, "unit": self.unit, "free": self.free,
                       "bounds": None if self.bounds is None else list(self.bounds), "group": self.group,
                       **({"note": self.note} if self.note else {})})


def _shown_only(loaded: LoadedSpec) -> list[Variable]:
    """The design a kind without variables of its own evaluates (the combined picker: its drive's and its linkage's,
    read from the spec files it names, and its installation angles), as fixed rows: the page shows them greyed
    and moves none.  Each value and unit as the kind's check reports them (its design_variables)."""
    result = grids.evaluator(loaded.kind, "fine")(loaded)
    described = result.design_variables or {}
    out = []
    for name, value in result.design.items():
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            continue
        unit = (described.get(name) or {}).get("unit", "")
        note = "from the part's spec file (check only)" if "." in name else "fixed in the spec (check only)"
        out.append(Variable(name, float(value), unit, None, False, None, note))
    return out


@dataclass
class Session:
    """The spec the studio was started on, and what the page may do with it."""

    loaded: LoadedSpec
    data: dict[str, Any]                  # the spec file's data with the kind's written-out design (explicit_design)
    variables: list[Variable] = field(default_factory=list)

    @classmethod
    def open(cls, spec_path: Path) -> "Session":
        loaded = load_spec(spec_path)
        # the data of the file load_spec read (not read again: it may have moved on), a design the spec leaves to
        # the kind written out
        loaded, data = kinds.explicit_design(loaded)
        info = describe(loaded.model)
        given = loaded.model.design_values() if hasattr(loaded.model, "design_values") else {}
        variables = []
        for name, value in given.items():       # a kind that declares no variables: all shown fixed
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                continue
            var = info.get(name, {"unit": "", "bounds": None, "free": False, "path": None})
            free = bool(var["free"] and var["bounds"] and var["path"])
            variables.append(Variable(name, float(value), var["unit"], tuple(var["bounds"]) if free else None,
                                      free, var["path"]))
        if not hasattr(loaded.model, "design_values"):
            variables = _shown_only(loaded)
        return cls(loaded, data, variables)

    @property
    def kind(self) -> str:
        return self.loaded.kind

    @property
    def free(self) -> list[Variable]:
        return [v for v in self.variables if v.free]

    def given(self) -> dict[str, float]:
        return {v.name: v.value for v in self.variables}

    # -- values -> spec ---------------------------------------------------------------------------------
    def values_of(self, sent: Any) -> dict[str, float]:
        """The page's values, checked: a dict of finite numbers for free variables, each within its
        bounds; missing ones keep the given value.  SpecError names the first bad one."""
        if not isinstance(sent, dict):
            raise SpecError(f"values: expected an object of design values, got {type(sent).__name__}")
        free = {v.name: v for v in self.free}
        out = self.given()
        for name, value in sent.items():
            if name not in free:
                raise SpecError(f"values.{str(name)[:60]}: not a free design variable of {self.loaded.name} "
                                f"(free: {', '.join(free) or 'none'})")
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not _finite_number(value):
                raise SpecError(f"values.{name}: expected a finite number, got {str(value)[:40]!r}")
            lo, hi = free[name].bounds
            if not lo <= value <= hi:
                # every digit that puts it outside (300 + 1e-9 read "300 lies outside [50, 300]"), bounds too
                raise SpecError(f"values.{name}: {_digits(value)} lies outside its bounds [{_digits(lo)}, "
                                f"{_digits(hi)}]")
            out[name] = float(value)
        return out

    def _other_spec_files(self) -> list[tuple[str, Path]]:
        """(TOML path, file) of every field naming another spec file (relative to the spec that holds it)."""
        return [(path, (self.loaded.path.parent / value).resolve())
                for path, info, value in walk_fields(self.loaded.model)
                if isinstance(value, str) and any(isinstance(m, SpecFile) for m in info.metadata)]

    def spec_data(self, values: dict[str, float], name: str | None = None,
                  folder: Path | None = None) -> dict[str, Any]:
        """The spec file's data with each free variable's start value (what ``check`` evaluates and start
        0 of ``solve``) set to ``values``; named ``name`` when given; written into ``folder`` (not the spec's
        own), the other spec files it names are named relative to that folder."""
        data = copy.deepcopy(self.data)
        if folder is not None:
            for path, target in self._other_spec_files():
                set_at_path(data, path, os.path.relpath(target, folder))
        for var in self.free:
            node = _node(data, var.path)
            if isinstance(node, dict):                      # {init, bounds}: the start value
                node["init"] = values[var.name]
            else:                                           # a [bounds] pair: the [design] table's value
                data.setdefault("design", {})[var.name] = values[var.name]
        if name is not None:
            data["name"] = name
        return data

    def loaded_with(self, values: dict[str, float]) -> LoadedSpec:
        data = self.spec_data(values)
        model = validate(type(self.loaded.model), data, prefix=self.kind)
        digest = hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()
        return LoadedSpec(model, self.loaded.path, digest, copy.deepcopy(data))

    def spec_text(self, values: dict[str, float], name: str, note: str, folder: Path) -> str:
        """A spec file for ``folder`` holding ``values`` as the free variables' start values (bounds kept)."""
        data = self.spec_data(values, name, folder)
        validate(type(self.loaded.model), data, prefix=self.kind)       # never write a spec check refuses
        head = [f"# {comment_text(note)}", f"# from {comment_text(self.loaded.path.name)} (sha256 {self.loaded.sha256})",
                ""]
        return "\n".join(head + write_toml(type(self.loaded.model), data, documented=False)) + "\n"

    # -- evaluation -------------------------------------------------------------------------------------
    def evaluate(self, sent: Any, grid: str = "fine") -> dict[str, Any]:
        """The rule table and the drawing at the page's values, on the coarse or the fine (``check``'s) grid."""
        if grid not in grids.GRIDS:
            raise SpecError(f"grid: expected one of {', '.join(grids.GRIDS)}, got {str(grid)[:20]!r}")
        values = self.values_of(sent)
        began = time.perf_counter()
        try:
            loaded = self.loaded_with(values)
            result = grids.evaluator(self.kind, grid)(loaded)
        except AgrisynthError as exc:        # e.g. a linkage that does not assemble at these values
            # the values at fault are the page's, not the spec file's the message may begin with
            text = str(exc)
            for prefix in (f"{self.loaded.path}: ", f"{self.loaded.path.name}: "):
                if text.startswith(prefix):
                    text = "at the page's values: " + text[len(prefix):]
                    break
            return {"grid": grid, "values": values, "error": text, "rules": [], "drawing": None,
                    "ms": 1e3 * (time.perf_counter() - began)}
        rules = [{k: r.get(k) for k in ("name", "value", "limit", "unit", "margin", "satisfied")}
                 | {"note": r.get("note") or r.get("where") or ""} for r in result.rules]
        return finite({"grid": grid, "grid_note": grids.note(self.kind, grid, self.loaded.model), "values": values, "error": None,
                       "rules": rules, "drawing": drawing.drawing(result), "scope": self.scope(),
                       "ms": 1e3 * (time.perf_counter() - began)})

    def scope(self) -> str:
        """Where the verdict holds: "" everywhere the spec asks, else (an operating range) at its nominal point
        only, as check says it -- a design may fail inside the range (solve re-checks it over the range)."""
        ranged = sorted(ranges_of(self.loaded.model))
        if not ranged:
            return ""
        return (f"at the nominal operating point ({', '.join(ranged)} given as a range: this page evaluates the "
                f"nominal value only; solve re-checks every rule over the range)")

    def describe(self) -> dict[str, Any]:
        return finite({"kind": self.kind, "name": self.loaded.name, "spec": self.loaded.path.name,
                       "variables": [v.to_json() for v in self.variables],
                       "grids": {g: grids.note(self.kind, g, self.loaded.model) for g in grids.GRIDS},
                       "solves": kinds.get(self.kind).solves,
                       "starts": _starts_of(getattr(self.loaded.model, "solver", None))})


def _starts_of(solver) -> int | str:
    """The spec's [solver] starts as the page's box shows them: a count, or "auto" where the spec asks for it."""
    if solver is None:
        return 1
    return "auto" if getattr(solver, "starts_auto", False) else getattr(solver, "starts", 1)


def _digits(x: float) -> str:
    """A number with the digits it has: 42 as "42", 42.000000001 whole (never rounded onto a bound it is not)."""
    return f"{x:g}" if float(f"{x:g}") == x else repr(float(x))
