"""``solved.toml``: a solve's design written as a spec with every design variable fixed.

The spec file as the user wrote it, with each free variable (``{init, bounds}``) replaced by its solved
value (floats written by repr, so they read back bit-identical), a ``[design]`` table's values (the
given design some kinds read, e.g. a path's free-timing crank angles) set to the solution,
and the name ``<name>_solved`` (so checking it never touches the solve's own folder).
``agrisynth check results/<name>/solved.toml`` then evaluates exactly the solved design.

Generic over kinds: where each variable is written comes from :mod:`synthesis.spec.design_info`; a kind whose
spec may leave part of its design to the kind (a path's control points, the convex fit by default) first
writes it out (``Kind.explicit_design``), so the solved values have a place.
"""

from __future__ import annotations

import re
from typing import Any

from pydantic import BaseModel

from synthesis import kinds
from synthesis.core.coordinates import BOUND_TOLERANCE
from synthesis.spec.common import comment_text, derived_name, is_free, validate
from synthesis.spec.design_info import describe
from synthesis.spec.reference import write_toml
from synthesis.errors import SpecError

FILENAME = "solved.toml"
_PART = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def path_parts(path: str) -> list[str | int]:
    """The keys and list indices of a TOML path as design_info writes it: ``arm.l2`` -> ["arm", "l2"],
    ``targets[1].x`` -> ["targets", 1, "x"]."""
    return [int(i) if i else key for key, i in _PART.findall(path)]


def at_path(data: Any, path: str) -> Any:
    """What the TOML ``path`` of ``data`` holds (every container on the way must exist)."""
    for part in path_parts(path):
        data = data[part]
    return data


def set_at_path(data: Any, path: str, value: Any) -> None:
    """Put ``value`` at the TOML ``path`` of ``data`` (every container on the way must exist)."""
    *head, last = path_parts(path)
    for part in head:
        data = data[part]
    data[last] = value


def solved_data(loaded, result) -> dict[str, Any]:
    """The spec file's data with the solved design in place of every free variable."""
    # the file's data as the run read it (not as the file is now), a design the spec left to the kind written out
    loaded, data = kinds.explicit_design(loaded)
    info = describe(loaded.model)
    if not info:
        raise SpecError(f"kind {loaded.kind}: its spec model lists no design variables (variables()), so the "
                        f"solved design cannot be written as a spec")
    bounds_read = set(kinds.get(loaded.kind).bounds_read(loaded.model))
    for name, var in info.items():
        if not var["free"]:
            continue
        if var["path"] is None or name not in result.design:
            raise SpecError(f"kind {loaded.kind}: the free variable {name} has no "
                            f"{'place in the spec file' if var['path'] is None else 'solved value'}")
        value = float(result.design[name])
        # a variable whose bounds the kind reads (a law fitted from them) keeps them, started at its solved value
        set_at_path(data, var["path"], {"init": value, "bounds": list(var["bounds"])} if name in bounds_read else value)
    data["name"] = derived_name(loaded.name, "_solved")
    _given_design(loaded, result, data)
    return data


#: the spec started at the elastic re-solve's design (a run no start of which satisfied every rule)
ELASTIC_FILENAME = "elastic.toml"


def elastic_toml(loaded, result) -> str | None:
    """The spec file with every free variable *started* at the elastic re-solve's design (``result.elastic.design``;
    bounds kept, so ``agrisynth solve`` starts there and ``agrisynth check`` evaluates it), named
    ``<name>_elastic``; None when the run has no such design or it cannot be written as this spec.

    The relaxation's design is where the rules give way least (or, needing no slack, hold at the solver's
    samples): often much nearer a design that meets them than the least violated start (a guide way's start broke
    seven rules where the elastic design missed one by 0.02 mm)."""
    design = (result.elastic or {}).get("design")
    if not isinstance(design, dict) or not design:
        return None
    try:
        loaded, data = kinds.explicit_design(loaded)
        info = describe(loaded.model)
        for name, var in info.items():
            if not var["free"]:
                continue
            value = design.get(name)
            if var["path"] is None or not isinstance(value, (int, float)):
                return None
            entry = at_path(data, var["path"])
            if not isinstance(entry, dict) or "init" not in entry:
                return None
            lo, hi = var["bounds"]
            # IPOPT ends within its bound relaxation (~1e-8 relative) of a bound: a start must lie inside
            entry["init"] = float(min(max(float(value), lo), hi))
        data["name"] = derived_name(loaded.name, "_elastic")
        validate(type(loaded.model), data, prefix=loaded.kind)
    except (SpecError, KeyError, IndexError, TypeError, ValueError):
        return None
    elastic = result.elastic
    needed = elastic_said(elastic)
    head_lines = [f"# {result.name}: no start of `agrisynth solve` satisfied every rule (status {result.status}).",
                  f"# The elastic re-solve's design ({needed})",
                  f"# as the start of every free design variable of {comment_text(loaded.path.name)}, bounds kept:",
                  f"#   agrisynth check {ELASTIC_FILENAME}   evaluates it on the 10x finer grid;",
                  f"#   agrisynth solve {ELASTIC_FILENAME}   solves from it (start 0).",
                  f"# spec sha256 {loaded.sha256}", ""]
    return "\n".join(head_lines + write_toml(type(loaded.model), data, documented=False)) + "\n"


def elastic_said(elastic: dict) -> str:
    """What the elastic re-solve's design is, in a few words (result.json ``elastic``)."""
    if not elastic.get("converged"):
        return f"where it stopped, not converged: {elastic.get('return_status')}"
    if elastic.get("relaxed"):
        return f"the smallest relaxation it found, giving way on {', '.join(elastic['relaxed'])}"
    return "it needed no slack: every rule holds at the solver's samples"


def _given_design(loaded, result, data: dict) -> None:
    """A ``[design]`` table (the given design a kind reads, e.g. a path synthesis', with free timing its crank
    angles too): each of its fields the result has is set to the solution, where the spec allows it (a
    field the spec already prescribes elsewhere, e.g. timed targets' crank angles, is left out)."""
    model = type(loaded.model)
    field = model.model_fields.get("design")
    section = getattr(loaded.model, "design", None)
    if field is None or not isinstance(section, BaseModel):
        return
    design = data.setdefault("design", {})
    for name in type(section).model_fields:
        if name not in result.design:
            continue
        value = result.design[name]
        trial = dict(design, **{name: [float(x) for x in value] if isinstance(value, list) else float(value)})
        try:
            validate(model, dict(data, design=trial), prefix=loaded.kind)
        except SpecError:
            continue
        design.clear()
        design.update(trial)
    if not design:
        del data["design"]


def _fixed_values_moved(model, design: dict) -> str:
    """"l10 = 161.373 where the spec fixes 140" for the design variables the spec fixes that ``design`` moved ("" when
    none did; a kind whose spec lists no variables says nothing)."""
    variables = model.variables() if hasattr(model, "variables") else {}
    moved = []
    for name, v in variables.items():
        value = design.get(name)
        if is_free(v) or not isinstance(value, (int, float)) or not isinstance(v, (int, float)):
            continue
        if abs(value - v) > BOUND_TOLERANCE * max(1.0, abs(v)):
            moved.append(f"{name} = {value:.6g} where the spec fixes {v:g}")
    return "; ".join(moved)


def solved_toml(loaded, result) -> str:
    data = solved_data(loaded, result)
    objective = result.objective or {}
    value = objective.get("value")
    moved = _fixed_values_moved(loaded.model, result.design)
    kept = [n for n in kinds.get(loaded.kind).bounds_read(loaded.model) if is_free(loaded.model.variables().get(n))]
    exactly = (f"#   agrisynth check {FILENAME}   evaluates exactly this design (the solve's rule table)." if not moved
               else f"#   NOTE: the solve's design is no design of this spec ({moved}: a start IPOPT stopped without "
                    f"meeting the rows that hold it); `agrisynth check {FILENAME}` evaluates the spec's values, not "
                    f"the solve's rule table.")
    head = [f"# {result.name} as solved by `agrisynth solve` (status {result.status}"
            + (f", {objective.get('name')} = {value:.6g}" if isinstance(value, (int, float)) else "") + "):",
            f"# the spec {comment_text(loaded.path.name)} with every free design variable fixed at its solved value"
            + (f" ({', '.join(kept)}: started there, bounds kept -- the kind reads them)." if kept else "."),
            exactly, f"# spec sha256 {loaded.sha256}", ""]
    return "\n".join(head + write_toml(type(loaded.model), data, documented=False)) + "\n"
