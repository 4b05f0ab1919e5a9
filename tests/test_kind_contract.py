"""The kind contract: a kind registered through the public contract alone checks and solves
with the same driver, verdict and result tail as the built-in ones; the registry is the only list."""

from __future__ import annotations

import json
import subprocess
import sys
import typing

import pytest

from conftest import LIBRARY, ROOT
from synthesis import kinds
from synthesis.core.solve import exit_error, run_solve
from synthesis.result import Result
from synthesis.spec import load_spec
from solving import agrisynth

TOY = """kind = "toy_disc"
name = "toy"
x = {{ init = 0.0, bounds = [-20.0, 20.0] }}
y = {{ init = 1.0, bounds = [-20.0, 20.0] }}
radius = {radius}
y_min = {y_min}
target = [30.0, 40.0]
[solver]
starts = 3
"""


@pytest.fixture
def toy():
    import toy_kind

    kinds.register(toy_kind.KIND)
    yield toy_kind.KIND
    kinds.unregister("toy_disc")


def test_a_toy_kind_checks_and_solves_to_its_known_optimum(tmp_path, toy):
    path = tmp_path / "toy.toml"
    path.write_text(TOY.format(radius=10.0, y_min=-5.0))
    loaded = load_spec(path)
    checked = toy.check(loaded)
    assert checked.all_satisfied and checked.status == "evaluated"
    result, reports, log = run_solve(toy, loaded, workers=1)
    # the target (30, 40) lies outside the disc of radius 10: the nearest point is 10 x (0.6, 0.8)
    assert result.status == "optimal"
    assert result.design["x"] == pytest.approx(6.0, abs=1e-6) and result.design["y"] == pytest.approx(8.0, abs=1e-6)
    assert result.objective["value"] == pytest.approx(40.0**2, rel=1e-7)
    assert result.extra["distance_to_target_mm"] == pytest.approx(40.0, abs=1e-6)
    data = json.loads(json.dumps(result.to_json(), allow_nan=False))
    assert data["schema_version"] == 5 and data["facts"] == {"distance_to_target_mm": result.extra["distance_to_target_mm"]}
    assert [row["start"] for row in data["starts"]] == [0, 1, 2] and data["elastic"] is None
    assert Result.from_json(data).extra == result.extra


def test_a_toy_kind_with_conflicting_rules_is_infeasible_and_names_them(tmp_path, toy):
    path = tmp_path / "toy.toml"
    path.write_text(TOY.format(radius=10.0, y_min=12.0))          # above y = 12 but inside r = 10: impossible
    loaded = load_spec(path)
    result, reports, _ = run_solve(toy, loaded, workers=1)
    assert result.status == "infeasible"
    assert set(result.elastic["conflicting"]) == {"inside_disc", "above_line"}
    # each rule alone is within the bounds: a conflict, none out of reach
    assert result.elastic["out_of_reach"] == []
    assert all(abs(alone) < 1e-6 for alone in result.elastic["alone"].values()) and result.elastic["alone"]
    message = str(exit_error(toy, result, reports))
    assert "Rules that conflict" in message and "re-solved alone from there" not in message


def test_a_toy_kind_rule_beyond_the_bounds_is_out_of_reach_not_in_conflict(tmp_path, toy):
    """y >= 25 with y bounded by 20: no other rule is to blame.  The disc (radius 20) touches the elastic design
    (0, 20) and binds there, but relaxing it would not lift y past its bound: it is not named as conflicting."""
    path = tmp_path / "toy.toml"
    path.write_text(TOY.format(radius=20.0, y_min=25.0))
    loaded = load_spec(path)
    result, reports, _ = run_solve(toy, loaded, workers=1)
    assert result.status == "infeasible"
    elastic = result.elastic
    assert elastic["relaxed"] == ["above_line"] and elastic["slacks"]["above_line"] == pytest.approx(5.0, abs=1e-6)
    assert elastic["alone"]["above_line"] == pytest.approx(5.0, abs=1e-6)
    assert elastic["out_of_reach"] == ["above_line"] and elastic["conflicting"] == ["above_line"]
    assert "inside_disc" in elastic["binding"] and elastic["hard"] == []
    assert elastic["at_bounds"] == [{"name": "y", "side": "upper", "bound": 20.0}]
    message = str(exit_error(toy, result, reports))
    assert "Rules out of reach" in message and "inside_disc" not in message
    assert "At the elastic design y (20) sits at its upper bound." in message
    assert "above_line (misses its limit by 5 mm; still by 5 mm re-solved alone from there, every other rule relaxed" in message


def test_a_design_the_elastic_re_solve_finds_without_slack_is_solved_from_and_kept(tmp_path, toy, monkeypatch):
    """No start satisfies the rules (here: every start's solver gives up at a point outside the disc), but the
    rules do not conflict: the elastic re-solve needs no slack.  Its design is a start the run missed: one more
    start (index = starts) solves the spec's NLP from it, is re-checked like any other and, satisfying every
    rule, is the result -- not status "failed" with a feasible design thrown away."""
    from synthesis.core.declared import DeclaredNLP
    from synthesis.core.outcome import StartOutcome

    solve = DeclaredNLP.solve

    def gives_up(self, start, x0):
        if self.compiled.elastic or start >= 3:
            return solve(self, start, x0)
        return StartOutcome(start, {"x": 19.0, "y": 19.0}, 41.0**2 + 21.0**2 - 20.0, "Infeasible_Problem_Detected",
                            False, 7, 0.0, "")
    monkeypatch.setattr(DeclaredNLP, "solve", gives_up)
    path = tmp_path / "toy.toml"
    path.write_text(TOY.format(radius=10.0, y_min=-5.0))
    result, reports, _ = run_solve(toy, load_spec(path), workers=1)
    assert result.status == "optimal" and result.solver["best_start"] == 3
    assert result.design["x"] == pytest.approx(6.0, abs=1e-6) and result.design["y"] == pytest.approx(8.0, abs=1e-6)
    rows = result.to_json()["starts"]
    assert [row["start"] for row in rows] == [0, 1, 2, 3]
    assert [row["satisfied_on_fine_grid"] for row in rows] == [False, False, False, True]
    assert rows[3]["details"] == {"start_from": "elastic re-solve"}
    assert result.elastic["converged"] and result.elastic["relaxed"] == []
    assert "solved from the elastic re-solve's design" in result.solver["status_note"]


def test_a_start_from_the_elastic_design_that_misses_a_rule_or_is_interrupted_is_not_kept(tmp_path, toy, monkeypatch):
    """The extra start is kept only when it satisfies every rule: otherwise the run is what it was (status failed,
    three starts).  A signal during it discards it, as the multistart discards an interrupted start, and the run
    ends interrupted with its three finished starts."""
    from synthesis.core import interrupt
    from synthesis.core.declared import DeclaredNLP
    from synthesis.core.interrupt import Interrupted
    from synthesis.core.outcome import StartOutcome

    solve = DeclaredNLP.solve
    stop_at_extra = {"on": False}

    def gives_up(self, start, x0):
        if self.compiled.elastic:
            return solve(self, start, x0)
        if start >= 3 and stop_at_extra["on"]:
            interrupt.simulate()
        return StartOutcome(start, {"x": 19.0, "y": 19.0}, 1000.0, "Infeasible_Problem_Detected", False, 7, 0.0, "")
    monkeypatch.setattr(DeclaredNLP, "solve", gives_up)
    path = tmp_path / "toy.toml"
    path.write_text(TOY.format(radius=10.0, y_min=-5.0))
    result, reports, _ = run_solve(toy, load_spec(path), workers=1)
    assert result.status == "failed" and [r.outcome.start for r in reports] == [0, 1, 2]
    assert result.solver["starts_run"] == 3 and result.elastic["converged"] and result.elastic["relaxed"] == []
    stop_at_extra["on"] = True
    try:
        with pytest.raises(Interrupted) as stopped:
            run_solve(toy, load_spec(path), workers=1)
    finally:
        interrupt.uninstall()
    kept, kept_reports, _ = stopped.value.partial
    assert kept.status == "interrupted" and [r.outcome.start for r in kept_reports] == [0, 1, 2]
    assert kept.solver["best_start"] in (0, 1, 2) and "--resume" in kept.solver["status_note"]


def test_the_registry_is_the_only_list_of_kinds():
    """Every kind is a Kind whose spec model's Literal kind is its name, whose objectives are exactly the spec's
    objective names, and whose figures, check and solve side exist."""
    from synthesis.core.kind import Kind, Solving

    for kind in kinds.all_kinds():
        assert isinstance(kind, Kind), kind
        model = kind.spec_model()
        assert typing.get_args(model.model_fields["kind"].annotation) == (kind.name,)
        assert callable(kind.check)
        assert kind.figures() and all(callable(writer) for writer in kind.figures().values()), kind.name
        if kind.solves:
            assert isinstance(kind.solving(), Solving), kind.name
            assert kind.objectives, kind.name
            if "objective" in model.model_fields:
                objective = model.model_fields["objective"].annotation
                names = typing.get_args(objective.model_fields["name"].annotation)
                assert set(names) == set(kind.objectives), kind.name
            else:                           # a kind with one objective and no [objective] section
                assert len(kind.objectives) == 1, kind.name
        if kind.example:
            assert (LIBRARY / kind.example).exists()


def test_listing_kinds_imports_no_kind_code():
    """`agrisynth problems` and `solve --help` read the registry without importing any kind's modules."""
    code = ("import sys; from synthesis.cli.options import objectives_help; objectives_help(); from synthesis import kinds; kinds.all_kinds(); "
            "bad = [m for m in sys.modules if m.split('.')[:2] in (['synthesis', 'kinematics'],) or "
            "m.endswith(('.nlp', '.solve', '.check', '.scene')) and m.startswith('synthesis.')]; print(bad)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


def test_solve_of_a_check_only_kind_is_bad_input(tmp_path):
    proc = agrisynth("solve", str(LIBRARY / "picker" / "cai2020_picker.toml"), "--out", str(tmp_path), cwd=ROOT,
                     timeout=120)
    assert proc.returncode == 2 and "has nothing to optimise" in proc.stderr and "Traceback" not in proc.stderr


def test_every_kind_with_a_studio_page_evaluates_its_own_coarse_grid():
    """`agrisynth studio` opens a spec of any kind: each registered kind gives its coarse grid (Kind.coarse_check,
    a CoarseCheck in its own package) and says in words what that grid and the fine one evaluate; the studio holds
    no list of kinds of its own."""
    import re

    from synthesis.core.coarse import of_kind
    from synthesis.core.kind import CoarseCheck, Poses
    from synthesis.spec import load_spec

    for kind in kinds.all_kinds():
        own = kind.coarse_check()
        assert own is not None, kind.name          # the library's kinds each give their own, in their own package
        assert own.evaluate.__module__.startswith(type(kind).__module__) or \
            own.evaluate.__module__ == "synthesis.core.coarse", kind.name
        coarse = of_kind(kind)
        assert coarse is own, kind.name
        assert isinstance(coarse, CoarseCheck), kind.name
        spec = load_spec(LIBRARY / kind.example).model
        for note in (coarse.note(spec), coarse.fine_note(spec)):
            assert isinstance(note, str) and note and "\n" not in note, (kind.name, note)
    # and the studio's code branches on no kind (its grids and drawing ask the kind: coarse_check, poses)
    names = "|".join(re.escape(n) for n in kinds.names())
    for path in sorted((ROOT / "synthesis" / "studio").glob("*.py")):
        assert not re.search(rf"[\"']({names})[\"']", path.read_text()), f"studio/{path.name} names a kind"
    for kind in kinds.all_kinds():
        if kind.poses() is not None:
            assert isinstance(kind.poses(), Poses), kind.name


def test_a_kind_without_its_own_coarse_grid_gets_its_check_on_a_tenth_of_the_solver_samples(monkeypatch):
    """Kind.coarse_check None (allowed): the studio's coarse grid is the check with every [solver] sample count
    divided by 10, not below the model's least (guide_way's smooth_redesign: samples_per_segment 40 -> 5)."""
    from synthesis.spec import LoadedSpec, load_spec
    from synthesis.studio import grids

    class WithoutCoarseGrid(type(kinds.get("guide_way"))):
        def coarse_check(self):
            return None
    bare = WithoutCoarseGrid()
    real_get = kinds.get
    monkeypatch.setattr(kinds, "get", lambda name: bare if name == "guide_way" else real_get(name))
    loaded = load_spec(LIBRARY / "guide_way" / "smooth_redesign.toml")
    assert grids.note("guide_way", "coarse", loaded.model) == "the check with [solver] samples_per_segment 40 -> 5"
    assert grids.note("guide_way", "fine", loaded.model) == "agrisynth check's own grid"
    coarse = grids.evaluator("guide_way", "coarse")(loaded)
    solver5 = loaded.model.solver.model_copy(update={"samples_per_segment": 5})
    spec5 = loaded.model.model_copy(update={"solver": solver5})
    at_5 = kinds.checker("guide_way")(LoadedSpec(spec5, loaded.path, loaded.sha256))
    fine = grids.evaluator("guide_way", "fine")(loaded)
    assert [(r["name"], r["value"]) for r in coarse.rules] == [(r["name"], r["value"]) for r in at_5.rules]
    assert [r["value"] for r in coarse.rules] != [r["value"] for r in fine.rules]


def test_another_package_adds_a_kind_through_the_entry_point_group(tmp_path, monkeypatch):
    """A package installed beside agrisynth adds a kind by naming it in the ``agrisynth.kinds`` entry-point group:
    the registry lists it, and it checks and solves like a built-in one.  The package here is the toy kind with the
    metadata pip would write for it (a dist-info folder on the path)."""
    import shutil

    package = tmp_path / "site"
    package.mkdir()
    shutil.copy(ROOT / "tests" / "toy_kind.py", package / "toy_kind_plugin.py")
    info = package / "toy_kind_plugin-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: toy-kind-plugin\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[agrisynth.kinds]\ntoy_disc = toy_kind_plugin:KIND\n")
    monkeypatch.syspath_prepend(str(package))
    kinds._installed.cache_clear()
    try:
        assert "toy_disc" in kinds.names() and "planting_fourbar" in kinds.names()
        toy = kinds.get("toy_disc")
        assert type(toy).__module__ == "toy_kind_plugin"
        path = tmp_path / "toy.toml"
        path.write_text(TOY.format(radius=10.0, y_min=-5.0))
        loaded = load_spec(path)
        result, _, _ = run_solve(toy, loaded, workers=1)
        assert result.status == "optimal" and result.design["x"] == pytest.approx(6.0, abs=1e-6)
    finally:
        monkeypatch.undo()
        kinds._installed.cache_clear()
    assert "toy_disc" not in kinds.names()


def test_a_plugin_that_cannot_load_is_left_out_with_a_warning_naming_it(tmp_path, monkeypatch):
    package = tmp_path / "site"
    info = package / "broken_kind-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: broken-kind\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[agrisynth.kinds]\nbroken = no_such_module_here:KIND\n")
    monkeypatch.syspath_prepend(str(package))
    kinds._installed.cache_clear()
    try:
        with pytest.warns(UserWarning, match="plugin 'broken' .*no_such_module_here"):
            listed = kinds.names()
        assert "broken" not in listed and "planting_fourbar" in listed
    finally:
        monkeypatch.undo()
        kinds._installed.cache_clear()


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_the_kind_contract_type_checks():
    """mypy checks every kind's class against synthesis.core.kind.Kind (a method's signature or return type that
    breaks the contract fails here, before any run), the registry and the toy kind, and type-checks the whole core,
    the run layer and every module of every kind; files and options: pyproject.toml [tool.mypy]."""
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mypy"]
    assert {"synthesis/core", "synthesis/runs", "synthesis/kinds"} <= set(config["files"])
    assert "exclude" not in config          # every module of every kind is checked
    proc = subprocess.run([sys.executable, "-m", "mypy", "--no-incremental"], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.startswith("Success: no issues found")
