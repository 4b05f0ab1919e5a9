"""Shared pieces of every spec model: strict base model, design variables, TOML reading, errors.

Errors name the TOML path, the bad value and what was expected, e.g.
``planting_fourbar.design.l2: expected > 0, got -3``, and suggest the fix where one is obvious.
"""

from __future__ import annotations

import difflib
import hashlib
import tomllib
from pathlib import Path
from typing import Annotated, Any, Union

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from synthesis.errors import SpecError


class StrictModel(BaseModel):
    """Frozen, unknown keys forbidden: a typo in a spec is an error, never silently ignored."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class FreeVariable(StrictModel):
    """A design variable left to the optimiser: start value and bounds (spec units)."""

    init: float = Field(description="start value (and the value `check` evaluates)")
    bounds: tuple[float, float] = Field(description="[lo, hi] the optimiser keeps it within")

    @model_validator(mode="after")
    def _ordered(self) -> "FreeVariable":
        lo, hi = self.bounds
        if lo > hi:
            raise ValueError(f"bounds [{lo:g}, {hi:g}] have lo > hi; write them as [{hi:g}, {lo:g}]")
        if not lo <= self.init <= hi:
            raise ValueError(f"init {self.init:g} lies outside its bounds [{lo:g}, {hi:g}]")
        return self


#: a number fixes the variable, a table ``{init = .., bounds = [lo, hi]}`` frees it
Variable = Union[float, FreeVariable]


def value_of(v: Variable) -> float:
    """The value `check` evaluates: the number itself, or the start value of a free variable."""
    return v.init if isinstance(v, FreeVariable) else float(v)


def bounds_of(v: Variable) -> tuple[float, float]:
    """[lo, hi] for the optimiser; a fixed variable has lo = hi."""
    return v.bounds if isinstance(v, FreeVariable) else (float(v), float(v))


def is_free(v: Variable) -> bool:
    return isinstance(v, FreeVariable)


def require_positive(name: str, v: Variable) -> None:
    """ValueError naming ``name`` unless the value (or a free variable's lower bound) is > 0."""
    lo = v.bounds[0] if isinstance(v, FreeVariable) else v
    if lo <= 0:
        raise ValueError(f"{name}: expected > 0, got {lo:g}" + (" (lower bound)" if isinstance(v, FreeVariable) else ""))


Interval = Annotated[tuple[float, float], Field(description="[lo, hi]")]

#: a spec's name is its result folder's name: letters, digits and _ . - only
RUN_NAME_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]*$"


class ProblemSpec(StrictModel):
    """What every spec file has besides its ``kind`` and its own sections."""

    name: str = Field(pattern=RUN_NAME_PATTERN, description="result folder name")
    source: str = Field("", description="where the numbers come from (paper, section, table)")


def starts_field(default: int):
    return Field(default, ge=1, le=10000, description="multistart starts (start 0 = the given design)")


def max_iter_field(default: int):
    return Field(default, ge=1, description="IPOPT iteration limit per start")


class MultistartSettings(StrictModel):
    """The [solver] settings of every kind that optimises; kinds add their sampling settings."""

    starts: int = starts_field(16)
    seed: int = Field(0, ge=0, description="seed of the Latin-hypercube starts")
    max_iter: int = max_iter_field(500)


def read_toml(path: Path) -> tuple[dict[str, Any], str]:
    """Parse a spec file; returns (data, sha256 of the bytes). Errors carry line and column."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SpecError(f"{path}: no such spec file") from None
    except OSError as exc:
        raise SpecError(f"{path}: cannot read ({exc.strerror})") from None
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise SpecError(f"{path}: not a UTF-8 text file (byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{path}: not valid TOML: {exc}") from None
    return data, hashlib.sha256(raw).hexdigest()


def _fields_at(model: type[BaseModel], loc: tuple) -> list[str]:
    """Names of the fields allowed at ``loc`` inside ``model`` (for did-you-mean)."""
    current: Any = model
    for part in loc:
        if isinstance(part, int):        # an item of a list of tables: its fields are the item model's
            continue
        fields = getattr(current, "model_fields", None)
        if fields is None or part not in fields:
            return []
        current = fields[part].annotation
        for arg in getattr(current, "__args__", ()) or ():
            if isinstance(arg, type) and issubclass(arg, BaseModel):
                current = arg
    fields = getattr(current, "model_fields", None)
    # a field spelled differently in TOML (``return`` is a Python keyword) is offered by its alias
    return [f.alias or n for n, f in fields.items()] if fields else []


#: pydantic error type -> (context key of the limit, symbol)
_COMPARISONS = {"greater_than": ("gt", ">"), "greater_than_equal": ("ge", ">="),
                "less_than": ("lt", "<"), "less_than_equal": ("le", "<=")}


def _describe(err: dict, model: type[BaseModel]) -> str:
    kind, ctx, got = err["type"], err.get("ctx", {}), err.get("input")
    # pydantic reports union branches as extra path parts ("float", "FreeVariable"): drop them
    loc = tuple(p for p in err["loc"] if p not in ("float", "FreeVariable", "function-after[_ordered(), FreeVariable]"))
    if kind == "missing":
        return f"{'.'.join(map(str, loc))}: missing required field"
    if kind == "extra_forbidden":
        allowed = _fields_at(model, loc[:-1])
        close = difflib.get_close_matches(str(loc[-1]), allowed, n=1, cutoff=0.5)
        hint = f"; did you mean '{close[0]}'?" if close else (f"; allowed: {', '.join(allowed)}" if allowed else "")
        return f"{'.'.join(map(str, loc))}: unknown field{hint}"
    path = ".".join(map(str, loc))
    if kind in _COMPARISONS:
        key, symbol = _COMPARISONS[kind]
        limit = ctx[key]
        return f"{path}: expected {symbol} {limit:g}, got {got}" if isinstance(limit, (int, float)) else \
            f"{path}: expected {symbol} {limit}, got {got}"
    if kind == "value_error":
        message = str(ctx.get("error", err["msg"]))
        # a whole-model validator (empty path) names the fields itself
        return f"{path}: {message}" if path else message
    if kind == "literal_error":
        return f"{path}: expected {ctx.get('expected')}, got {got!r}"
    return f"{path}: {err['msg'].lower()}, got {got!r}"


def validate(model: type[BaseModel], data: dict[str, Any], prefix: str) -> BaseModel:
    """Validate ``data`` into ``model``; on failure raise SpecError listing every bad field."""
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        seen: list[str] = []
        for err in exc.errors():
            line = f"{prefix}.{_describe(err, model)}"
            if line not in seen:
                seen.append(line)
        # a union of "number | table" yields one error per branch: keep the most specific ones
        raise SpecError("\n".join(_prune_union_noise(seen))) from None


def _prune_union_noise(lines: list[str]) -> list[str]:
    specific = [ln for ln in lines if "input should be a valid" not in ln and "dictionary" not in ln]
    return specific or lines
