"""A kind's NLP seen as a design: which decision entries are design coordinates, their affine map to the
design variables, the variables' units and the tolerance box.  Kind-agnostic: a kind whose NLP works in other
coordinates than the design itself declares their map (``Kind.design_affine``), a kind whose spec gives its design
variables no unit declares theirs (``Kind.design_unit``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pydantic import BaseModel

from synthesis.core.ipopt import NLPOutcome, answered_by, compiled_in
from synthesis.core.kind import Kind, own_half_width_refused
from synthesis.core.verdict import FINE
from synthesis.spec.design_info import acute_variables, describe, non_negative_variables, positive_variables
from synthesis.errors import SpecError
from synthesis.spec.common import FreeVariable, value_of


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
    #: the variables others determine (:attr:`Kind.follows`), by index: follower -> {other: d follower / d other}
    followers: dict[int, dict[int, float]] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.names)

    @property
    def moves(self) -> np.ndarray:
        """T (n x n): the offsets of a design in the box are T u for the offsets u of the variables it moves on their
        own (a follower's entry of u is unused: its half-width is 0, :func:`box_of`); the identity without
        followers."""
        T = np.eye(self.n)
        for j, others in self.followers.items():
            T[j, :] = 0.0
            for k, c in others.items():
                T[j, k] = c
        return T

    def spread(self, box: np.ndarray) -> np.ndarray:
        """Each variable's half-width in the box: its own, a follower's the sum of |d follower / d other| times the
        others' (how far the design in the box moves it)."""
        out = np.array(box, dtype=float)
        for j, others in self.followers.items():
            out[j] = sum(abs(c) * float(box[k]) for k, c in others.items())
        return out

    def moved_followers(self, box: np.ndarray) -> dict[str, dict[str, float]]:
        """The followers the box moves (:meth:`spread` above 0), by result key: follower -> {other: d follower /
        d other} (result.json's ``follows``, the Monte-Carlo's note)."""
        moved = self.spread(box)
        return {self.keys[j]: {self.keys[k]: c for k, c in others.items()}
                for j, others in self.followers.items() if moved[j] > 0}

    def coordinates(self, d: np.ndarray) -> np.ndarray:
        return np.linalg.solve(self.J, np.asarray(d, float) - self.d0)


def followers_of(follows: dict[str, dict[str, float]], keys: list[str]) -> dict[int, dict[int, float]]:
    """A kind's :attr:`~synthesis.core.kind.Kind.follows` by index into ``keys`` (result keys), for the followers whose
    variables are all there."""
    out = {}
    for follower, others in follows.items():
        if any(k in follows for k in others):     # a kind's definition, never a user's input
            raise ValueError(f"follows: {follower} follows a variable that follows others")
        if follower in keys and all(k in keys for k in others):
            out[keys.index(follower)] = {keys.index(k): float(c) for k, c in others.items()}
    return out


def design_map(kind: Kind, nlp, spec) -> DesignMap:
    """The design variables of the kind's built NLP, their result keys and units, and the map d = d0 + J x[:n]."""
    names = list(nlp.names)
    info = describe(spec)
    keys = spec_keys(names, info)
    units = [info[k]["unit"] if k in info else kind.design_unit for k in keys]
    d0, J = kind.design_affine(spec, len(names))
    return DesignMap(names, keys, units, d0, J, followers_of(kind.follows, keys))


def half_width(names, unit: str, length: float | None, angle: float | None,
               per_variable: dict[str, float]) -> float:
    """One variable's half-width: ``per_variable``'s entry under any of its ``names`` (0 included: the variable held
    exact), else ``length`` for a length in mm, ``angle`` for an angle in deg, else 0."""
    for name in names:
        if name in per_variable:
            return float(per_variable[name])
    if unit == "mm" and length is not None:
        return float(length)
    if unit == "deg" and angle is not None:
        return float(angle)
    return 0.0


def box_of(dmap: DesignMap, length: float | None, angle: float | None, per_variable: dict[str, float]) -> np.ndarray:
    """Half-width per design variable: by name (or result key) from ``per_variable``, else by unit."""
    known = set(dmap.names) | set(dmap.keys)
    unknown = sorted(set(per_variable) - known)
    if unknown:
        raise SpecError(f"tolerance: {', '.join(unknown)}: no variable this kind's analysis varies (it varies "
                        f"{', '.join(dmap.keys)})")
    for j, others in dmap.followers.items():
        given = [n for n in (dmap.keys[j], dmap.names[j]) if n in per_variable]
        if given:
            raise SpecError(f"tolerance: {own_half_width_refused(given[0], [dmap.keys[k] for k in others])}")
    box = [0.0 if j in dmap.followers else half_width((key, name), unit, length, angle, per_variable)
           for j, (name, key, unit) in enumerate(zip(dmap.names, dmap.keys, dmap.units))]
    if not any(box) and (length or angle):
        # a half-width that reaches no design variable would leave the box empty without a word
        given = " and ".join(f"{what} {w:g} {u}" for what, w, u in (("length", length, "mm"), ("angle", angle, "deg"))
                             if w)
        listed = ", ".join(f"{k} ({u})" if u else k for k, u in zip(dmap.keys, dmap.units))
        raise SpecError(f"tolerance: the half-width ({given}) applies to no design variable, so the tolerance box "
                        f"is empty; the design variables: {listed}")
    return np.array(box)


def box_fits(lo: float, hi: float, width: float, acute: bool, zero_allowed: bool = False) -> bool:
    """Whether some value in [lo, hi] keeps its box [v - width, v + width] inside the range the kind holds the
    variable to: > 0, >= 0 (``zero_allowed``: a dwell), or (0, 90) deg for an acute one.  One design is lo = hi."""
    if zero_allowed:        # a width summed from others' (a follower's) may carry their rounding: 0.1 x 3 > 0.3
        return hi - width >= -1e-12 * max(1.0, width)
    top = 90.0 - width if acute else float("inf")
    return max(lo, width) < min(hi, top) or (lo == hi and width < lo < top)


def refuse_crossing_zero(spec, dmap: DesignMap, design: dict, box: np.ndarray) -> None:
    """A half-width that reaches zero or below for a variable the kind holds > 0 (a link length, a radius, a speed),
    below zero for one it holds >= 0 (a cam's dwell), or 90 deg or beyond for one it holds acute, is refused
    (SpecError naming it): such a sample is no design of the kind, yet its rules could be evaluated and counted (a
    planting arm at +-1000 mm had links of -1865 mm, and its depth held in 5 % of the samples)."""
    positive, acute, non_negative = positive_variables(spec), acute_variables(spec), non_negative_variables(spec)
    for j, (name, key, unit, width) in enumerate(zip(dmap.names, dmap.keys, dmap.units, dmap.spread(box))):
        value = design.get(key)
        is_acute = key in acute or name in acute
        zero_allowed = key in non_negative or name in non_negative
        if (width <= 0 or not isinstance(value, float)
                or not (is_acute or zero_allowed or key in positive or name in positive)
                or box_fits(value, value, width, is_acute, zero_allowed)):
            continue
        # the half-width both ends allow: an acute angle's nearer end of (0, 90), a positive or non-negative value's 0
        room = min(value, 90.0 - value) if is_acute else value
        low = value - width <= 0
        every = "angle" if unit == "deg" else "length"
        if j in dmap.followers:
            drivers = ", ".join(dmap.keys[k] for k in dmap.followers[j])
            remedy = (f"it follows {drivers}, which move it by up to {width:g} {unit} in the box: give them smaller "
                      f"half-widths" if room > 0 else
                      # no half-width of 0 is taken, and any other moves it below 0: the box must leave them out
                      f"it follows {drivers}, and a {key} of 0 cannot move down: leave them out of the box, giving "
                      f"the others their half-widths one by one (--tol NAME=V, tolerance.variables)")
        elif zero_allowed and room == 0:     # no half-width of 0 is taken: the box must leave it out
            remedy = (f"a {key} of 0 cannot move down, so no half-width for every {every} holds it: leave it out of "
                      f"the box, giving the others theirs one by one (--tol NAME=V, tolerance.variables)")
        else:
            remedy = f"give it a half-width {'of at most' if zero_allowed else 'below'} {room:g} {unit}"
        limit = ">= 0" if zero_allowed else "> 0" if low else "< 90"
        raise SpecError(f"tolerance: the box reaches {value - width if low else value + width:g} {unit} for {key} "
                        f"({value:g} {unit} +- {width:g}), which must be {limit}: {remedy}")


def refuse_box_outside_bounds(spec, design_unit: str, where, follows: dict[str, dict[str, float]] | None = None) -> None:
    """SpecError when no design a tolerance-robust solve may try keeps its box ([tolerance]) inside the range the spec
    holds a variable to: > 0, >= 0, or 0 < angle < 90 for an acute one -- a fixed variable's value, or every value in
    a free one's bounds, within the half-width of a limit.  ``design_unit``: the unit of a variable the spec gives
    none (the kind's); ``follows``: the kind's :attr:`~synthesis.core.kind.Kind.follows` (a follower's half-width is
    how far the others move it).  (Where some design does, the solve runs; its answer's Monte-Carlo check is not
    run if the answer's box crosses a limit: ``synthesis.tolerance.robust``.)"""
    tol = getattr(spec, "tolerance", None)
    if tol is None or not callable(getattr(spec, "variables", None)):
        return
    info = describe(spec)
    positive, acute, non_negative = positive_variables(spec), acute_variables(spec), non_negative_variables(spec)
    values = spec.variables()
    names = list(info)
    units = [info[n]["unit"] or design_unit for n in names]
    dmap = DesignMap(names, names, units, np.zeros(len(names)), np.eye(len(names)), followers_of(follows or {}, names))
    followed = {names[j]: [names[k] for k in others] for j, others in dmap.followers.items()}
    widths = dict(zip(names, dmap.spread(np.array([
        0.0 if j in dmap.followers else half_width((n,), u, tol.length, tol.angle, dict(tol.variables))
        for j, (n, u) in enumerate(zip(names, units))]))))
    for name in [n for n in info if n in positive or n in acute or n in non_negative]:
        entry = info[name]
        width = widths[name]
        lo, hi = entry["bounds"] if entry["free"] else (value_of(values[name]),) * 2
        if width <= 0 or box_fits(lo, hi, width, name in acute, name in non_negative):
            continue
        which = (f"no design in its bounds [{lo:g}, {hi:g}] {entry['unit']} keeps" if entry["free"]
                 else f"its value {lo:g} {entry['unit']} does not keep")
        inside = (f"between {width:g} and {90.0 - width:g}" if name in acute
                  else f"at or above {width:g}" if name in non_negative else f"above {width:g}")
        limit = "(0, 90)" if name in acute else ">= 0" if name in non_negative else "> 0"
        at_zero = name in non_negative and hi == 0        # 0 cannot move down: no half-width holds it
        if name in followed:
            drivers = ", ".join(followed[name])
            remedy = (f"leave {drivers} (which {name} follows) out of the box, giving the others their half-widths "
                      f"one by one (tolerance.variables)" if at_zero
                      else f"give {drivers} (which {name} follows) smaller half-widths")
        elif at_zero:
            remedy = (f"leave {name} out of the box (0 cannot move down), giving the others their half-widths one by "
                      f"one (tolerance.variables)")
        else:
            remedy = f"give {name} a smaller half-width (tolerance.variables)"
        raise SpecError(f"{where}: [tolerance] +-{width:g} {entry['unit']} on {name}: {which} the box inside "
                        f"{limit} (the value must lie {inside}): {remedy} or {'bounds' if entry['free'] else 'a value'} "
                        f"further from the limit")


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
