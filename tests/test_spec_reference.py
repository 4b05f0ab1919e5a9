"""The spec reference (`agrisynth spec KIND`, `--template`, docs/specs.md), generated from the spec models.

Every registered kind is covered, including kinds added after this file was written: the tests iterate
the registry.  A kind whose package does not import is skipped with the import error as the reason.
"""

from __future__ import annotations

import re
import tomllib

import pytest
from click.testing import CliRunner

from conftest import LIBRARY
from synthesis import kinds
from synthesis.spec import reference as specref
from synthesis.cli import cli
from synthesis.spec import load_spec
from synthesis.spec.common import read_toml
from solving import agrisynth


def _kind(name: str):
    try:
        kind = kinds.get(name)
        return kind, kind.spec_model()
    except Exception as exc:    # noqa: BLE001 - a kind another session is still writing
        pytest.skip(f"kind {name}: its package does not import ({type(exc).__name__}: {exc})")


@pytest.fixture(params=kinds.names())
def kind_name(request) -> str:
    return request.param


def test_every_field_has_a_description_and_a_unit(kind_name):
    _, model = _kind(kind_name)
    assert specref.missing_descriptions(model) == []


def test_template_validates_and_checks_like_its_example(kind_name, tmp_path):
    kind, model = _kind(kind_name)
    assert kind.example, f"{kind_name}: Kind.example names no library spec to start a template from"
    path = tmp_path / "sub" / "start.toml"
    path.parent.mkdir()
    result = CliRunner().invoke(cli, ["spec", kind_name, "--template", "--out", str(path)])
    assert result.exit_code == 0, result.output
    printed = tmp_path / "elsewhere" / "printed.toml"           # the printed text, saved anywhere
    printed.parent.mkdir()
    printed.write_text(specref.template(kind_name))
    example = specref.LIBRARY / kind.example
    expected = kinds.checker(kind_name)(load_spec(example)).rules
    for written in (path, printed):
        loaded = load_spec(written)                               # validates
        assert loaded.kind == kind_name and loaded.name == f"my_{kind_name}"
        # nothing of the example is lost: the same data apart from name and source (spec files: beside the file
        # written, with the library's bytes; the printed text names the library's own)
        ours, theirs = tomllib.loads(written.read_text()), read_toml(example)[0]
        for key in ("name", "source"):
            ours.pop(key), theirs.pop(key, None)
        for key, _ in specref._spec_file_fields(model):
            if key in theirs:
                named, library_file = written.parent / ours.pop(key), example.parent / theirs.pop(key)
                if written == path:
                    assert named.parent == path.parent and named.read_bytes() == library_file.read_bytes()
                else:
                    assert named == library_file.resolve()
        assert ours == theirs
        # and `check` runs on it, with the example's rule table
        rules = kinds.checker(kind_name)(loaded).rules
        assert [(r["name"], r["value"], r["satisfied"]) for r in rules] == \
            [(r["name"], r["value"], r["satisfied"]) for r in expected]


def test_a_template_s_spec_files_go_beside_it_and_are_never_replaced(tmp_path):
    """The picker's template names two linkage specs: written into a folder, they are copied beside it (moved with
    it, it still checks); a file of one's name that is not the library's stops the template before anything is
    written; one with the library's bytes is used as it is."""
    folder = tmp_path / "mine"
    folder.mkdir()
    result = CliRunner().invoke(cli, ["spec", "picker", "--template", "--out", str(folder / "p.toml")])
    assert result.exit_code == 0, result.output
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["cai2020_crank_rocker.toml", "cai2020_double_crank.toml", "p.toml"], names
    moved = tmp_path / "moved"
    folder.rename(moved)
    assert kinds.checker("picker")(load_spec(moved / "p.toml")).rules
    # a second template beside the first: the linkages there are the library's, used as they are
    result = CliRunner().invoke(cli, ["spec", "picker", "--template", "--out", str(moved / "q.toml")])
    assert result.exit_code == 0, result.output
    # an edited linkage is never replaced: refused, nothing written
    (moved / "cai2020_crank_rocker.toml").write_text("# edited\n")
    result = agrisynth("spec", "picker", "--template", "--out", str(moved / "r.toml"))
    assert result.returncode == 2 and "is not the library's cai2020_crank_rocker.toml" in result.stderr, result.stderr
    assert "Traceback" not in result.stderr
    assert not (moved / "r.toml").exists()


def test_template_comments_every_field(kind_name):
    _, model = _kind(kind_name)
    text = specref.template(kind_name)
    for e in specref.entries(model):
        if not e.section:
            key = e.path.rsplit(".", 1)[-1]
            assert f"\n{key} = " in text or f"\n# {key} = " in text, e.path
        assert e.description.split()[0] in text


def test_reference_lists_every_field(kind_name):
    _, model = _kind(kind_name)
    result = CliRunner().invoke(cli, ["spec", kind_name])
    assert result.exit_code == 0, result.output
    for e in specref.entries(model):
        assert (e.heading if e.section else e.path) in result.output
        # piped: folded at 120 characters, never cut (the description's words in order, whatever the line breaks)
        assert " ".join(e.description.split()) in " ".join(result.output.split())
    assert max(len(line) for line in result.output.splitlines()) <= 120


def test_docs_specs_md_is_current():
    """docs/specs.md is generated; regenerate it with `python -m synthesis.spec.reference` when a model changes."""
    current = specref.DOCS.read_text() if specref.DOCS.exists() else ""
    assert current == specref.markdown(), f"docs/specs.md is stale: run `{specref.REGENERATE}`"
    for name in kinds.names():
        assert f"\n## {name}\n" in current


def test_reference_reads_units_and_ranges():
    rows = {e.path: e for e in specref.kind_entries("planting_fourbar")}
    assert (rows["arm.l2"].unit, rows["arm.l2"].required) == ("mm", True)
    assert rows["arm.l2"].type == "number, or {init, bounds} (free)"
    assert (rows["operation.crank_speed"].unit, rows["operation.crank_speed"].range) == ("r/min", "> 0, <= 2000")
    assert (rows["rules.p1p3"].default, rows["solver.starts"].default) == ("unset", "16")   # follows seedling_height
    assert rows["rules"].section and not rows["rules"].required
    path = {e.path: e for e in specref.kind_entries("fourbar_path")}
    assert path["linkage.rcy"].unit == "mm"           # "(90 deg counter-clockwise), mm": the aside is not the unit
    assert path["linkage.r1"].type == "number, or {init, bounds} (free)"
    tubes = {e.path: e for e in specref.kind_entries("guide_tube")}
    assert tubes["tubes[]"].many and tubes["tubes[].angle"].unit == "deg"


#: a name with a hyphen between letters ("crank-rocker"); signs such as guide_way's form "y-" are not names
HYPHENATED = re.compile(r"[a-z]-[a-z]")


@pytest.mark.parametrize("kind_name", kinds.names())
def test_one_way_to_write_a_variable_and_one_spelling_of_names(kind_name):
    """Every design variable is a number (fixed) or {init, bounds} (free), never a [lo, hi] pair
    of its own; every linkage assembly is branch = -1 | 1; every named choice is written with underscores."""
    entries = specref.kind_entries(kind_name)
    for e in entries:
        assert "[lo, hi] (frees it)" not in e.type, e.path
        if e.path.rsplit(".", 1)[-1] == "branch":
            assert e.type == "-1 | 1", (e.path, e.type)
        for choice in re.findall(r'"([^"]*)"', e.type):
            assert not HYPHENATED.search(choice), (e.path, choice)
    variables = getattr(kinds.get(kind_name).spec_model(), "variables", None)
    if kinds.get(kind_name).solves and kind_name != "guide_way":     # guide_way frees its path's control points
        assert callable(variables), f"{kind_name}: the spec model lists its design variables (variables())"


def test_spec_command_errors_are_one_line(tmp_path):
    unknown = agrisynth("spec", "planting_forbar", timeout=120)
    assert unknown.returncode == 2 and unknown.stdout == ""
    assert unknown.stderr.startswith("error: unknown kind 'planting_forbar' (did you mean planting_fourbar? known kinds: ")
    assert len(unknown.stderr.strip().splitlines()) == 1
    runner = CliRunner()
    existing = tmp_path / "mine.toml"
    existing.write_text("keep me")
    refused = runner.invoke(cli, ["spec", "crank_rocker", "--template", "--out", str(existing)])
    assert refused.exit_code != 0 and "already exists" in str(refused.exception)
    assert existing.read_text() == "keep me"
    written = runner.invoke(cli, ["spec", "crank_rocker", "--template", "--out", str(tmp_path / "new.toml")])
    assert written.exit_code == 0 and load_spec(tmp_path / "new.toml").kind == "crank_rocker"


def test_piped_problems_table_never_cuts_a_file_name():
    proc = agrisynth("problems", timeout=120)
    assert proc.returncode == 0, proc.stderr
    for path in sorted(specref.LIBRARY.rglob("*.toml")):
        assert str(path.relative_to(specref.LIBRARY)) in proc.stdout
    assert "…" not in proc.stdout
    # piped: folded at 120 characters ($COLUMNS unset), a file name kept whole on its line
    assert max(len(line) for line in proc.stdout.splitlines()) <= 120


def _documented_ranges(model):
    """(TOML path, range text) of every design variable whose range a validator enforces (json_schema_extra)."""
    from synthesis.spec.design_info import walk_fields

    return [(path, field.json_schema_extra["range"]) for path, field, _ in walk_fields(model)
            if isinstance(field.json_schema_extra, dict) and "range" in field.json_schema_extra]


def test_a_documented_range_is_the_one_the_loader_enforces(kind_name):
    """The range column names "> 0" or ">= lo, <= hi" for the design variables a validator checks (a trial:
    tillage's theta and a crank-rocker's links showed no range though the loader refused values outside one).
    Beyond each stated limit the kind's example spec is refused, naming the field."""
    import copy

    from synthesis.errors import SpecError
    from synthesis.spec.common import validate

    kind, model = _kind(kind_name)
    if kind.example is None:
        pytest.skip(f"{kind_name}: no example spec")
    path = LIBRARY / kind.example
    loaded = load_spec(path)
    data = tomllib.loads(path.read_text())
    def table_at(root, dotted: str):         # "tubes[0]" -> root["tubes"][0]
        node = root
        for part in dotted.split("."):
            key, _, index = part.partition("[")
            node = node[key] if not index else node[key][int(index.rstrip("]"))]
        return node

    documented = _documented_ranges(loaded.model)
    for field_path, text in documented:
        section, name = field_path.rsplit(".", 1)
        for bound in text.split(", "):
            symbol, number = bound.split(" ")
            limit = float(number)
            edited = copy.deepcopy(data)
            table_at(edited, section)[name] = {">": limit, ">=": limit - 1.0, "<=": limit + 1.0, "<": limit}[symbol]
            with pytest.raises(SpecError, match=re.escape(name)):
                validate(model, edited, prefix=kind_name)


def test_a_template_named_as_a_folder_that_is_not_there_is_refused(tmp_path):
    proc = agrisynth("spec", "comb_finger", "--template", "--out", "tdir/", cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and "tdir/: names a folder (it ends in /) and there is no folder tdir" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and list(tmp_path.iterdir()) == []


def test_a_type_s_alternatives_do_not_shift_the_piped_reference_s_columns():
    """The piped reference separates its columns by " | ": a type written `integer | "auto"` made six of five."""
    result = CliRunner().invoke(cli, ["spec", "crank_rocker"])
    line = next(line for line in result.output.splitlines() if line.startswith("  solver.starts | "))
    assert line.split(" | ") == ["  solver.starts", 'integer or "auto"', "", "8", ">= 1, <= 10000"], line


def test_a_template_named_as_a_spec_file_it_names_is_refused_and_nothing_is_written(tmp_path):
    """`spec picker --template --out cai2020_crank_rocker.toml` copied the linkage there, then wrote the template over
    it: a picker spec naming itself as its crank-rocker (check: "is a 'picker' spec, expected kind 'crank_rocker'")."""
    proc = agrisynth("spec", "picker", "--template", "--out", "cai2020_crank_rocker.toml", cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and "the template names a spec file of this name beside it" in proc.stderr
    assert list(tmp_path.iterdir()) == []
