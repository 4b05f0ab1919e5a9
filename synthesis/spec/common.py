"""Shared pieces of every spec model: strict base model, design variables, TOML reading, errors.

Errors name the TOML path, the bad value and what was expected, e.g.
``<kind>.design.l2: expected > 0, got -3``, and suggest the fix where one is obvious.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import re
import types
import tomllib
from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_args, get_origin

import numpy as np
from pydantic import (BaseModel, BeforeValidator, ConfigDict, Field, PrivateAttr, ValidationError, field_validator,
                      model_validator)
from pydantic_core import PydanticCustomError

from synthesis.errors import SpecError
from synthesis.files import read_regular, shown
from synthesis.spec.docmeta import TomlType, units_in


def _sign_not_a_bool(value: Any) -> Any:
    """TOML's ``true`` is no sign: pydantic's literal check takes it for 1 (True == 1), so ``branch = true`` ran the
    +1 assembly while ``false`` was refused; refused alike, with the literal's own message."""
    if isinstance(value, bool):
        raise PydanticCustomError("literal_error", "Input should be -1 or 1", {"expected": "-1 or 1"})
    return value


#: a sign field (an assembly branch, a required sign): -1 or +1, and never a boolean
Sign = Annotated[Literal[-1, 1], BeforeValidator(_sign_not_a_bool)]


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


def within_a_turn(cls, v):
    """A field validator for an angle variable (a number, or init and bounds): within one turn either way,
    [-360, 360] deg.  An angle of 1000 deg is a typo more likely than a wish for 280: say so rather than take it
    modulo a turn in silence.  Use: ``_turn = field_validator("zeta")(within_a_turn)``."""
    for x in ([v] if isinstance(v, (int, float)) else [v.init, *v.bounds]):
        # (IPOPT may end 1e-8 relative past a bound it relaxes: a solved.toml with a bound at 360 holds 360.0000036)
        if not abs(x) <= 360.0 * (1.0 + 1e-7):
            raise ValueError(f"expected an angle within one turn, [-360, 360] deg, got {x:.10g}")
    return v


def value_of(v: Variable) -> float:
    """The value `check` evaluates: the number itself, or the start value of a free variable."""
    return v.init if isinstance(v, FreeVariable) else float(v)


def bounds_of(v: Variable) -> tuple[float, float]:
    """[lo, hi] for the optimiser; a fixed variable has lo = hi."""
    return v.bounds if isinstance(v, FreeVariable) else (float(v), float(v))


def design_box(variables: dict[str, Variable], names) -> tuple[np.ndarray, np.ndarray]:
    """The optimiser's box of the design variables ``names``: bounds (n x 2; a fixed one has lo = hi) and
    the given (start) values, in spec units."""
    return (np.array([bounds_of(variables[n]) for n in names], dtype=float),
            np.array([value_of(variables[n]) for n in names], dtype=float))


def is_free(v: Variable) -> bool:
    return isinstance(v, FreeVariable)


def documented_range(text: str) -> dict:
    """``json_schema_extra`` of a design variable whose range a validator enforces (its value, or a free one's
    bounds), for the spec reference's range column: a Field bound cannot say it of a number-or-{init, bounds} field."""
    return {"range": text}


#: a length (or speed) > 0: the mark is also what :func:`require_positive_fields` checks
POSITIVE = documented_range("> 0")
#: an angle variable :func:`within_a_turn` checks; an angle strictly between 0 and 90 deg (its own validator)
WITHIN_A_TURN = documented_range(">= -360, <= 360")
ACUTE = documented_range("> 0, < 90")
#: a value >= 0 its own validator checks (a cam's dwell: none at all is a cam, less is not)
NON_NEGATIVE = documented_range(">= 0")


def require_positive(name: str, v: Variable) -> None:
    """ValueError naming ``name`` unless the value (or a free variable's lower bound) is > 0."""
    lo = v.bounds[0] if isinstance(v, FreeVariable) else v
    if lo <= 0:
        raise ValueError(f"{name}: expected > 0, got {lo:g}" + (" (lower bound)" if isinstance(v, FreeVariable) else ""))


def require_positive_fields(model: BaseModel) -> None:
    """:func:`require_positive` of every field marked :data:`POSITIVE`, in field order: the reference's range column
    and the check read one mark."""
    for name, field in type(model).model_fields.items():
        if field.json_schema_extra == POSITIVE:
            require_positive(field.alias or name, getattr(model, name))


Interval = Annotated[tuple[float, float], Field(description="[lo, hi]")]

#: the folders other commands write under results/ (compare's, bench's, the studio's): no spec's run folder
RESERVED_RUN_NAMES = ("compare", "bench", "studio")

#: a spec's name is its result folder's name: letters, digits and _ . - only
RUN_NAME_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]*$"
MAX_NAME_LENGTH = 100


def comment_text(text: str) -> str:
    """``text`` fit for one TOML comment line: a control character (a newline in a file name) would end the comment
    and make the rest of the name TOML -- written as "?"."""
    return re.sub(r"[\x00-\x1f\x7f]", "?", text)


def derived_name(name: str, suffix: str) -> str:
    """``name`` + ``suffix`` (a solved.toml's ``_solved``), the name cut so the whole keeps to MAX_NAME_LENGTH (a
    100-character name's solved.toml was refused by check, its name 107 characters long)."""
    return name[:MAX_NAME_LENGTH - len(suffix)] + suffix


class ToleranceSpec(StrictModel):
    """[tolerance]: manufacturing tolerances of the design variables (half-widths of a box around the design).
    In a spec, ``solve`` holds every rule at its linearised worst case in the box and Monte-Carlo checks the
    answer; ``agrisynth tolerance`` reads it too."""

    length: float | None = Field(None, ge=0, le=1e3, description="half-width for every length, mm")
    angle: float | None = Field(None, ge=0, le=90, description="half-width for every angle, deg")
    # each > 0, as --tol NAME=VALUE takes it: a negative half-width made the linear worst case better than the nominal
    variables: dict[str, Annotated[float, Field(gt=0, le=1e3)]] = Field(
        default_factory=dict, description="half-width per design variable, in its own unit (mm for lengths, deg for "
                                          "angles), each > 0, at most 1000 for a length and 90 for an angle (as length and angle); "
                                          "overrides length/angle")
    samples: int = Field(2000, ge=0, le=1_000_000, description="Monte-Carlo samples of the answer")
    seed: int = Field(0, ge=0, le=2**53, description="Monte-Carlo seed")


class ProblemSpec(StrictModel):
    """What every spec file has besides its ``kind`` and its own sections."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=MAX_NAME_LENGTH,
                      description="result folder name: letters, digits, _ . - (starting with a letter or digit), at most 100 characters; not compare, bench or studio, not ending in -check or -tolerance (other commands' folders)")
    source: str = Field("", description="where the numbers come from (paper, section, table)")
    tolerance: ToleranceSpec | None = Field(None, description="[tolerance] table: tolerance-robust solve")

    @field_validator("name")
    @classmethod
    def _not_another_commands_folder(cls, name: str) -> str:
        taken = another_commands_folder(name)
        if taken is not None:
            raise taken
        return name


def another_commands_folder(name: str) -> PydanticCustomError | None:
    """Why no spec may be named ``name`` although it is a folder name: another command's run folder is named so."""
    # check writes OUT/<name>-check/ and tolerance OUT/<name>-tolerance/: a spec named so would meet another
    # spec's run folder
    for suffix in ("-check", "-tolerance"):
        if name.lower().endswith(suffix):       # (a file system that ignores case meets X-Check too)
            return PydanticCustomError("run_name_suffix", "may not end in '{suffix}': agrisynth names another "
                                       "command's run folder <name>{suffix}", {"suffix": suffix})
    # and compare, bench and the studio write results/compare/, results/bench/, results/studio/ (a solve named
    # "compare" was replaced by a comparison page under --force)
    if name.lower() in RESERVED_RUN_NAMES:
        return PydanticCustomError("run_name_reserved", "may not be '{name}': agrisynth's {command} command "
                                   "writes results/{command}/", {"name": name, "command": name.lower()})
    return None


def usable_name(name: str) -> bool:
    """Whether a spec may be named ``name``: what :class:`ProblemSpec` takes."""
    return (len(name) <= MAX_NAME_LENGTH and re.fullmatch(RUN_NAME_PATTERN, name) is not None
            and another_commands_folder(name) is None)


#: [solver] starts: a whole number, or the word "auto" (read by SolverSettings' validator, never stored here)
Starts = Annotated[int, TomlType('integer | "auto"')]


def starts_field(default: int):
    return Field(default, ge=1, le=10000, description='multistart starts (start 0 = the given design), or "auto": '
                                                      'batches until the confidence rule holds (`--starts auto`)')


def max_iter_field(default: int, note: str = ""):
    return Field(default, ge=1, le=1_000_000, description="IPOPT iteration limit per start" + note)


class MultistartSettings(StrictModel):
    """The [solver] settings of every kind that optimises; kinds add their sampling settings."""

    starts: Starts = starts_field(16)
    seed: int = Field(0, ge=0, le=2**53, description="seed of the Latin-hypercube starts")
    max_iter: int = max_iter_field(500)
    #: starts = "auto": the multistart grows until it is sure (synthesis.core.solve.AutoStarts); ``starts`` is then
    #: the kind's default, which a fixed-starts run of the spec would use
    _starts_auto: bool = PrivateAttr(False)

    @model_validator(mode="wrap")
    @classmethod
    def _auto_starts(cls, data, handler):
        given = data.get("starts") if isinstance(data, dict) else None
        # spelled as --starts takes it (any case); another word is not a number of starts
        auto = isinstance(given, str) and given.strip().lower() == "auto"
        if isinstance(given, str) and not auto:
            raise ValueError(f'starts: expected a whole number 1..10000 or "auto", got {json.dumps(given[:20])}')
        model = handler({k: v for k, v in data.items() if k != "starts"} if auto else data)
        if auto:
            model._starts_auto = True
        return model

    @property
    def starts_auto(self) -> bool:
        """Whether the spec says ``starts = "auto"``."""
        return self._starts_auto


#: what a spec file may hold: a file of at most MAX_SPEC_BYTES, tables nested at most MAX_DEPTH deep,
#: strings of at most MAX_STRING characters, arrays of at most MAX_ITEMS items, numbers finite and of
#: magnitude at most MAX_MAGNITUDE (floats) or MAX_INT (integers)
MAX_SPEC_BYTES = 1_000_000
MAX_DEPTH = 16
MAX_STRING = 10_000
MAX_ITEMS = 100_000
MAX_MAGNITUDE = 1e12
MIN_MAGNITUDE = 1e-12     #: the smallest non-zero magnitude of a spec number
MAX_INT = 2**53


#: a number followed by a unit, outside quotes (``crank_speed = 250 rpm``): TOML has no such value
_UNQUOTED_UNIT = re.compile(r"[=,\[{]\s*([-+]?\d[\d_]*(?:\.\d+)?(?:[eE][-+]?\d+)?\s*[A-Za-z%\u00b0\u00b5][\w/%\u00b0\u00b5^*.-]*)")


def _unquoted_unit_hint(text: str, exc: tomllib.TOMLDecodeError) -> str:
    """"; a value with a unit must be quoted ("250 rpm")" when the line TOML stopped at holds a number with a unit
    (the parser's own message names only the column); "" otherwise."""
    at = re.search(r"\(at line (\d+), column \d+\)$", str(exc))        # Python 3.11's error has no lineno
    lines = text.splitlines()
    line = lines[int(at.group(1)) - 1] if at and 0 < int(at.group(1)) <= len(lines) else ""
    found = _UNQUOTED_UNIT.search(line.split("#")[0])
    return f'; a value with a unit must be quoted ("{found.group(1).strip()}")' if found else ""


def read_toml(path: Path) -> tuple[dict[str, Any], str]:
    """Parse a spec file; returns (data, sha256 of the bytes). Errors carry line and column.

    Refused with one line (SpecError, exit 2): anything but a regular file of at most MAX_SPEC_BYTES,
    an empty file, bytes that are not UTF-8, invalid TOML (duplicate keys included), and values
    :func:`check_values` refuses."""
    path = Path(path)
    raw = read_regular(path, MAX_SPEC_BYTES, "spec file", SpecError)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SpecError(f"{path}: not a UTF-8 text file (byte {exc.start})") from None
    # a byte-order mark (Windows editors save "UTF-8 with BOM") is no content: TOML's parser refused it as "Invalid
    # statement (at line 1, column 1)", which named nothing the user could see
    text = text.removeprefix("\ufeff")
    if not text.strip():
        raise SpecError(f"{path}: empty file (a spec needs at least kind and name)")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{path}: not valid TOML: {shown(str(exc), 200)[1:-1]}{_unquoted_unit_hint(text, exc)}") from None
    except RecursionError:
        raise SpecError(f"{path}: not valid TOML: nested deeper than {MAX_DEPTH} levels") from None
    try:
        check_values(data)
    except SpecError as exc:
        raise SpecError(f"{path}: {exc}") from None
    return data, hashlib.sha256(raw).hexdigest()


def check_values(data: Any, where: str = "", depth: int = 0) -> None:
    """SpecError naming the first value no spec may hold: NaN or infinity, a number beyond the bounds,
    a string too long, an array too long, nesting too deep, a date or time."""
    name = where or "the file"
    if depth > MAX_DEPTH:
        raise SpecError(f"{name}: nested deeper than {MAX_DEPTH} levels")
    if isinstance(data, bool):
        return
    if isinstance(data, float):
        if not math.isfinite(data):
            raise SpecError(f"{name}: {data} is not a finite number")
        if abs(data) > MAX_MAGNITUDE:
            raise SpecError(f"{name}: {data:g} is beyond the largest magnitude a spec value may have ({MAX_MAGNITUDE:g})")
        if data != 0.0 and abs(data) < MIN_MAGNITUDE:
            # below this, products and quotients of spec values underflow to 0 or overflow (1 / 5e-324):
            # no physical quantity in mm, s, deg or m/s is that small
            raise SpecError(f"{name}: {data:g} is below the smallest magnitude a spec value may have "
                            f"({MIN_MAGNITUDE:g}); write 0 if you mean zero")
    elif isinstance(data, int):
        if abs(data) > MAX_INT:
            raise SpecError(f"{name}: {shown(data, 30)} is beyond the largest integer a spec value may have (2^53)")
    elif isinstance(data, str):
        if len(data) > MAX_STRING:
            raise SpecError(f"{name}: a string of {len(data)} characters (at most {MAX_STRING})")
    elif isinstance(data, dict):
        for key, value in data.items():
            if len(key) > 200:
                raise SpecError(f"{name}: a key of {len(key)} characters (at most 200)")
            check_values(value, f"{where}.{key}" if where else key, depth + 1)
    elif isinstance(data, list):
        if len(data) > MAX_ITEMS:
            raise SpecError(f"{name}: an array of {len(data)} items (at most {MAX_ITEMS})")
        for i, value in enumerate(data):
            check_values(value, f"{name}[{i}]", depth + 1)
    else:       # TOML dates and times: no spec field is one
        raise SpecError(f"{name}: a {type(data).__name__} ({shown(data, 40)}) is not a spec value")


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


#: pydantic error type of a wrongly typed value -> what was expected
_TYPES = {"float_type": "a number", "float_parsing": "a number", "int_type": "an integer", "int_parsing": "an integer",
          "int_from_float": "an integer", "bool_type": "true or false", "string_type": "a string",
          "model_type": "a table", "dict_type": "a table", "model_attributes_type": "a table",
          "list_type": "an array", "tuple_type": "an array", "finite_number": "a finite number"}


def _model_in(tp: Any) -> Any:
    """The pydantic model an annotation leads into (through Optional, unions, lists, Annotated), or None."""
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return tp
    for arg in getattr(tp, "__args__", ()) or ():
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _field_at(model: type[BaseModel], loc: tuple):
    """The pydantic field at ``loc`` (TOML keys, list indices skipped), or None."""
    current: Any = model
    found = None
    for part in loc:
        if isinstance(part, int):
            continue
        fields = getattr(current, "model_fields", None) or {}
        found = next((f for n, f in fields.items() if part in (n, f.alias)), None)
        if found is None:
            return None
        current = _model_in(found.annotation)
    return found


def _unit_hint(model: type[BaseModel], loc: tuple) -> str:
    """" in mm" (the field's unit, from its description) or ""."""
    field = _field_at(model, loc)
    units = units_in(field.description) if field is not None else []
    return f" in {' or '.join(units)}" if units else ""


def _pair_text(model: type[BaseModel], loc: tuple) -> str:
    field = _field_at(model, loc)
    lo_hi = loc and loc[-1] == "bounds" or field is not None and "[lo, hi]" in (field.description or "")
    return "[lo, hi] (two numbers)" if lo_hi else "two numbers"


def _describe(err: dict, model: type[BaseModel]) -> str:
    kind, ctx, got = err["type"], err.get("ctx", {}), err.get("input")
    # pydantic reports union branches as extra path parts ("float", "FreeVariable"): drop them
    loc = tuple(p for p in err["loc"] if p not in ("float", "FreeVariable", "function-after[_ordered(), FreeVariable]",
                                                   "OperatingRange", "constrained-float"))
    if kind == "missing" and len(loc) > 1 and isinstance(loc[-1], int) and isinstance(got, list):
        # a tuple given too few items: pydantic names the first missing index ("bounds.1")
        return f"{'.'.join(map(str, loc[:-1]))}: expected {_pair_text(model, loc[:-1])}, got {shown(got)}"
    if kind == "too_long" and ctx.get("field_type") == "Tuple" and isinstance(got, list) and ctx.get("max_length") == 2:
        return f"{'.'.join(map(str, loc))}: expected {_pair_text(model, loc)}, got {shown(got)}"
    if kind == "missing":
        return f"{'.'.join(map(str, loc))}: missing required field"
    if kind == "extra_forbidden":
        allowed = _fields_at(model, loc[:-1])
        key = str(loc[-1])
        close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.7) or \
            [a for a in allowed if len(a) >= 3 and (key.startswith(a) or a.startswith(key))][:1]
        hint = f"; did you mean '{close[0]}'?" if close else (f"; allowed: {', '.join(allowed)}" if allowed else "")
        if len(loc) == 1 and not close:
            hint += " (a note about the spec goes in source = \"...\" or a # comment)"
        return f"{'.'.join(map(str, loc))}: unknown field{hint}"
    path = ".".join(map(str, loc))
    if kind in _COMPARISONS:
        key, symbol = _COMPARISONS[kind]
        limit = ctx[key]
        return f"{path}: expected {symbol} {limit:g}, got {shown(got)}" if isinstance(limit, (int, float)) else \
            f"{path}: expected {symbol} {limit}, got {shown(got)}"
    if kind == "value_error":
        message = str(ctx.get("error", err["msg"]))
        # a whole-model validator (empty path) names the fields itself
        return f"{path}: {message}" if path else message
    if kind in ("float_type", "float_parsing") and isinstance(got, str):
        # "0.8 m/s", "300 rpm": the unit of every field is fixed; say which
        return f"{path}: expected a number{_unit_hint(model, loc)}, written without a unit, got {shown(got)}"
    if (kind in ("float_type", "float_parsing") and isinstance(got, dict) and "range" in got
            and "OperatingRange" not in str(getattr(_field_at(model, loc), "annotation", ""))):
        # an operating range where this kind takes one value (README: which conditions take a range)
        return (f"{path}: expected a number{_unit_hint(model, loc)}, got {shown(got)}: this field takes one value, "
                f"not an operating range {{range = [lo, hi], ...}}")
    if kind in _TYPES:
        return f"{path}: expected {_TYPES[kind]}, got {shown(got)}"
    if kind == "literal_error":
        return f"{path}: expected {ctx.get('expected')}, got {shown(got)}"
    if kind == "string_pattern_mismatch" and ctx.get("pattern") == RUN_NAME_PATTERN:
        return (f"{path}: letters, digits, '_', '.' and '-' only, starting with a letter or digit (it names the "
                f"result folder), got {shown(got)}")
    # pydantic's message as it is, only its first letter lowered (lowering all of it misstates a pattern: A-Z)
    message = err["msg"]
    return f"{path}: {message[:1].lower()}{message[1:]}, got {shown(got)}"


def validate(model: type[BaseModel], data: dict[str, Any], prefix: str) -> BaseModel:
    """Validate ``data`` into ``model``; on failure raise SpecError listing every bad field.

    A model may refuse forms it no longer reads, with their new spelling, before anything else:
    ``old_forms(data) -> str`` (a line per form, "" when there is none)."""
    old_forms = getattr(model, "old_forms", None)
    if callable(old_forms) and isinstance(data, dict):
        message = old_forms(data)
        if message:
            raise SpecError("\n".join(f"{prefix}.{line}" for line in message.splitlines()))
    try:
        text = json.dumps(data, allow_nan=False)
    except (TypeError, ValueError, RecursionError):     # Python objects (not from a file): validated as they are
        text = None
    try:
        # strict, from JSON: a float field takes integers and floats only (never ``true`` or ``"75"``), an
        # integer field integers only; arrays still fill tuples
        return model.model_validate(data) if text is None else model.model_validate_json(text, strict=True)
    except ValidationError as exc:
        order = _file_order(data)
        errors = _best_table_branches(exc.errors(), _model_names(model))
        # in file order, each line once (a dict keeps the first: a list's `in` made thousands of errors quadratic)
        seen = list(dict.fromkeys(f"{prefix}.{_describe(err, model)}"
                                  for err in sorted(errors, key=lambda e: _position(order, e["loc"]))))
        # a union of "number | table" yields one error per branch: keep the most specific ones
        raise SpecError("\n".join(capped(_prune_union_noise(_misspelt_only(seen))))) from None


def _model_names(model: type[BaseModel]) -> set[str]:
    """The class names of the tables a union among a spec model's fields offers (a link's BarLink | LumpedLink, through
    lists and tables of them): what pydantic puts in an error's path for each branch of such a union."""
    names: set[str] = set()
    seen: set[type] = set()
    todo: list[Any] = [model]
    while todo:
        tp = todo.pop()
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            if tp not in seen:
                seen.add(tp)
                todo += [f.annotation for f in tp.model_fields.values()]
            continue
        args = get_args(tp)
        tables = [a.__name__ for a in args if isinstance(a, type) and issubclass(a, BaseModel)]
        if get_origin(tp) in (Union, types.UnionType) and len(tables) > 1:       # not X | None: a choice of tables
            names.update(tables)
        todo += list(args)
    return names


def _best_table_branches(errors: list, branches_named: set[str]) -> list:
    """Where a field takes one of several tables (a link as a bar {density, area} or lumped {mass, com, inertia}) and
    fits none, pydantic complains of every branch: only the branch the given keys fit best is kept (the fewest keys
    it does not know, then the fewest complaints), its name dropped from the path -- a lumped link with a negative
    inertia was told "BarLink.mass: unknown field" four times and never its inertia."""
    branches: dict[tuple, dict[str, list]] = {}
    for err in errors:
        loc = err["loc"]
        # a union's branch is named by its model's class; a key the user named (a pose "Pick") is no branch
        k = next((i for i, part in enumerate(loc) if isinstance(part, str) and part in branches_named), None)
        if k is not None:
            branches.setdefault(tuple(loc[:k]), {}).setdefault(loc[k], []).append(err)
    chosen, dropped = {}, set()
    for where, by_branch in branches.items():
        if len(by_branch) < 2:
            continue
        best = min(by_branch, key=lambda b: (sum(e["type"] == "extra_forbidden" for e in by_branch[b]),
                                            len(by_branch[b])))
        chosen[where] = best
        dropped.update(id(e) for b, errs in by_branch.items() if b != best for e in errs)
    out = []
    for err in errors:
        if id(err) in dropped:
            continue
        loc = err["loc"]
        for where, best in chosen.items():
            if tuple(loc[:len(where)]) == where and len(loc) > len(where) and loc[len(where)] == best:
                err = {**err, "loc": (*where, *loc[len(where) + 1:])}
                break
        out.append(err)
    return out


def _misspelt_only(lines: list[str]) -> list[str]:
    """Without "T.x: missing required field" where a line of the same table says "T.y: unknown field; did you mean
    'x'?": one misspelt key read as two faults, the side effect first (it sits earlier in the file)."""
    suggested = set()
    for line in lines:
        match = re.match(r"^(.*)\.[^.:]+: unknown field; did you mean '([^']+)'\?$", line)
        if match:
            suggested.add(f"{match.group(1)}.{match.group(2)}: missing required field")
    return [line for line in lines if line not in suggested]


def _file_order(data: Any, prefix: tuple = (), order: dict | None = None) -> dict[tuple, int]:
    """Every key path of ``data`` -> its position in the file (TOML tables keep the file's order)."""
    order = {} if order is None else order
    items = data.items() if isinstance(data, dict) else enumerate(data) if isinstance(data, list) else ()
    for key, value in items:
        order[(*prefix, key)] = len(order)
        if len(order) < 100_000:
            _file_order(value, (*prefix, key), order)
    return order


def _position(order: dict[tuple, int], loc: tuple) -> int:
    """Where the field an error is about sits in the file: its longest prefix that is in the file (a
    missing top-level field: after everything in the file)."""
    for n in range(len(loc), 0, -1):
        if tuple(loc[:n]) in order:
            return order[tuple(loc[:n])]
    return len(order)


#: a message lists at most this many problems (the first names the first bad field), then "and N more"
MAX_PROBLEM_LINES = 5


def capped(lines: list[str], most: int = MAX_PROBLEM_LINES) -> list[str]:
    """The first ``most - 1`` lines and "... and N more", when there are more than ``most``."""
    if len(lines) <= most:
        return lines
    return [*lines[:most - 1], f"... and {len(lines) - most + 1} more problem(s) in the spec (fix these first)"]


_NUMBER = ": expected a number, got "
_TABLE = ": expected a table, got "


class _Prefixes:
    """Which lines of a list start with a given path followed by a given separator, found in time linear in the
    lines' total length: each line is indexed at the positions where a separator follows the length of some path
    asked about (the error lines of a spec with thousands of bad list entries made the pairwise search quadratic:
    8,000 entries took over two minutes)."""

    def __init__(self, lines: list[str], paths: set[str], separators: tuple[str, ...]):
        lengths = {len(p) for p in paths}
        #: (path, separator) -> up to two distinct lines starting with them (enough to find "another one")
        self.owners: dict[tuple[str, str], list[str]] = {}
        for ln in lines:
            for sep in separators:
                at = ln.find(sep)
                while at >= 0:
                    if at in lengths and ln[:at] in paths:
                        found = self.owners.setdefault((ln[:at], sep), [])
                        if ln not in found and len(found) < 2:
                            found.append(ln)
                    at = ln.find(sep, at + 1)

    def other_than(self, line: str, path: str, *separators: str) -> bool:
        """Whether a line other than ``line`` starts with ``path`` and one of ``separators``."""
        return any(o != line for sep in separators for o in self.owners.get((path, sep), ()))


def _prune_union_noise(lines: list[str]) -> list[str]:
    """Merge a "number | table" union's two complaints about one field into one line (linear in the lines)."""
    given = set(lines)
    out: list[str] = []
    for ln in lines:
        path, _, rest = ln.partition(_NUMBER)
        table_path, _, table_rest = ln.partition(_TABLE)
        if rest and f"{path}{_TABLE}{rest}" in given:
            out.append(f"{path}: expected a number (or a table {{init = ..., bounds = [lo, hi]}}), got {rest}")
        elif table_rest and f"{table_path}{_NUMBER}{table_rest}" in given:
            continue
        else:
            out.append(ln)
    # "expected a number in mm, written without a unit" already says what to write: drop the table branch
    tables = {ln.partition(_TABLE)[0] for ln in out if ln.partition(_TABLE)[2]}
    numbers = _Prefixes(out, tables, (": expected a number",))
    out = [ln for ln in out if not (ln.partition(_TABLE)[2] and numbers.owners.get((ln.partition(_TABLE)[0],
                                                                                    ": expected a number")))]
    # a table given for a "number | table" field: the table's own complaints say what is wrong with it
    # (its fields' complaints, or its own: e.g. "init 500 lies outside its bounds [28, 42]")
    given_tables = {ln.partition(_NUMBER)[0] for ln in out if ": expected a number, got {" in ln}
    inside = _Prefixes(out, given_tables, (".", ": "))
    out = [ln for ln in out if not (": expected a number, got {" in ln
                                    and inside.other_than(ln, ln.partition(_NUMBER)[0], ".", ": "))]
    # a number given for a "number | range table" field: the number's own complaint says what is wrong with it
    out = _without_range_table_branch(out)
    out = [_free_hint(ln) for ln in out]
    specific = [ln for ln in out if "input should be a valid" not in ln and "dictionary" not in ln]
    return specific or out


def _without_range_table_branch(lines: list[str]) -> list[str]:
    """``lines`` without each "<path>: expected a table, got <v>" for which another line reads "<path>: expected
    ..., got <v>" (the number branch's own complaint about the same value)."""
    asked = {}
    for ln in lines:
        path, _, rest = ln.partition(_TABLE)
        if rest:
            asked.setdefault(path, set()).add(rest)
    owners: dict[tuple[str, str], list[str]] = {}      # (path, value) -> up to two distinct lines saying so
    lengths = {len(p) for p in asked}
    for ln in lines:
        at = ln.find(": expected ")
        while at >= 0:
            if at in lengths and ln[:at] in asked:
                values = asked[ln[:at]]
                tail = ln.find(", got ")
                while tail >= 0:
                    value = ln[tail + len(", got "):]
                    if value in values:
                        found = owners.setdefault((ln[:at], value), [])
                        if ln not in found and len(found) < 2:
                            found.append(ln)
                    tail = ln.find(", got ", tail + 1)
            at = ln.find(": expected ", at + 1)
    kept = []
    for ln in lines:
        path, _, rest = ln.partition(_TABLE)
        if rest and any(o != ln for o in owners.get((path, rest), ())):
            continue
        kept.append(ln)
    return kept


def _free_hint(line: str) -> str:
    """``l2 = [25, 45]`` for a number-or-table field: show the table that frees it within those bounds."""
    path, sep, got = line.partition(": expected a number (or a table {init = ..., bounds = [lo, hi]}), got ")
    try:
        lo, hi = (float(x) for x in got.strip("[]").split(","))
    except ValueError:
        return line
    if not sep or not lo <= hi:
        return line
    return (f"{path}: expected a number, or a table to free it: "
            f"{path.rsplit('.', 1)[-1]} = {{init = {0.5 * (lo + hi):g}, bounds = [{lo:g}, {hi:g}]}}, got {got}")
