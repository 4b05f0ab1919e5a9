"""solved.toml: every solve's design as a spec with everything fixed; `check` of it reproduces the solve's
rule table exactly.  And what a piped `solve` prints: a line per finished start, the solved design.

Every solving kind of the registry is covered (kinds added later too); a kind whose package does not import
is skipped with the import error as the reason.
"""

from __future__ import annotations

import re


import pytest

from conftest import LIBRARY
from synthesis import kinds
from synthesis.spec import design_info
from synthesis.core import solve as core
from synthesis.spec.solved import FILENAME, solved_toml
from synthesis.errors import SpecError
from synthesis.spec import load_spec
from synthesis.spec.common import read_toml
from solving import agrisynth

#: kinds whose `check` cannot reproduce a solve's rule table, and why (xfail strict: a fix turns them red)
KNOWN: dict[str, str] = {}


def _solving_kinds() -> list:
    out = []
    for name in kinds.names():
        try:
            solves = kinds.get(name).solves
        except Exception as exc:    # noqa: BLE001 - a kind another session is still writing
            out.append(pytest.param(name, marks=pytest.mark.skip(reason=f"kind {name} does not import: {exc}")))
            continue
        if solves:
            marks = [pytest.mark.xfail(reason=KNOWN[name], strict=True)] if name in KNOWN else []
            if name == "guide_way":     # a solve of seconds: run with the slow tests
                marks.append(pytest.mark.slow)
            out.append(pytest.param(name, marks=marks))
    return out


def again_value(model, path: str):
    """The value a spec model holds at a TOML path (``design.crank_deg``), lists as lists of floats."""
    for part in path.split("."):
        model = getattr(model, part)
    return [float(a) for a in model] if isinstance(model, (list, tuple)) else model


def _table(rules: list[dict]) -> list[tuple]:
    return [(r["name"], r["value"], r["limit"], r["unit"], r["satisfied"], r["margin"]) for r in rules]


@pytest.mark.parametrize("kind_name", _solving_kinds())
def test_check_of_solved_toml_reproduces_the_solve(kind_name, tmp_path):
    kind = kinds.get(kind_name)
    loaded = load_spec(LIBRARY / kind.example)
    assert design_info.describe(loaded.model), "the spec model lists no design variables to fix"
    result, _, _ = core.run_solve(kinds.solving_kind(kind_name), loaded, starts=1, workers=1)
    path = tmp_path / FILENAME
    path.write_text(solved_toml(loaded, result))
    again = load_spec(path)
    assert again.name == f"{loaded.name}_solved"
    described = design_info.describe(again.model)
    assert described and not any(v["free"] for v in described.values())      # everything fixed
    assert _table(kinds.checker(kind_name)(again).rules) == _table(result.rules)
    # result.json's design_variables list the variables solved.toml fixes: every one the solve could move, free
    # (guide_way's fitted control points were missing: its spec leaves them to the kind)
    from synthesis.runs.specs import described as _described

    # (and the list-valued design values, each at its path: fourbar_path's crank angles, at [design] crank_deg)
    listed = _described(result, loaded).design_variables
    lists = design_info.describe_lists(again.model)
    assert set(listed) == set(described) | set(lists) | set(design_info.describe_choices(again.model))
    assert all(again_value(again.model, v["path"]) == result.design[n] for n, v in lists.items())
    explicit = kinds.explicit_design(loaded, read_toml(loaded.path)[0])[0].model
    assert {n for n, v in listed.items() if v["free"]} == {n for n, v in {
        **design_info.describe(explicit), **design_info.describe_lists(explicit)}.items() if v["free"]}
    assert all(n in result.design for n, v in listed.items() if v["free"])


@pytest.mark.slow
def test_piped_solve_prints_each_start_the_design_and_writes_solved_toml(tmp_path):
    text = (LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").read_text()
    for old, new in (('name = "cai2020_crank_rocker_synthesis"', 'name = "tight"'),
                     ("l7 = { init = 50.0, bounds = [5.0, 200.0] }", "l7 = { init = 50.0, bounds = [5.0, 52.0] }")):
        assert old in text, old
        text = text.replace(old, new)
    spec = tmp_path / "tight.toml"
    spec.write_text(text)
    proc = agrisynth("solve", str(spec), "--out", str(tmp_path / "out"), "--workers", "1", "--starts", "3", timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    started = [ln for ln in lines if ln.startswith("start ") and " finished (" in ln]
    assert sorted(int(ln.split()[1]) for ln in started) == [0, 1, 2]
    assert {ln.split("(")[1].split(")")[0] for ln in started} == {"1/3", "2/3", "3/3"}
    # the solved design: given, solution, unit, bounds and the at-bound mark, one row per variable
    row = next(ln for ln in lines if ln.startswith("│ l7 "))
    cells = [c.strip() for c in row.strip("│").split("│")]
    assert cells == ["l7", "50", "52", "mm", "[5, 52]", "at upper bound"]
    l10 = [c.strip() for c in next(ln for ln in lines if ln.startswith("│ l10 ")).strip("│").split("│")]
    assert l10 == ["l10", "140", "140", "mm", "fixed", ""]
    # solved.toml beside the result, and `check` of it gives the solve's rule table
    folder = tmp_path / "out" / "tight"
    check = agrisynth("check", str(folder / FILENAME), "--out", str(tmp_path / "out"), timeout=300)
    assert check.returncode == 0, check.stderr
    import json

    solved = json.loads((folder / "result.json").read_text())
    checked = json.loads((tmp_path / "out" / "tight_solved-check" / "result.json").read_text())
    assert _table(checked["rules"]) == _table(solved["rules"])
    assert checked["design"] == solved["design"]
    assert solved["design_variables"]["l7"] == {"path": "links.l7", "unit": "mm", "bounds": [5.0, 52.0], "free": True}


def test_check_of_a_planting_solved_toml_gives_the_solve_s_rule_values_to_the_last_digit(tmp_path):
    """redesign_from_example4: the solve re-checked on 160 / 720 samples (10x its [solver] counts) while `check`
    samples 400 / 3600, so accel_throw read 20796.92 in the solve and 20796.67 in the check of its solved.toml.
    The re-check is never coarser than `check` now."""
    loaded = load_spec(LIBRARY / "planting_arm" / "redesign_from_example4.toml")
    assert loaded.model.solver.samples_per_phase * 10 < 400
    result, _, _ = core.run_solve(kinds.solving_kind("planting_fourbar"), loaded, starts=1, workers=1)
    path = tmp_path / FILENAME
    path.write_text(solved_toml(loaded, result))
    assert _table(kinds.checker("planting_fourbar")(load_spec(path)).rules) == _table(result.rules)


def test_solved_toml_is_written_from_the_spec_as_the_run_read_it(tmp_path):
    """The spec file edited during a solve (l1 75 -> 90): solved.toml held the edited l1 under the first file's
    sha256, a design never solved.  It is written from the data the run read."""
    source = (LIBRARY / "planting_arm" / "redesign_from_example1.toml").read_text()
    assert "\nl1 = 75" in source
    path = tmp_path / "race.toml"
    path.write_text(source)
    loaded = load_spec(path)
    result, _, _ = core.run_solve(kinds.solving_kind("planting_fourbar"), loaded, starts=1, workers=1)
    path.write_text(source.replace("\nl1 = 75", "\nl1 = 90"))          # edited while the run went on
    written = tmp_path / FILENAME
    written.write_text(solved_toml(loaded, result))
    again = load_spec(written)
    assert again.model.design_values()["l1"] == 75.0 == result.design["l1"]
    assert _table(kinds.checker("planting_fourbar")(again).rules) == _table(result.rules)


def test_an_angle_a_bound_relaxation_left_a_hair_past_a_turn_still_loads(tmp_path):
    """IPOPT relaxes bounds by 1e-8 relative: a solve whose zeta ends on a bound at -360 writes -360.0000036, and
    check of its solved.toml must read it; 360.001 is still refused."""
    source = (LIBRARY / "planting_arm" / "taiwan_example1.toml").read_text()
    for zeta, loads in (("-360.0000035999994", True), ("360.001", False)):
        path = tmp_path / "z.toml"
        path.write_text(re.sub(r"(?m)^zeta = .*$", f"zeta = {zeta}", source))
        if loads:
            assert load_spec(path).model.arm.zeta == float(zeta)
        else:
            with pytest.raises(SpecError, match="got 360.001"):
                load_spec(path)


def test_a_solved_or_elastic_spec_s_name_keeps_to_the_length_a_spec_may_have():
    """A 100-character spec name gave solved.toml the name <name>_solved, 107 characters, which check refused."""
    from synthesis.spec.common import MAX_NAME_LENGTH, derived_name, usable_name

    for suffix in ("_solved", "_elastic"):
        long = derived_name("a" * MAX_NAME_LENGTH, suffix)
        assert len(long) == MAX_NAME_LENGTH and long.endswith(suffix) and usable_name(long)
        assert derived_name("arm", suffix) == f"arm{suffix}"


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_solved_toml_reads_back_whatever_the_spec_s_file_name_and_text_hold(tmp_path):
    """A DEL character in `source` was written raw into solved.toml (a control character TOML refuses), a newline in
    the spec's file name ended the header comment and made the rest of the name TOML: check refused the file."""
    text = (LIBRARY / "steering" / "steering_redesign_40.toml").read_text()
    text = re.sub(r'(?m)^source = "', 'source = "del\\\\u007f here, ', text, count=1)
    spec = tmp_path / "ev\nil.toml"
    spec.write_text(text)
    assert "\x7f" in load_spec(spec).model.source
    solve = agrisynth("solve", str(spec), "--starts", "2", "--workers", "1", "--out", str(tmp_path / "out"),
                      cwd=tmp_path)
    assert solve.returncode == 0, solve.stderr
    solved = next((tmp_path / "out").glob("*/solved.toml"))
    assert "\x7f" not in solved.read_text() and "# the spec ev?il.toml with" in solved.read_text()
    check = agrisynth("check", str(solved), "--out", str(tmp_path / "check"), cwd=tmp_path)
    assert check.returncode == 0, check.stderr
    assert load_spec(solved).model.source == load_spec(spec).model.source
