"""The spec reference, generated from the kinds' pydantic models (never written by hand).

``agrisynth spec KIND`` prints every field of a kind's spec (TOML path, type, unit, default, allowed
range, description), ``agrisynth spec KIND --template`` writes a commented starting file, and
``docs/specs.md`` is the same reference for every kind::

    python -m synthesis.spec.reference            # regenerate docs/specs.md
    python -m synthesis.spec.reference --check    # exit 1 when docs/specs.md is stale

Units are read from the field descriptions (``"crank OA, mm"``); a numeric field without a unit says
``dimensionless``.  A template is the kind's library example (``Kind.example``) written field by field
through the model: every field with its description, the example's values, and the fields the example
leaves at their default commented out; so a template validates and checks like that example.
"""

from __future__ import annotations

import inspect
import json
import math
import re
import sys
import textwrap
import types
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_args, get_origin

import annotated_types as at
from pydantic import BaseModel

from synthesis import kinds
from synthesis.library import IMPORT_ROOT, LIBRARY, checkout
from synthesis.spec.common import FreeVariable, StrictModel, read_toml
from synthesis.spec.docmeta import UNITS, SpecFile, TomlType, units_in

#: the reference of every kind, generated into the source checkout's docs (an installed copy has no docs folder)
DOCS = IMPORT_ROOT / "docs" / "specs.md"
REGENERATE = "python -m synthesis.spec.reference"

DIMENSIONLESS = "dimensionless"


# ---------------------------------------------------------------------------------------- the model's fields

@dataclass(frozen=True)
class Entry:
    """One row of the reference: a field, or a section (TOML table) heading its fields."""

    path: str               # TOML path: "arm.l2", "tubes[].angle"; a section: "arm", "tubes[]"
    section: bool
    many: bool              # a section written as [[path]] (a list of tables)
    type: str
    unit: str
    default: str            # "" when required
    range: str
    required: bool
    description: str
    numeric: bool           # a quantity: a number, numbers, or a free variable

    @property
    def heading(self) -> str:
        return f"[[{self.path.removesuffix('[]')}]]" if self.many else f"[{self.path}]"


def _unwrap(tp) -> tuple[Any, list]:
    """Annotated[T, meta...] -> (T, [meta...]) (nested Annotated flattened)."""
    meta: list = []
    while get_origin(tp) is Annotated:
        tp, *more = get_args(tp)
        meta += more
    return tp, meta


def _optional(tp) -> tuple[Any, bool]:
    if get_origin(tp) in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        if len(args) < len(get_args(tp)):
            return (args[0] if len(args) == 1 else Union[tuple(args)]), True
    return tp, False


def _is_model(tp) -> bool:
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def _section_of(tp) -> tuple[type[BaseModel] | None, bool]:
    """(model, many) when the annotation is a section, a list of sections, or an optional one."""
    tp, _ = _unwrap(tp)
    tp, _ = _optional(tp)
    tp, _ = _unwrap(tp)
    if _is_model(tp) and tp is not FreeVariable:
        return tp, False
    if get_origin(tp) is list:
        (item,) = get_args(tp)
        item, _ = _unwrap(item)
        if _is_model(item) and item is not FreeVariable:
            return item, True
    return None, False


def _named_sections(tp) -> type[BaseModel] | None:
    """The model of a table of named tables (``dict[str, Model]``), else None."""
    tp, _ = _unwrap(tp)
    tp, _ = _optional(tp)
    tp, _ = _unwrap(tp)
    if get_origin(tp) is dict:
        value, _ = _unwrap(get_args(tp)[1])
        if _is_model(value) and value is not FreeVariable:
            return value
    return None


def type_text(tp, meta: list | None = None) -> tuple[str, bool]:
    """How a value of annotation ``tp`` is written in TOML, and whether it is a quantity (has a unit)."""
    tp, more = _unwrap(tp)
    meta = list(meta or []) + more
    tp, optional = _optional(tp)
    tp, more = _unwrap(tp)
    meta += more
    text, numeric = _type_text(tp, meta)
    return text, numeric


def _type_text(tp, meta: list) -> tuple[str, bool]:
    override = next((m for m in meta if isinstance(m, TomlType)), None)
    origin, args = get_origin(tp), get_args(tp)
    if origin in (Union, types.UnionType) and FreeVariable in args:
        text, numeric = "number, or {init, bounds} (free)", True
    elif tp is bool:
        text, numeric = "true | false", False
    elif tp is int:
        text, numeric = "integer", False
    elif tp is float:
        text, numeric = "number", True
    elif tp is str:
        text, numeric = ("file (relative to this spec)" if any(isinstance(m, SpecFile) for m in meta) else "string"), False
    elif origin is Literal:
        text, numeric = " | ".join(toml_value(a) for a in args), False
    elif origin is tuple:
        parts = [type_text(a) for a in args if a is not Ellipsis]
        text = "[" + ", ".join(p for p, _ in parts) + (", ..." if Ellipsis in args else "") + "]"
        numeric = any(n for _, n in parts)
    elif origin is list:
        inner, numeric = type_text(args[0])
        text = f"list of {inner}"
    elif origin is dict:
        inner, numeric = type_text(args[1])
        text = f"table of name = {inner}"
    elif origin in (Union, types.UnionType):
        parts = [type_text(a) for a in args]
        text, numeric = " or ".join(p for p, _ in parts), any(n for _, n in parts)
    else:
        text, numeric = getattr(tp, "__name__", str(tp)), False
    return (str(override) if override else text), numeric


def _range_text(meta: list, what: str = "item(s)") -> str:
    out = []
    for m in meta:
        for cls, symbol, attr in ((at.Gt, ">", "gt"), (at.Ge, ">=", "ge"), (at.Lt, "<", "lt"), (at.Le, "<=", "le"),
                                  (at.MultipleOf, "multiple of", "multiple_of")):
            if isinstance(m, cls):
                out.append(f"{symbol} {_num(getattr(m, attr))}")
        if isinstance(m, at.MinLen):
            out.append(f"at least {m.min_length} {what}")
        if isinstance(m, at.MaxLen):
            out.append(f"at most {m.max_length} {what}")
    return ", ".join(out)


def _num(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def _one_line(text: str | None) -> str:
    return " ".join((text or "").split())


def _doc(cls) -> str:
    """The first paragraph of the section's own docstring (or of a base section's; never the generic ones)."""
    for c in cls.__mro__:
        if c in (StrictModel, BaseModel, object):
            break
        doc = c.__dict__.get("__doc__")
        if doc:
            return _one_line(inspect.cleandoc(doc).split("\n\n")[0])
    return ""


def _default_text(field, section: bool) -> str:
    if field.is_required():
        return ""
    if field.default_factory is not None:
        value = field.default_factory()
        if isinstance(value, BaseModel):
            return "(all defaults)"
        return toml_value(value)
    if field.default is None:
        return "unset"
    return toml_value(field.default)


def entries(model: type[BaseModel], prefix: str = "") -> list[Entry]:
    """Every field of ``model`` in file order: first a table's own values, then its sections."""
    values, sections = [], []
    for name, field in model.model_fields.items():
        key = field.alias or name
        path = f"{prefix}{key}"
        sub, many = _section_of(field.annotation)
        default = _default_text(field, sub is not None)
        if sub is not None:
            desc = _one_line(field.description) or _doc(sub)
            head = Entry(path + ("[]" if many else ""), True, many, "list of tables" if many else "table", "",
                         default, _range_text(field.metadata), field.is_required(), desc, False)
            sections.append(head)
            sections += entries(sub, f"{path}[]." if many else f"{path}.")
            continue
        named = _named_sections(field.annotation)
        if named is not None:            # a table of named tables ([key_poses.<name>]): each name's fields below
            sections.append(Entry(path, True, False, "table of named tables", "", default,
                                  _range_text(field.metadata), field.is_required(),
                                  _one_line(field.description) or _doc(named), False))
            sections += entries(named, f"{path}.<name>.")
            continue
        text, numeric = type_text(field.annotation, field.metadata)
        desc = _one_line(field.description)
        # "... by backoff x 10 deg (dimensionless)": a factor whose description names the unit it multiplies
        unit = " or ".join(units_in(desc)) if numeric and not desc.endswith(f"({DIMENSIONLESS})") else ""
        documented = (field.json_schema_extra or {}).get("range", "") if isinstance(field.json_schema_extra,
                                                                                    dict) else ""
        values.append(Entry(path, False, False, text, unit, default,
                            _range_text(field.metadata + _number_arm_meta(field.annotation),
                                        "characters" if field.annotation is str else "item(s)") or documented,
                            field.is_required(), desc, numeric))
    return values + sections


def _number_arm_meta(tp) -> list:
    """The constraints of a "number or table" union's number arm (``Annotated[float, Field(gt=0)] | Range``)."""
    tp, _ = _unwrap(tp)
    if get_origin(tp) not in (Union, types.UnionType):
        return []
    meta = []
    for arg in get_args(tp):
        inner, more = _unwrap(arg)
        if inner in (float, int):
            meta += [m for field_info in more for m in getattr(field_info, "metadata", [field_info])]
    return meta


def missing_descriptions(model: type[BaseModel]) -> list[str]:
    """Fields without a description, and quantities whose description names no unit (nor 'dimensionless')."""
    out = []
    for e in entries(model):
        if not e.description:
            out.append(f"{e.path}: no description")
        elif e.numeric and not e.unit and DIMENSIONLESS not in e.description:
            out.append(f"{e.path}: a quantity without a unit ({', '.join(UNITS)}) or '{DIMENSIONLESS}' "
                       f"in its description: {e.description!r}")
    return out


# ---------------------------------------------------------------------------------------- TOML values

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def toml_key(key: str) -> str:
    return key if _BARE_KEY.match(key) else json.dumps(key, ensure_ascii=False)


def toml_value(v: Any) -> str:
    """One TOML value (inline): floats written by repr, so they read back bit-identical."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        # JSON's escapes are TOML's; DEL is a control character to TOML, not to JSON
        return json.dumps(v, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(v, BaseModel):
        v = v.model_dump(by_alias=True, exclude_none=True)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_key(str(k))} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")


#: a list of lists written inline longer than this is written one item a line
LONG_LIST = 100


def _assignment(key: str, value: Any, lead: str) -> list[str]:
    """``key = value`` as lines: a long list of lists (e.g. a path's control points) one item a line."""
    inline = toml_value(value)
    if len(inline) <= LONG_LIST or not isinstance(value, (list, tuple)) or not all(isinstance(v, (list, tuple))
                                                                                  for v in value):
        return [f"{lead}{key} = {inline}"]
    return [f"{lead}{key} = ["] + [f"{lead}    {toml_value(v)}," for v in value] + [f"{lead}]"]


def _comment(text: str, indent: str = "") -> list[str]:
    return textwrap.wrap(text, width=100, initial_indent=f"{indent}# ", subsequent_indent=f"{indent}#   ")


def _field_note(e: Entry) -> str:
    facts = [e.type, e.range, "required" if e.required else f"default {e.default}"]
    return f"{e.description} [" + "; ".join(f for f in facts if f) + "]"


def write_toml(model: type[BaseModel], data: dict | None, *, documented: bool = True,
               rewrite: dict[str, Any] | None = None) -> list[str]:
    """The lines of a TOML file of ``model`` holding ``data`` (a parsed spec), in the model's field order.

    ``documented``: each field preceded by its description, and every field ``data`` leaves out written
    commented out at its default (sections too).  ``rewrite``: TOML path -> value replacing data's."""
    lines: list[str] = []
    _table(model, data, "", lines, commented=False, documented=documented, rewrite=rewrite or {})
    while lines and not lines[-1]:
        lines.pop()
    return lines


def _table(model, data, prefix, lines, *, commented, documented, rewrite, path_prefix=None) -> None:
    path_prefix = prefix if path_prefix is None else path_prefix
    by_path = {e.path: e for e in entries(model, path_prefix)}
    for name, field in model.model_fields.items():
        key = field.alias or name
        if _section_of(field.annotation)[0] is not None or _named_sections(field.annotation) is not None:
            continue
        e = by_path[f"{path_prefix}{key}"]
        given = data is not None and key in data
        if documented:
            lines += _comment(_field_note(e))
        if given:
            value = rewrite.get(e.path, data[key])
            lines += _assignment(toml_key(key), value, "# " if commented else "")
        elif documented:
            lines.append(f"# {toml_key(key)} = {e.default if e.default not in ('', 'unset') else '<' + e.type + '>'}")
    for name, field in model.model_fields.items():
        key = field.alias or name
        named = _named_sections(field.annotation)
        if named is not None:
            _named_tables(named, key, field, data, prefix, lines, by_path[f"{path_prefix}{key}"],
                          commented=commented, documented=documented, rewrite=rewrite, path_prefix=path_prefix)
            continue
        sub, many = _section_of(field.annotation)
        if sub is None:
            continue
        e = by_path[f"{path_prefix}{key}" + ("[]" if many else "")]
        table_path = f"{prefix}{toml_key(key)}"
        given = data.get(key) if data is not None else None
        if given is None and not documented:
            continue
        if many:
            items = given if given else [None]
            for i, item in enumerate(items):
                lines.append("")
                if documented and i == 0:
                    lines += _comment(f"{e.heading}: {e.description}" + ("" if e.required else " (optional)"))
                off = commented or item is None
                lines.append(f"{'# ' if off else ''}[[{table_path}]]")
                _table(sub, item, f"{table_path}.", lines, commented=off, documented=documented and i == 0, rewrite=_item_rewrite(rewrite, e.path, i),
                       path_prefix=f"{path_prefix}{key}[].")
        else:
            lines.append("")
            if documented:
                lines += _comment(f"[{e.path}]: {e.description}" + ("" if e.required else
                                                                    f" (optional; default {e.default})"))
            off = commented or given is None
            lines.append(f"{'# ' if off else ''}[{table_path}]")
            _table(sub, given, f"{table_path}.", lines, commented=off, documented=documented, rewrite=rewrite,
                   path_prefix=f"{path_prefix}{key}.")


def _named_tables(model, key, field, data, prefix, lines, e, *, commented, documented, rewrite, path_prefix) -> None:
    """A table of named tables ([key_poses.<name>]): each name the data gives as its own table; none given, one
    commented out under the placeholder NAME."""
    given = data.get(key) if data is not None else None
    if not given and not documented:
        return
    items = dict(given) if given else {"NAME": None}
    for i, (name, item) in enumerate(items.items()):
        lines.append("")
        if documented and i == 0:
            lines += _comment(f"[{e.path}.<name>]: {e.description}" + ("" if e.required else " (optional)"))
        off = commented or item is None
        table_path = f"{prefix}{toml_key(key)}.{toml_key(name)}"
        lines.append(f"{'# ' if off else ''}[{table_path}]")
        _table(model, item, f"{table_path}.", lines, commented=off, documented=documented and i == 0,
               rewrite=rewrite, path_prefix=f"{path_prefix}{key}.<name>.")


def _item_rewrite(rewrite: dict, list_path: str, index: int) -> dict:
    """rewrite keys of item ``index`` of a list of tables ("tubes[1].angle") -> the generic item path."""
    head = list_path.removesuffix("[]")
    out = dict(rewrite)
    for k, v in rewrite.items():
        if k.startswith(f"{head}[{index}]."):
            out[f"{head}[]." + k[len(f"{head}[{index}]."):]] = v
        elif k.startswith(f"{head}[]."):
            out.pop(k, None)
    return out


# ---------------------------------------------------------------------------------------- what the CLI shows

def kind_entries(kind_name: str) -> list[Entry]:
    return entries(kinds.get(kind_name).spec_model())


FREE_VARIABLE_NOTE = ("A design variable (type `number, or {init, bounds} (free)`) is fixed by a number and "
                      "freed for `solve` by an inline table `{init = start value, bounds = [lo, hi]}`; "
                      "`check` evaluates `init`.")


def template(kind_name: str, directory: Path | None = None) -> str:
    """A commented starting spec of the kind: its library example written through the model.

    ``directory``: the folder the file will be written in, beside the spec files it names, which
    :func:`template_companions` lists (the names the library example gives them, so the copies are the user's to
    edit); None (the text printed): the spec files are named by their absolute paths in the library, so the text
    checks wherever it is saved."""
    kind = kinds.get(kind_name)
    model = kind.spec_model()
    example = _example_of(kind)
    data, _ = read_toml(example)
    rewrite: dict[str, Any] = {"name": f"my_{kind_name}", "source": f"template from problems/{kind.example}"}
    named = []
    for e, field in _spec_file_fields(model):
        if e in data:
            if directory is None:
                rewrite[e] = str((example.parent / data[e]).resolve())
            named.append(e)
    beside = (["# The spec files it names (" + ", ".join(named) + ") are the library example's, copied beside this "
               "file to edit."] if directory is not None else
              ["# The spec files it names (" + ", ".join(named) + ") are the library's own files: to edit one, copy "
               "it with `agrisynth problems --copy NAME` and name the copy here."]) if named else []
    head = [f"# A {kind_name} spec: {kind.summary}.",
            f"# Written by `agrisynth spec {kind_name} --template` from the library example problems/{kind.example};",
            "# fields left at their default are commented out.  The reference: `agrisynth spec "
            f"{kind_name}` (docs/specs.md in the source tree).",
            *_comment(FREE_VARIABLE_NOTE), *beside, ""]
    return "\n".join(head + write_toml(model, data, rewrite=rewrite)) + "\n"


def _example_of(kind) -> Path:
    if not kind.example:
        raise ValueError(f"kind {kind.name!r} names no library example (Kind.example) to start a template from")
    return LIBRARY / kind.example


def template_companions(kind_name: str) -> list[tuple[Path, str]]:
    """(library file, name relative to the template) of each spec file the kind's template written into a folder
    names: the library example's own spec files, by the names the example gives them (inside its folder)."""
    kind = kinds.get(kind_name)
    example = _example_of(kind)
    data, _ = read_toml(example)
    return [((example.parent / data[e]).resolve(), str(data[e]))
            for e, _ in _spec_file_fields(kind.spec_model()) if e in data]


def _spec_file_fields(model):
    for name, field in model.model_fields.items():
        if any(isinstance(m, SpecFile) for m in field.metadata):
            yield field.alias or name, field


def markdown(kind_names: list[str] | None = None) -> str:
    """docs/specs.md: the reference of every registered kind (a kind whose package does not import is
    named, with the error, instead of its table)."""
    names = kinds.names() if kind_names is None else kind_names
    out = ["# Spec reference", "",
           f"Generated from the spec models by `{REGENERATE}`; do not edit by hand (a test fails when it is stale).",
           "The same reference for one kind: `agrisynth spec KIND`; a commented starting file: "
           "`agrisynth spec KIND --template`.", "",
           "Units: lengths mm, angles deg, time s, speeds m/s, crank speeds r/min. " + FREE_VARIABLE_NOTE, "",
           "Kinds: " + ", ".join(f"[`{n}`](#{n})" for n in names), ""]
    for name in names:
        out += [f"## {name}", ""]
        try:
            kind = kinds.get(name)
            rows = entries(kind.spec_model())
        except Exception as exc:    # noqa: BLE001 - a kind being written by someone else: say so, keep the rest
            out += [f"Not documented: its package does not import ({type(exc).__name__}: {exc}).", ""]
            continue
        out += [f"{kind.summary}." + (f" Example: `problems/{kind.example}`." if kind.example else ""), ""]
        out += ["| TOML path | type | unit | default | range | description |", "|---|---|---|---|---|---|"]
        for e in rows:
            cells = [f"**{e.heading}**" if e.section else f"`{e.path}`", e.type, e.unit,
                     "required" if e.required else e.default, e.range, e.description]
            out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        out.append("")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if checkout() is None:
        print(f"{DOCS.relative_to(IMPORT_ROOT)} belongs to agrisynth's source checkout; this agrisynth is installed "
              f"from {IMPORT_ROOT}: run `{REGENERATE}` in a checkout")
        return 2
    text = markdown()
    if argv == ["--check"]:
        current = DOCS.read_text() if DOCS.exists() else ""
        if current != text:
            print(f"{DOCS} is stale: run `{REGENERATE}`")
            return 1
        return 0
    if argv:
        print(f"usage: {REGENERATE} [--check]")
        return 2
    DOCS.parent.mkdir(exist_ok=True)
    DOCS.write_text(text)
    print(f"wrote {DOCS}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
