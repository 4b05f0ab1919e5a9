"""The run layer (synthesis/runs/): runs take a request and a subscriber, hand over events, never print, and keep
an interrupted solve in one place; the command line draws those events (the kind's headline among them)."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from solving import agrisynth
from synthesis import kinds, runs
from synthesis.core import interrupt
from synthesis.library import LIBRARY
from synthesis.runs import events
from synthesis.runs.requests import CheckRequest, CheckWritten, SolveRequest

ROCKER = LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml"


def test_the_runs_import_neither_click_nor_rich_nor_the_studio():
    code = ("import sys\n"
            "from synthesis.runs import checking, solving, tolerancing, benching, comparing, library\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'click', 'rich', 'starlette', 'uvicorn'}),"
            " sorted(m for m in sys.modules if m.startswith(('synthesis.cli', 'synthesis.studio'))))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["[]", "[]"]


@pytest.mark.slow         # three short solves
def test_a_resume_stopped_while_it_recounts_the_finished_starts_leaves_the_run_it_resumed_as_it_was(tmp_path):
    """A run of 8 starts interrupted after 4, resumed, and the resume stopped (SIGTERM) as it counts the 2nd of
    those 4 again: nothing is replaced -- the interrupted run's result.json and starts.jsonl are byte for byte as
    they were, no staging folder is left -- and the outcome names that folder with its 4 starts; resuming it then
    finishes the run."""
    folder = tmp_path / "cai2020_crank_rocker_synthesis"

    def stop_after(k):
        def subscriber(event) -> None:
            if isinstance(event, events.StartFinished) and event.done == k:
                interrupt.simulate(signal.SIGTERM)
        return subscriber

    try:
        first = runs.solve(SolveRequest(ROCKER, tmp_path, starts=8, workers=1), stop_after(4))
        assert first.exit_code == 143 and first.stopped is not None and first.stopped.finished == 4
        before = {name: (folder / name).read_bytes() for name in ("result.json", "starts.jsonl")}
        again = runs.solve(SolveRequest(ROCKER, resume=folder, workers=1), stop_after(2))
    finally:
        interrupt.uninstall()
    assert again.exit_code == 143 and again.stopped is not None
    assert again.stopped.kept == folder and again.stopped.finished == 4 and again.stopped.total == 8
    assert {name: (folder / name).read_bytes() for name in before} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [folder.name]
    done = runs.solve(SolveRequest(ROCKER, resume=folder, workers=1), lambda event: None)
    assert done.exit_code in (0, 1) and json.loads((folder / "result.json").read_text())["status"] != "interrupted"


def test_help_imports_neither_casadi_nor_matplotlib():
    code = ("import sys\nsys.argv = ['agrisynth', '--help']\nfrom synthesis.program import main\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'casadi', 'matplotlib', 'numpy', 'scipy'}),"
            " file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and "agrisynth check SPEC" in proc.stdout, proc.stderr
    assert proc.stderr.strip() == "[]"


@pytest.mark.parametrize("argv", [["problems"], ["spec", "planting_fourbar"]])
def test_commands_that_draw_nothing_import_no_matplotlib(argv):
    """The terminal's views (every command's) read the tolerance module's Monte-Carlo lines; its figure's matplotlib
    is imported by the figure alone (0.2-0.3 s of a listing)."""
    code = (f"import sys\nsys.argv = ['agrisynth', *{argv!r}]\nfrom synthesis.program import main\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'matplotlib', 'PIL', 'ezdxf'}), file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout, proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == "[]"


def test_every_command_is_listed_with_its_own_short_help():
    """agrisynth --help lists the commands without importing them: its one-liners are the commands' own."""
    from synthesis.cli import COMMANDS, cli

    for name, (_, short) in COMMANDS.items():
        assert cli.get_command(None, name).get_short_help_str(limit=1000) == short, name


@pytest.mark.slow
def test_check_hands_over_its_result_and_the_kinds_headline(tmp_path, monkeypatch, capsys):
    """The kind's headline (Kind.headline) travels with the written result and is printed right after the rule
    table; the run itself prints nothing."""
    kind_class = type(kinds.get("crank_rocker"))
    monkeypatch.setattr(kind_class, "headline", lambda self, result: [f"headline of {result.name}: 1.5 mm rms"])
    seen = []
    outcome = runs.check(CheckRequest(ROCKER, tmp_path), seen.append)
    interrupt.uninstall()
    assert capsys.readouterr().out == ""
    (written,) = seen
    assert isinstance(written, events.ResultWritten) and isinstance(written.details, CheckWritten)
    assert written.details.headline == ["headline of cai2020_crank_rocker_synthesis: 1.5 mm rms"]
    assert written.folder == tmp_path / "cai2020_crank_rocker_synthesis-check" == outcome.folder
    assert outcome.exit_code == (1 if outcome.result.violated() else 0)
    assert json.loads((outcome.folder / "result.json").read_text())["status"] == "evaluated"

    proc = agrisynth("check", str(ROCKER), "--out", str(tmp_path / "cli"))
    lines = proc.stdout.splitlines()
    table_end = max(i for i, ln in enumerate(lines) if ln.startswith("└"))
    assert lines[table_end + 1] == "headline of cai2020_crank_rocker_synthesis: 1.5 mm rms", proc.stdout


@pytest.mark.slow
def test_a_signal_during_a_solve_keeps_its_finished_starts_in_one_place(tmp_path):
    """SIGTERM noted once the first start has finished (as the handler notes it): the run stops at its next safe
    point, writes the best-so-far result (status interrupted) with starts.jsonl, and answers exit 143 with what
    the terminal says of it."""
    seen = []

    def subscriber(event) -> None:
        seen.append(event)
        if isinstance(event, events.StartFinished):
            interrupt.simulate(signal.SIGTERM)

    try:
        outcome = runs.solve(SolveRequest(ROCKER, tmp_path, starts=4, workers=1), subscriber)
    finally:
        interrupt.uninstall()
    assert outcome.exit_code == 143 and outcome.stopped is not None and outcome.stopped.signal_name == "SIGTERM"
    finished = [e for e in seen if isinstance(e, events.StartFinished)]
    assert 1 <= len(finished) < 4 and outcome.stopped.finished == len(finished) and outcome.stopped.total == 4
    assert finished[0].line().startswith(f"start {finished[0].start} finished (1/4): objective ")
    folder = tmp_path / "cai2020_crank_rocker_synthesis"
    assert outcome.stopped.kept == folder == outcome.folder
    assert json.loads((folder / "result.json").read_text())["status"] == "interrupted"
    assert len((folder / "starts.jsonl").read_text().splitlines()) == 1 + len(finished)    # its header, then each
    assert not any(isinstance(e, events.ResultWritten) for e in seen)     # no summary: the run did not finish


def test_a_start_event_reads_as_the_line_a_piped_solve_prints():
    e = events.StartFinished(3, 2, 16, 12.3456789, "feasible", "Solve_Succeeded", 41, 0.123, 0, 11.5, "feasible")
    assert e.line() == ("start 3 finished (2/16): objective 12.3457, feasible, IPOPT Solve_Succeeded in 41 "
                        "iterations, 0.12 s; best so far: start 0")


def test_a_value_with_an_unquoted_unit_says_to_quote_it(tmp_path):
    spec = tmp_path / "unit.toml"
    spec.write_text('kind = "crank_rocker"\nname = "unit"\ncrank_speed = 250 rpm\n')
    proc = agrisynth("check", str(spec), "--out", str(tmp_path / "out"))
    assert proc.returncode == 2 and proc.stderr.strip().splitlines() == [proc.stderr.strip()], proc.stderr
    assert proc.stderr.strip() == (f"error: {spec}: not valid TOML: Expected newline or end of document after a "
                                   f'statement (at line 3, column 19); a value with a unit must be quoted ("250 rpm")')
    spec.write_text('kind = "crank_rocker"\nname = "unit"\nl2 = { init = 50.0 mm, bounds = [5.0, 200.0] }\n')
    assert 'must be quoted ("50.0 mm")' in agrisynth("check", str(spec)).stderr
    spec.write_text('kind = "crank_rocker"\nname = "unit"\nl2 = [1, 2\n')        # another TOML error: no hint
    assert "must be quoted" not in agrisynth("check", str(spec)).stderr


def test_the_studio_worker_tells_the_page_progress_and_lines_not_printed_text():
    """What the studio's worker sends for each event: progress and the line the page shows (JSON, never a print)."""
    from synthesis.studio.worker import message

    start = events.StartFinished(1, 1, 4, 3.5, "worst violation 0.2", "Solve_Succeeded", 12, 0.5, 1, 3.5,
                                 "worst violation 0.2")
    assert message(events.SolveStarted("arm", 4)) == {"total": 4}
    assert message(start) == {"done": 1, "total": 4, "line": start.line()}
    assert message(events.Note("l2 looks like metres")) == {"line": "note: l2 looks like metres"}
    assert message(events.StartsDone()) is None and message(events.SolverLog("ipopt")) is None


def test_bench_takes_a_library_spec_by_name_as_check_and_solve_do(tmp_path, monkeypatch):
    """From a folder without the spec (an installed tool's user), bench finds the library's spec of that name and
    says so; a file of that name in the working folder is taken before it."""
    from synthesis.runs.benching import problems_by_kind
    from synthesis.runs.requests import BenchRequest

    monkeypatch.chdir(tmp_path)
    told: list = []
    by_kind = problems_by_kind(BenchRequest(("planting_arm/redesign_from_example1.toml",)), told.append)
    [loaded] = by_kind["planting_fourbar"]
    assert loaded.path == LIBRARY / "planting_arm" / "redesign_from_example1.toml"
    assert [type(e).__name__ for e in told] == ["SpecFromLibrary"]
    own = tmp_path / "planting_arm" / "redesign_from_example1.toml"
    own.parent.mkdir()
    own.write_text(loaded.path.read_text().replace('name = "redesign_from_example1"', 'name = "mine"'))
    [mine] = problems_by_kind(BenchRequest((), (Path("planting_arm/redesign_from_example1.toml"),)))["planting_fourbar"]
    assert mine.model.name == "mine"
    # the bare name check and solve take (no .toml, no folder): it was "neither a kind with a bench nor a spec file"
    [bare] = problems_by_kind(BenchRequest(("steering_redesign_40",)))["steering_linkage"]
    assert bare.path == LIBRARY / "steering" / "steering_redesign_40.toml"
    # one name twice -- the same spec, another spec of that name, a spec named as a problem of a kind's default set:
    # one figure and indistinguishable rows, refused naming both
    from synthesis.runs.benching import _cases
    from synthesis.runs.requests import BadRequest

    other = tmp_path / "other.toml"
    other.write_text((LIBRARY / "planting_arm" / "redesign_from_example1.toml").read_text().replace(
        'name = "redesign_from_example1"', 'name = "steering_redesign_40"'))
    for twice in (("steering_redesign_40", "steering/steering_redesign_40.toml"),
                  ("steering_redesign_40", str(other)), ("steering_linkage", str(other))):
        request = BenchRequest(twice, quick=True)
        with pytest.raises(BadRequest, match="two problems named 'steering_redesign_40'"):
            _cases(request, problems_by_kind(request), lambda event: None)
