"""A loader no file can break: hypothesis mutates each kind's library spec (fields missing, extra,
wrongly typed, non-finite, huge, negative, empty, nested, unicode, whole files of random bytes) and runs
``check`` in-process.  Every document either is refused as bad input (an AgrisynthError: one message, exit 2)
or checks to a result whose JSON has no NaN or infinity -- never any other exception (a traceback).

100 documents per kind in the default suite; ``pytest -m fuzz`` runs 300 per kind, with the rest of the fuzz
campaign (tests/test_fuzz_campaign.py, tests/test_soak.py).  Both are derandomized: CI sees the same documents
every run, so a failure there reproduces.
Also: spec files are data -- no eval/exec/pickle/yaml.load/shell=True/os.system in the source.
"""

from __future__ import annotations

import json
import sys
import math
import re
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import LIBRARY, ROOT
from synthesis import kinds
from synthesis.errors import AgrisynthError
from synthesis.result import result_text
from synthesis.spec import load_spec


def library_kinds() -> list[str]:
    """Kinds with an example spec in problems/ (a kind still being built, without one, is skipped)."""
    return [k.name for k in kinds.all_kinds() if k.example and (LIBRARY / k.example).is_file()]


# --- a TOML writer for arbitrary documents (inline tables: any nesting on one line) -----------------------

def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return "{" + ", ".join(f"{json.dumps(str(k), ensure_ascii=False)} = {toml_value(x)}" for k, x in v.items()) + "}"


def toml_document(data: dict) -> str:
    # the campaign's hostile documents nest lists 400 deep (and deeper when two such edits meet): two frames a level
    # here, so the writer, not the tool under test, would hit Python's default limit of 1000
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10000))
    try:
        return "".join(f"{json.dumps(str(k), ensure_ascii=False)} = {toml_value(v)}\n" for k, v in data.items())
    finally:
        sys.setrecursionlimit(limit)


def paths(data, prefix=()) -> list[tuple]:
    out = [prefix] if prefix else []
    if isinstance(data, dict):
        for k, v in data.items():
            out += paths(v, prefix + (k,))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            out += paths(v, prefix + (i,))
    return out


scalars = st.one_of(
    st.booleans(), st.integers(), st.integers(min_value=-10, max_value=10),
    st.floats(allow_nan=True, allow_infinity=True), st.floats(-1e3, 1e3), st.sampled_from([0.0, -0.0, 1e308, -1e308,
                                                                                          5e-324, 1e12, 1e13]),
    st.text(max_size=40), st.sampled_from(["", "75", "nan", "inf", "1e3", "true", "../x", "a/b", "x" * 300]),
)
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=5),
                                                        st.dictionaries(st.text(max_size=8), inner, max_size=4)),
                      max_leaves=12)


@st.composite
def documents(draw, base: dict):
    """A mutated copy of ``base`` (or, now and then, random bytes)."""
    if draw(st.integers(0, 19)) == 0:
        return draw(st.binary(max_size=300))
    data = json.loads(json.dumps(base))
    for _ in range(draw(st.integers(1, 3))):
        where = draw(st.sampled_from(paths(data) or [("kind",)]))
        parent = data
        for part in where[:-1]:
            parent = parent[part]
        key = where[-1]
        op = draw(st.sampled_from(["number", "number", "number", "replace", "replace", "delete", "extra", "nest"]))
        old = parent[key]
        if op == "number":        # a valid document with a strange value: reaches the model code
            if isinstance(old, (int, float)) and not isinstance(old, bool):
                new = draw(st.one_of(st.floats(-1e4, 1e4), st.sampled_from([0, -1, 1e-9, 1e9, -1e9, 1e12]),
                                     st.floats(0.5, 2.0).map(lambda f: old * f), st.just(-old)))
                parent[key] = int(new) if isinstance(old, int) and abs(new) < 2**53 else new
        elif op == "replace":
            parent[key] = draw(values)
        elif op == "delete":
            if isinstance(parent, dict):
                del parent[key]
            elif isinstance(parent, list) and parent:
                parent.pop(key)
        elif op == "extra":
            target = parent if isinstance(parent, dict) else data
            target[draw(st.text(min_size=1, max_size=10))] = draw(values)
        else:
            deep = draw(values)
            for _ in range(draw(st.integers(1, 40))):
                deep = {"x": deep} if draw(st.booleans()) else [deep]
            parent[key] = deep
    return toml_document(data).encode("utf-8")


REACHED = {"check": 0}


def check_in_process(raw: bytes, folder: Path) -> None:
    """What ``agrisynth check`` does before the figures: load, check, result.json's text."""
    path = folder / "fuzzed_spec.toml"
    path.write_bytes(raw)
    try:
        loaded = load_spec(path)
        result = kinds.checker(loaded.kind)(loaded)
    except AgrisynthError as exc:
        assert exc.exit_code in (2, 3) and str(exc).strip()
        return
    REACHED["check"] += 1
    data = json.loads(result_text(result))          # raises on NaN/inf: result_text must have replaced them
    assert data["status"] == "evaluated"
    for name, value in loaded.model.design_values().items() if hasattr(loaded.model, "design_values") else ():
        assert not isinstance(value, float) or math.isfinite(value), (name, value)


def fuzz(kind: str, examples: int, tmp_path: Path, derandomize: bool = False) -> None:
    example = LIBRARY / kinds.get(kind).example
    base = tomllib.loads(example.read_text())
    for sibling in example.parent.glob("*.toml"):     # specs a spec refers to (the picker's two linkages)
        (tmp_path / sibling.name).write_bytes(sibling.read_bytes())

    @settings(max_examples=examples, deadline=None, database=None, derandomize=derandomize,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(documents(base))
    def run(raw):
        check_in_process(raw, tmp_path)

    before = REACHED["check"]
    run()
    print(f"{kind}: {examples} documents, {REACHED['check'] - before} reached a result")


#: the kinds whose 100 documents take seconds: run with the slow tests (the study below fuzzes every kind)
SLOW_TO_FUZZ = {"clamp_cam", "comb_finger", "combing_chain", "crank_rocker", "fourbar_path", "guide_way", "picker",
                "planting_fourbar", "rotary_planetary", "steering_linkage", "tillage_linkage"}


@pytest.mark.parametrize("kind", [pytest.param(k, marks=pytest.mark.slow) if k in SLOW_TO_FUZZ else k
                                  for k in library_kinds()])
def test_no_spec_document_crashes_check(kind, tmp_path):
    # the default suite sees the same 100 documents every run (deterministic CI)
    fuzz(kind, 100, tmp_path, derandomize=True)


@pytest.mark.fuzz
@pytest.mark.parametrize("kind", library_kinds())
def test_no_spec_document_crashes_check_study(kind, tmp_path):
    fuzz(kind, 300, tmp_path, derandomize=True)


FORBIDDEN = re.compile(r"\b(eval|exec)\s*\(|\bpickle\b|yaml\.load\b|shell\s*=\s*True|os\.system\b|"
                       r"__import__\s*\(|importlib\.import_module\s*\(")


def test_spec_files_are_data_no_code_runs_from_them():
    """No eval/exec/pickle/yaml.load/shell=True/os.system anywhere in agrisynth; a module is imported by name only
    by the registry, the package of a kind folder it found on disk (synthesis/kinds/__init__.py), and from constant
    tables: the command line's command modules and the run layer's (cli/ and runs/__init__.py), never from spec text (a spec's kind is looked up among those folders' kinds)."""
    hits = []
    for path in sorted((ROOT / "synthesis").rglob("*.py")):
        for n, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0]
            registry = (path == ROOT / "synthesis" / "kinds" / "__init__.py"
                        and 'importlib.import_module(f"{__name__}.{folder}")' in code)
            # the command line's own table of its command modules (a constant, never spec text)
            registry |= (path == ROOT / "synthesis" / "cli" / "__init__.py"
                         and "importlib.import_module(COMMANDS[name][0])" in code)
            # the run layer's functions, each imported with its module when first used (a constant table)
            registry |= (path == ROOT / "synthesis" / "runs" / "__init__.py"
                         and 'importlib.import_module(f"synthesis.runs.{_RUNS[name]}")' in code)
            if FORBIDDEN.search(code) and not registry:
                hits.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert hits == []


def test_a_spec_with_many_bad_fields_gets_a_few_lines_naming_the_first(tmp_path):
    """One line per problem, the first naming the first bad field, at most 5 lines ("... and N more")."""
    from synthesis.spec.common import MAX_PROBLEM_LINES

    base = tomllib.loads((LIBRARY / "planting_arm" / "taiwan_example1.toml").read_text())
    base["arm"] = {k: f"{v} mm" if isinstance(v, (int, float)) and not isinstance(v, bool) else v
                   for k, v in base["arm"].items()}
    for i in range(30):
        base[f"extra{i}"] = 1
    path = tmp_path / "many.toml"
    path.write_text(toml_document(base))
    with pytest.raises(AgrisynthError) as err:
        load_spec(path)
    lines = str(err.value).splitlines()
    assert len(lines) == MAX_PROBLEM_LINES and err.value.exit_code == 2
    assert "planting_fourbar.arm.l1: expected a number in mm, written without a unit, got '75 mm'" in lines[0]
    assert re.fullmatch(r"\.\.\. and \d+ more problem\(s\) in the spec \(fix these first\)", lines[-1])
    assert not any("expected a table" in ln for ln in lines)     # the number|table union says it once
