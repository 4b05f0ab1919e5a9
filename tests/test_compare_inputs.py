"""`agrisynth compare` and result files no one should trust: every malformed file is refused with
one line naming it (exit 2) before anything is drawn -- never a traceback, a hang or a page with NaN.

The default suite runs the catalogue below (each refused at load, so it is fast); ``pytest -m fuzz`` adds a
hypothesis study that mutates a real result.json and runs the whole compare, drawing included.
"""

from __future__ import annotations

import copy
import json
import os
import re
from pathlib import Path

import pytest

from conftest import PLANTING
from synthesis import kinds
from synthesis.report.compare import load_candidates, write_comparison
from synthesis.errors import AgrisynthError
from synthesis.result import result_text
from synthesis.spec import load_spec
from solving import agrisynth


@pytest.fixture(scope="module")
def good(tmp_path_factory) -> tuple[Path, dict]:
    """A real result.json (seed 000 example 1, checked) and its data."""
    folder = tmp_path_factory.mktemp("good")
    loaded = load_spec(PLANTING / "taiwan_example1.toml")
    (folder / "result.json").write_text(result_text(kinds.checker(loaded.kind)(loaded)))
    return folder / "result.json", json.loads((folder / "result.json").read_text())


def _edit(base: dict, change) -> bytes:
    data = copy.deepcopy(base)
    change(data)
    return json.dumps(data).encode()


def _rule(key, value):
    return lambda d: d["rules"][0].update({key: value})


def _raw_number(base: dict, key: str, text: str) -> bytes:
    """rules[0][key] written as a bare JSON token (NaN, Infinity, 1e400, 5,001 digits)."""
    return _edit(base, _rule(key, "@@")).replace(b'"@@"', text.encode())


def malformed(base: dict) -> dict[str, bytes]:
    utf8 = json.dumps(base).encode()
    return {
        "not_utf8": b'{"kind": "\xff\xfe"}',
        "latin1": utf8.replace(b'"kind"', b'"k\xe9ind"'),
        "utf16": json.dumps(base).encode("utf-16"),
        "bom": b"\xef\xbb\xbf" + utf8,
        "empty": b"",
        "nul_bytes": b"\x00" * 1000,
        "truncated": utf8[:300],
        "nested_list": b"[" * 100_000 + b"]" * 100_000,
        "nested_object": b'{"a":' * 50_000 + b"1" + b"}" * 50_000,
        "nested_in_rules": utf8.replace(b'"rules": [', b'"rules": [' + b"[" * 3000 + b"]" * 3000 + b",", 1),
        "top_level_list": b"[1, 2]",
        "digits_5001": _raw_number(base, "value", "9" * 5001),
        "nan_value": _raw_number(base, "value", "NaN"),
        "infinite_margin": _raw_number(base, "margin", "-Infinity"),
        "overflowing_value": _raw_number(base, "value", "1e400"),
        "overflowing_design": _edit(base, lambda d: d["design"].update(l1="@@")).replace(b'"@@"', b"1e999"),
        "string_value": _edit(base, _rule("value", "12.5")),
        "string_margin": _edit(base, _rule("margin", "lots")),
        "string_normalised_margin": _edit(base, _rule("normalised_margin", "x")),
        "string_limit": _edit(base, _rule("limit", ["0", 1])),
        "boolean_limit": _edit(base, _rule("limit", [True, None])),
        "scalar_limit": _edit(base, _rule("limit", 3.0)),
        "numeric_unit": _edit(base, _rule("unit", 5)),
        "list_where": _edit(base, _rule("where", ["P1", "P6"])),        # found by the fuzz campaign
        "object_note": _edit(base, _rule("note", {"why": 1})),
        "string_satisfied": _edit(base, _rule("satisfied", "true")),
        "numeric_rule_name": _edit(base, _rule("name", 7)),
        "huge_rule_name": _edit(base, _rule("name", "r" * 200_000)),
        "rules_object": _edit(base, lambda d: d.update(rules={"a": 1})),
        "rules_strings": _edit(base, lambda d: d.update(rules=["a", "b"])),
        "missing_rules": _edit(base, lambda d: d.pop("rules")),
        "kind_list": _edit(base, lambda d: d.update(kind=["planting_fourbar"])),
        "kind_unknown": _edit(base, lambda d: d.update(kind="teleporter")),
        "huge_name": _edit(base, lambda d: d.update(name="<script>alert(1)</script>" * 1000)),
        "status_unknown": _edit(base, lambda d: d.update(status="great")),
        "schema_string": _edit(base, lambda d: d.update(schema_version="2")),
        "schema_future": _edit(base, lambda d: d.update(schema_version=99)),
        "design_list": _edit(base, lambda d: d.update(design=[1, 2])),
        "design_nested": _edit(base, lambda d: d.update(design={k: {"a": [1]} for k in d["design"]})),
        # version 3 on: every design entry a number or a list of numbers (compare showed "long" in the table)
        "design_string": _edit(base, lambda d: d["design"].update(l2="long")),
        "design_boolean": _edit(base, lambda d: d["design"].update(l2=True)),
        "design_list_of_strings": _edit(base, lambda d: d["design"].update(l2=["a", 1])),
        "design_variables_numbers": _edit(base, lambda d: d.update(design_variables={"l1": 5})),
        # the fuzz campaign's find: bounds of one number crashed the design table's at-bound marks
        "design_variables_one_bound": _edit(base, lambda d: d.update(
            design_variables={"l2": {"path": "arm.l2", "unit": "mm", "bounds": [0], "free": True}})),
        "design_variables_string_free": _edit(base, lambda d: d.update(
            design_variables={"l2": {"path": "arm.l2", "unit": "mm", "bounds": None, "free": "yes"}})),
        "objective_string_value": _edit(base, lambda d: d.update(objective={"name": "x", "value": "low"})),
        "objective_list": _edit(base, lambda d: d.update(objective=[1])),
        "solver_list": _edit(base, lambda d: d.update(solver=[1])),
        "trajectory_list": _edit(base, lambda d: d.update(trajectory=[1, 2])),
    }


def _special(name: str, folder: Path) -> Path:
    path = folder / f"{name}.json"
    if name == "fifo":
        os.mkfifo(path)
    elif name == "dev_zero_link":
        path.symlink_to("/dev/zero")
    elif name == "oversized":
        with open(path, "wb") as fh:
            fh.truncate(600 * 1024**2)        # sparse, larger than a result may be
    elif name == "folder_without_result":
        path.mkdir()
    return path


SPECIAL = ("fifo", "dev_zero_link", "oversized", "folder_without_result", "missing")


def _refused(paths: list[Path]) -> str:
    with pytest.raises(AgrisynthError) as err:
        load_candidates(paths)
    message = str(err.value)
    assert err.value.exit_code == 2 and "\n" not in message and len(message) < 400, message
    return message


def test_every_malformed_result_file_is_refused_in_one_line(good, tmp_path):
    path, base = good
    cases = malformed(base)
    assert len(cases) + len(SPECIAL) >= 40
    for name, raw in cases.items():
        bad = tmp_path / f"{name}.json"
        bad.write_bytes(raw)
        assert str(bad) in _refused([path, bad]), name
    for name in SPECIAL:
        bad = _special(name, tmp_path)
        assert str(bad) in _refused([path, bad]), name


def test_compare_cli_refuses_a_fifo_and_non_utf8_in_one_line_and_writes_nothing(good, tmp_path):
    path, _ = good
    fifo = _special("fifo", tmp_path)
    latin = tmp_path / "latin.json"
    latin.write_bytes(b'{"kind": "\xe9"}')
    proc = agrisynth("compare", str(path), str(fifo), "--out", str(tmp_path / "cmp"), timeout=60)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and str(fifo) in proc.stderr
    from test_run_folders import cli_in_process

    code, err = cli_in_process("compare", str(path), str(latin), "--out", str(tmp_path / "cmp"))
    assert code == 2 and len(err.strip().splitlines()) == 1 and f"{latin}: not a UTF-8 text file" in err, err
    assert not (tmp_path / "cmp").exists()


@pytest.mark.slow          # a whole comparison page: seconds
@pytest.mark.parametrize("where", ["operation", "vehicle", "envelope", "cam"])
def test_a_result_whose_condition_table_is_not_a_table_compares_without_it(good, tmp_path, where):
    """facts.<where> = true (a hand-edited file; the fuzz campaign's find for `operation`): the page is written, the
    other candidate's conditions shown, no traceback."""
    path, base = good
    bad = tmp_path / "bad.json"
    bad.write_bytes(_edit(base, lambda data: data["facts"].__setitem__(where, True)))
    page = write_comparison(load_candidates([path, bad]), tmp_path / "cmp")
    assert "forward speed" in page.read_text()


@pytest.mark.slow
def test_compare_never_writes_over_or_into_a_result_it_compares(tmp_path):
    """--out naming a RESULT folder (with --force, which replaces an agrisynth folder) or a folder inside it is refused
    in one line (exit 2) before anything is written: the page would replace, or sit in, what it compares."""
    from test_run_folders import cli_in_process

    for name in ("a", "b"):
        code, _ = cli_in_process("check", str(PLANTING / "taiwan_example1.toml"), "--out", str(tmp_path / name))
        assert code == 1
    a, b = tmp_path / "a" / "taiwan_example1-check", tmp_path / "b" / "taiwan_example1-check"
    before = sorted(p.name for p in a.iterdir())
    for out in (a, a / "cmp"):
        code, err = cli_in_process("compare", str(a), str(b), "--out", str(out), "--force")
        assert code == 2 and len(err.strip().splitlines()) == 1 and f"holds or is inside RESULT {a}" in err, err
        assert sorted(p.name for p in a.iterdir()) == before
    code, err = cli_in_process("compare", str(b), str(a / "result.json"), "--out", str(a), "--force")
    assert code == 2 and "holds or is inside RESULT" in err
    code, err = cli_in_process("compare", str(a / "result.json"), str(b), "--out", str(a / "cmp"))
    assert code == 2 and "holds or is inside RESULT" in err and not (a / "cmp").exists()
    loop = tmp_path / "loop"
    loop.symlink_to(loop)                          # a symlink loop is the loader's to name, in one line
    for args in ((str(loop), str(b), "--out", str(tmp_path / "c1")), (str(a), str(b), "--out", str(loop))):
        code, err = cli_in_process("compare", *args)
        assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    proc = agrisynth("compare", str(a), str(b), "--out", str(tmp_path / "cmp"), timeout=120)
    assert proc.returncode == 0 and (tmp_path / "cmp" / "compare.html").is_file(), proc.stderr


# --- the study: mutate a real result.json and run the whole compare (pytest -m fuzz) ---------------------

@pytest.mark.fuzz
def test_no_mutated_result_file_crashes_compare(good, tmp_path):
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    path, base = good
    leaves = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=False, allow_infinity=False),
                       st.sampled_from([1e308, -1e308, 5e-324, 0.0, -0.0]), st.text(max_size=30))
    values = st.recursive(leaves, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                          st.dictionaries(st.text(max_size=6), inner, max_size=3)),
                          max_leaves=8)
    keys = ["design", "rules", "objective", "solver", "trajectory", "facts", "versions", "design_variables",
            "starts", "elastic", "baseline_design", "status", "name"]
    runs = {"n": 0}

    @settings(max_examples=60, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(st.sampled_from(keys), st.integers(0, 50), values)
    def run(key, which, value):
        data = copy.deepcopy(base)
        target = data.get(key)
        if isinstance(target, dict) and target:
            target[sorted(target)[which % len(target)]] = value
        elif isinstance(target, list) and target:
            entry = target[which % len(target)]
            if isinstance(entry, dict) and entry:
                entry[sorted(entry)[which % len(entry)]] = value
            else:
                target[which % len(target)] = value
        else:
            data[key] = value
        runs["n"] += 1
        bad = tmp_path / f"m{runs['n']}.json"
        bad.write_text(json.dumps(data))
        try:
            page = write_comparison(load_candidates([path, bad]), tmp_path / f"cmp{runs['n']}")
        except AgrisynthError as exc:
            assert exc.exit_code == 2 and "\n" not in str(exc)
            return
        # no number shown as NaN; a figure that cannot be drawn says why in words, which may quote matplotlib's
        # "Axis limits cannot be NaN or Inf" (a mutated design that does not assemble)
        shown = re.sub(r"comparison figures not drawn: [^<]*", "", page.read_text())
        assert "NaN" not in shown

    run()


@pytest.mark.slow
def test_candidates_of_different_agrisynth_versions_are_said_on_the_terminal_and_the_page(good, tmp_path):
    path, base = good
    other = tmp_path / "other.json"
    other.write_bytes(_edit(base, lambda data: data["versions"].__setitem__("agrisynth", "9.9.9")))
    same = tmp_path / "same.json"
    same.write_bytes(_edit(base, lambda data: None))
    proc = agrisynth("compare", str(path), str(other), "--out", str(tmp_path / "cmp"), cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    said = " ".join((proc.stdout + proc.stderr).split())
    version = base["versions"]["agrisynth"]
    assert re.search(rf"written by different versions of agrisynth \(.*: {re.escape(version)}, .*: 9\.9\.9\)", said), said
    assert "different versions of agrisynth" in (tmp_path / "cmp" / "compare.html").read_text()
    proc = agrisynth("compare", str(path), str(same), "--out", str(tmp_path / "cmp2"), cwd=tmp_path, timeout=300)
    assert proc.returncode == 0 and "different versions" not in proc.stdout + proc.stderr


def test_compare_of_bench_folders_alone_says_they_are_benches(tmp_path):
    """Two bench folders and no run: "needs at least one RESULT" read as if the paths given were not seen."""
    for name in ("b1", "b2"):
        (tmp_path / name / "bench").mkdir(parents=True)
        (tmp_path / name / "bench" / "bench.json").write_text("{}")
    proc = agrisynth("compare", str(tmp_path / "b1"), str(tmp_path / "b2"), "--out", str(tmp_path / "cmp"),
                     cwd=tmp_path, timeout=120)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    said = " ".join(proc.stderr.split())
    assert "compare needs at least one RESULT (a run folder or its result.json)" in said
    assert f"{tmp_path / 'b1'}, {tmp_path / 'b2'} are benches, which compare shows beside a run of their kind" in said
    assert not (tmp_path / "cmp").exists()


@pytest.mark.slow
def test_compare_without_out_writes_a_folder_per_comparison(good, tmp_path):
    """The README's order of work compares twice (two examples, then its own runs): with one default folder the
    second compare needed --force.  Each comparison has its own: results/compare/<A>_vs_<B>/."""
    path, base = good
    for name in ("arm_a", "arm_b", "arm_c"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "result.json").write_bytes(_edit(base, lambda data: None))
    first = agrisynth("compare", "arm_a", "arm_b", cwd=tmp_path, timeout=300)
    second = agrisynth("compare", "arm_a", "arm_c/result.json", cwd=tmp_path, timeout=300)
    assert first.returncode == 0 and second.returncode == 0, first.stderr + second.stderr
    assert (tmp_path / "results" / "compare" / "arm_a_vs_arm_b" / "compare.html").is_file()
    assert (tmp_path / "results" / "compare" / "arm_a_vs_arm_c" / "compare.html").is_file()
    again = agrisynth("compare", "arm_a", "arm_b", cwd=tmp_path, timeout=300)     # the same comparison: --force
    assert again.returncode == 2 and "give --force to replace it" in again.stderr
    # an earlier version's results/compare/ (a run folder itself): said, not written into
    (tmp_path / "results" / "compare").rename(tmp_path / "kept")
    (tmp_path / "results" / "compare").mkdir()
    (tmp_path / "results" / "compare" / ".agrisynth-run").write_text(
        (tmp_path / "kept" / "arm_a_vs_arm_b" / ".agrisynth-run").read_text())
    old = agrisynth("compare", "arm_a", "arm_b", cwd=tmp_path, timeout=300)
    assert old.returncode == 2 and "is itself a comparison's folder (an earlier version's default" in old.stderr
    # a default folder inside a RESULT is named as the default, not as an --out never given
    (tmp_path / "results" / "compare" / ".agrisynth-run").unlink()
    inside = agrisynth("compare", "arm_a", ".", cwd=tmp_path, timeout=300)
    assert inside.returncode == 2 and "the default output folder results/compare/" in inside.stderr


def test_the_default_compare_folder_of_many_results_keeps_to_a_folder_name():
    from synthesis.runs.comparing import default_out

    many = tuple(Path(f"results/redesign_from_example1_solve_{i}") for i in range(12))
    out = default_out(many)
    assert out.parent == Path("results/compare") and len(out.name) <= 100
    assert re.fullmatch(r"redesign_from_example1_solve_0_and_11_more_[0-9a-f]{8}", out.name), out.name
    assert default_out(many[:1] + many[2:]) != out          # another comparison, however shortened
    # a name changed to fit ("run 1") could be another's ("run_1"): hashed too
    assert re.fullmatch(rf"run_1_vs_{re.escape(Path.cwd().name)}_[0-9a-f]{{8}}",
                        default_out((Path("a b/run 1/result.json"), Path("."))).name)
    # names alone that could name another comparison: a hash of the full paths tells them apart
    assert default_out((Path("old/arm"), Path("new/arm"))) != default_out((Path("new/arm"), Path("other/arm")))
    assert default_out((Path("a_vs_b"), Path("c"))) != default_out((Path("a"), Path("b_vs_c")))
    assert default_out((Path("x/a_vs"), Path("y/b"))) != default_out((Path("x/a"), Path("y/vs_b")))
    assert default_out((Path("a b"), Path("c"))) != default_out((Path("a_b"), Path("c")))
    # a run given as its folder or as its result.json is one run: the same comparison, the same folder
    assert default_out((Path("old/arm/result.json"), Path("new/arm"))) == default_out((Path("old/arm"),
                                                                                      Path("new/arm")))
    assert default_out((Path(os.fsdecode(b"arm\xff")), Path("b"))).name.startswith("arm__vs_b_")


@pytest.mark.parametrize("value", [None, -1, {}, [], 1e300, "<b>x</b>"])
def test_a_bench_row_s_text_fields_of_any_json_type_make_a_page(value):
    """A bench.json whose method (or time-to-target text, or ratio text) was null, a number, a table or a list was an
    AttributeError out of html.escape in `compare`; any JSON value is now its escaped text, none a dash (and the
    missing ratio a dash, not the escaped entity "&amp;ndash;" it showed)."""
    from synthesis.report.page import bench_table

    row = {"problem": "p", "method": value, "objective": 1.0, "time_to_target_text": value, "time_ratio_text": value}
    page = bench_table([{"rows": [row]}])
    assert "&amp;ndash;" not in page and "<b>x</b>" not in page
    cells = page.split("<td>p</td>")[1]
    assert cells.startswith("<td>–</td>" if value in (None,) else "<td>")


def test_a_library_warning_while_drawing_the_comparison_goes_to_its_log(tmp_path, monkeypatch, capsys):
    """matplotlib's "Tight layout not applied" (a legend of 60 candidates) was printed on the terminal by compare;
    check and solve keep library warnings in their logs."""
    import warnings

    from synthesis.runs import comparing

    def draws(cands, folder, bench):
        warnings.warn("Tight layout not applied. made up by the test", UserWarning)
        (folder / "compare.html").write_text("<html></html>")

    monkeypatch.setattr(comparing, "write_comparison_files", draws)
    comparing._write_page([], tmp_path, [])
    assert "Tight layout not applied. made up by the test" in (tmp_path / "warnings.log").read_text()
    assert "Tight layout" not in capsys.readouterr().err
