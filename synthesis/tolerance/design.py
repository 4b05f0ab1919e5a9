"""A kind's NLP seen as a design: which decision entries are design coordinates, their affine map to the
design variables, the variables' units and the tolerance box.  Kind-agnostic: a kind whose NLP works in other
coordinates than the design itself declares their map (``Kind.design_affine``), a kind whose spec gives its design
variables no unit declares theirs (``Kind.design_unit``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydantic import BaseModel

from synthesis.core.ipopt import NLPOutcome, answered_by, compiled_in
from synthesis.core.kind import Kind
from synthesis.core.verdict import FINE
from synthesis.spec.design_info import acute_variables, describe, positive_variables
from synthesis.errors import SpecError
from synthesis.spec.common import FreeVariable


def spec_keys(names, info) -> list[str]:
    """The spec's design variable of each NLP variable name: the same name, or the one spec name ending in
    ``_<name>`` (an NLP that names an angle ``I`` where its spec says ``delta_I``)."""
    keys = []
    for n in names:
        if n in info:
            keys.append(n)
        else:
            match = [k for k in info if k.endswith("_" + n)]
            keys.append(match[0] if len(match) == 1 else n)
    return keys


def freed(spec: BaseModel) -> BaseModel:
    """The spec with every fixed design variable written as a free one with bounds [v, v], so the kind's
    NLP carries it as a decision entry (a tolerance applies to fixed dimensions too)."""
    update = {}
    for name, field in type(spec).model_fields.items():
        value = getattr(spec, name)
        if isinstance(value, FreeVariable):
            continue
        if isinstance(value, BaseModel):
            new = freed(value)
            if new is not value:
                update[name] = new
        elif isinstance(value, list) and value and all(isinstance(v, BaseModel) for v in value):
            new = [freed(v) for v in value]
            if any(a is not b for a, b in zip(new, value)):
                update[name] = new
        elif isinstance(value, (int, float)) and not isinstance(value, bool) and "FreeVariable" in str(field.annotation):
            update[name] = FreeVariable(init=float(value), bounds=(float(value), float(value)))
    return spec.model_copy(update=update) if update else spec


def fine(spec: BaseModel) -> BaseModel:
    """The spec with every ``[solver]`` sample count FINE x larger: the analysis samples the rules on
    the re-check's grid."""
    solver = getattr(spec, "solver", None)
    if not isinstance(solver, BaseModel):
        return spec
    update = {n: FINE * getattr(solver, n) for n in type(solver).model_fields
              if "samples" in n and isinstance(getattr(solver, n), int) and not isinstance(getattr(solver, n), bool)}
    return spec.model_copy(update={"solver": solver.model_copy(update=update)}) if update else spec


@dataclass
class DesignMap:
    """The design variables of a kind's NLP and how its decision vector holds them."""

    names: list[str]           # design variables, NLP order
    keys: list[str]            # their keys in result.json ``design``
    units: list[str]
    d0: np.ndarray
    J: np.ndarray              # d = d0 + J x[:n]

    @property
    def n(self) -> int:
        return len(self.names)

    def coordinates(self, d: np.ndarray) -> np.ndarray:
        return np.linalg.solve(self.J, np.asarray(d, float) - self.d0)


def design_map(kind: Kind, nlp, spec) -> DesignMap:
    """The design variables of the kind's built NLP, their result keys and units, and the map d = d0 + J x[:n]."""
    names = list(nlp.names)
    info = describe(spec)
    keys = spec_keys(names, info)
    units = [info[k]["unit"] if k in info else kind.design_unit for k in keys]
    d0, J = kind.design_affine(spec, len(names))
    return DesignMap(names, keys, units, d0, J)


def box_of(dmap: DesignMap, length: float | None, angle: float | None, per_variable: dict[str, float]) -> np.ndarray:
    """Half-width per design variable: by name (or result key) from ``per_variable``, else by unit."""
    known = set(dmap.names) | set(dmap.keys)
    unknown = sorted(set(per_variable) - known)
    if unknown:
        raise SpecError(f"tolerance: {', '.join(unknown)}: no variable this kind's analysis varies (it varies "
                        f"{', '.join(dmap.keys)})")
    box = []
    for name, key, unit in zip(dmap.names, dmap.keys, dmap.units):
        if key in per_variable or name in per_variable:
            box.append(float(per_variable.get(key, per_variable.get(name))))
        elif unit == "mm" and length is not None:
            box.append(float(length))
        elif unit == "deg" and angle is not None:
            box.append(float(angle))
        else:
            box.append(0.0)
    if not any(box) and (length or angle):
        # a half-width that reaches no design variable would leave the box empty without a word
        given = " and ".join(f"{what} {w:g} {u}" for what, w, u in (("length", length, "mm"), ("angle", angle, "deg"))
                             if w)
        listed = ", ".join(f"{k} ({u})" if u else k for k, u in zip(dmap.keys, dmap.units))
        raise SpecError(f"tolerance: the half-width ({given}) applies to no design variable, so the tolerance box "
                        f"is empty; the design variables: {listed}")
    return np.array(box)


def refuse_crossing_zero(spec, dmap: DesignMap, design: dict, box: np.ndarray) -> None:
    """A half-width that reaches zero or below for a variable the kind holds > 0 (a link length, a radius, a speed),
    or 90 deg or beyond for one it holds acute, is refused
    (SpecError naming it): such a sample is no design of the kind, yet its rules could be evaluated and counted (a
    planting arm at +-1000 mm had links of -1865 mm, and its depth held in 5 % of the samples)."""
    positive, acute = positive_variables(spec), acute_variables(spec)
    for name, key, unit, width in zip(dmap.names, dmap.keys, dmap.units, box):
        value = design.get(key)
        if width <= 0 or not isinstance(value, float):
            continue
        is_acute = key in acute or name in acute
        # the half-width both ends allow: an acute angle's nearer end of (0, 90), a positive value's 0
        room = min(value, 90.0 - value) if is_acute else value
        if (key in positive or name in positive or is_acute) and value - width <= 0:
            raise SpecError(f"tolerance: the box reaches {value - width:g} {unit} for {key} ({value:g} {unit} +- "
                            f"{width:g}), which must be > 0: give it a half-width below {room:g} {unit}")
        if is_acute and value + width >= 90:
            raise SpecError(f"tolerance: the box reaches {value + width:g} {unit} for {key} ({value:g} {unit} +- "
                            f"{width:g}), which must be < 90: give it a half-width below {room:g} {unit}")


def whole_problem(nlp) -> None:
    """The kind's NLP solves its whole problem from every start: a second, reduced form it may solve first
    (``KindNLP.configuration``) is dropped, so a tolerance box holds, and the analysis reads, every rule as the
    whole problem holds it in the spec's design coordinates."""
    nlp.whole_problem_only()


def kind_start(nlp, x_design: np.ndarray):
    """(compiled NLP, decision vector, parameters) the kind's own solve would start IPOPT from at this
    design: its guesses of the auxiliaries (crank angles of precision points, extremes, ...), never solved."""
    seen = []

    def capture(compiled, start, w0, p):
        seen.append((compiled, np.array(w0, float), np.array(p, float)))
        return NLPOutcome(start, np.array(w0, float), 0.0, "captured", True, 0, 0.0, "")

    refused: SpecError | None = None
    with answered_by(compiled_in(nlp), capture):
        try:
            nlp.solve(0, np.asarray(x_design, float))
        except SpecError as exc:      # the kind refuses to solve this spec at all: its own words say why
            refused = exc
        except Exception:   # noqa: BLE001 - only the captured start matters
            pass
    if not seen:
        if refused is not None:
            raise SpecError(f"tolerance: {refused}") from None
        raise SpecError("the kind's NLP made no solve call to take its start from")
    compiled, w0, p = seen[0]
    return compiled, w0[:compiled.problem.x.numel()], p
