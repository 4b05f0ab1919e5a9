"""Output folders: a run replaces only an earlier agrisynth run, and only with --force; anything
else at OUT/<name> is kept (exit 2); two runs racing into one folder leave one whole run and no leftovers."""

from __future__ import annotations

import json
import multiprocessing
import time
import re
from pathlib import Path

import pytest

from conftest import PLANTING
from synthesis.errors import OutputError
from synthesis.result import RUN_MARKER, is_run_folder, open_run_folder, write_folder
from solving import agrisynth


def artifacts(token: str) -> dict:
    """Two files written from the same token: a folder mixing two runs has different tokens in them."""
    return {"result.json": lambda p: p.write_text(json.dumps({"token": token})),
            "report.html": lambda p: p.write_text(token)}


def test_a_run_folder_carries_the_marker_and_is_replaced_only_with_force(tmp_path):
    final, replaced = write_folder(tmp_path / "run", artifacts("a"))
    assert not replaced and is_run_folder(final) and (final / RUN_MARKER).is_file()
    with pytest.raises(OutputError, match="holds an earlier agrisynth run; give --force"):
        write_folder(tmp_path / "run", artifacts("b"))
    assert json.loads((final / "result.json").read_text())["token"] == "a"
    _, replaced = write_folder(tmp_path / "run", artifacts("b"), force=True)
    assert replaced and json.loads((final / "result.json").read_text())["token"] == "b"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]       # no staging or .old leftovers


@pytest.mark.parametrize("added", ["notes.txt", "sub/data.csv", "myspec.toml"])
def test_force_never_deletes_what_a_user_put_in_a_run_folder(tmp_path, added):
    """agrisynth never deletes anything it cannot prove it wrote.  The marker lists what the run wrote at
    its commit; --force replaces the folder only while it holds no more (exit 2 naming the entry otherwise), and a
    folder whose marker lists nothing (an earlier version's) is never replaced either."""
    final, _ = write_folder(tmp_path / "run", artifacts("a"))
    assert json.loads((final / RUN_MARKER).read_text())["contents"] == ["report.html", "result.json"]
    extra = final / added
    extra.parent.mkdir(exist_ok=True)
    extra.write_text("mine")
    with pytest.raises(OutputError, match=f"cannot prove it wrote there \\({added.split('/')[0]}"):
        write_folder(tmp_path / "run", artifacts("b"), force=True)
    assert extra.read_text() == "mine" and json.loads((final / "result.json").read_text())["token"] == "a"
    extra.unlink()
    if extra.parent != final:
        extra.parent.rmdir()
    _, replaced = write_folder(tmp_path / "run", artifacts("b"), force=True)   # as written again: replaced
    assert replaced and json.loads((final / "result.json").read_text())["token"] == "b"
    (final / ".DS_Store").write_text("finder")       # OS metadata is not a user's work: replaced with the run
    _, replaced = write_folder(tmp_path / "run", artifacts("c"), force=True)
    assert replaced and not (final / ".DS_Store").exists()


def test_a_run_folder_of_an_earlier_version_is_replaced_only_if_it_holds_agrisynths_file_names(tmp_path):
    """A marker without a contents list (written before markers listed them): --force replaces the folder when it
    holds only top-level files named as agrisynth names its outputs (and figures); a user's file or a subfolder is
    refused, named in the one-line message."""
    final, _ = write_folder(tmp_path / "run", artifacts("a"))
    marker = json.loads((final / RUN_MARKER).read_text())
    (final / RUN_MARKER).write_text(json.dumps({k: v for k, v in marker.items() if k != "contents"}))
    (final / "trajectory.png").write_text("figure")
    _, replaced = write_folder(tmp_path / "run", artifacts("b"), force=True)
    assert replaced and json.loads((final / "result.json").read_text())["token"] == "b"
    for extra in ("notes.txt", "myspec.toml", "sub/x.png"):
        (final / RUN_MARKER).write_text(json.dumps({k: v for k, v in marker.items() if k != "contents"}))
        (final / extra).parent.mkdir(exist_ok=True)
        (final / extra).write_text("mine")
        top = extra.split("/")[0] + ("/" if "/" in extra else "")
        with pytest.raises(OutputError, match=f"cannot prove it wrote there \\({top}\\)"):
            write_folder(tmp_path / "run", artifacts("c"), force=True)
        assert (final / extra).read_text() == "mine"
        (final / extra).unlink()
        if "/" in extra:
            (final / extra).parent.rmdir()


@pytest.mark.slow
def test_resume_from_a_staging_folder_writes_the_spec_named_folder(tmp_path):
    """README: after a SIGKILL or a power loss, resume from the staging folder (OUT/.<name>.run-XXXX, no folder name):
    the result goes to OUT/<spec name>.  A finished run's folder stands in for the staging one (same marker and
    starts.jsonl)."""
    import shutil

    spec = str(PLANTING.parent / "steering" / "steering_redesign_27.toml")
    proc = agrisynth("solve", spec, "--starts", "2", "--workers", "1", "--out", str(tmp_path / "a"), timeout=300)
    assert proc.returncode == 0, proc.stderr
    staging = tmp_path / "b" / ".steering_redesign_27.run-abc123"
    shutil.copytree(tmp_path / "a" / "steering_redesign_27", staging)
    proc = agrisynth("solve", spec, "--resume", str(staging), timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "resumed: 2 finished start(s)" in proc.stdout
    assert json.loads((tmp_path / "b" / "steering_redesign_27" / "result.json").read_text())["solver"]["starts"] == 2


@pytest.mark.slow
def test_force_through_the_cli_keeps_a_users_file_and_says_so(tmp_path):
    proc = agrisynth("check", str(PLANTING / "taiwan_example1.toml"), "--out", str(tmp_path), timeout=120)
    assert proc.returncode == 1, proc.stderr
    notes = tmp_path / "taiwan_example1-check" / "notes.txt"
    notes.write_text("field trial, 2026")
    proc = agrisynth("check", str(PLANTING / "taiwan_example1.toml"), "--out", str(tmp_path), "--force", timeout=120)
    assert proc.returncode == 2 and "notes.txt" in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and notes.read_text() == "field trial, 2026"


@pytest.mark.parametrize("force", [False, True])
def test_a_folder_agrisynth_did_not_write_is_never_replaced(tmp_path, force):
    precious = tmp_path / "precious"
    precious.mkdir()
    (precious / "thesis.txt").write_text("data")
    with pytest.raises(OutputError, match="agrisynth did not write .*never replaces or deletes it"):
        write_folder(precious, artifacts("a"), force=force)
    assert (precious / "thesis.txt").read_text() == "data"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["precious"]


@pytest.mark.parametrize("command, file, name", [("check", "myspec-check", "myspec"),
                                                  ("solve", "myspec.toml", "myspec.toml")])
@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_the_spec_file_itself_is_never_replaced(tmp_path, command, file, name):
    """A spec whose run folder would be its own file (check writes OUT/<name>-check/, solve OUT/<name>/)."""
    spec = tmp_path / file
    spec.write_text((PLANTING.parent / "steering" / "steering_redesign_27.toml").read_text()
                    .replace('name = "steering_redesign_27"', f'name = "{name}"'))
    before = spec.read_text()
    proc = agrisynth(command, file, "--out", ".", "--force", cwd=tmp_path, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert f"{file} is the spec file itself" in proc.stderr and "Traceback" not in proc.stderr
    assert spec.read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [file]


@pytest.mark.parametrize("where", ["file/sub", "name-not-a-folder"])
def test_an_impossible_out_is_refused_before_any_work(tmp_path, where):
    (tmp_path / "file").write_text("x")
    (tmp_path / "name-not-a-folder").write_text("x")
    with pytest.raises(OutputError, match="--out"):
        open_run_folder(tmp_path / where, "run")


@pytest.mark.parametrize("name", ["", "..", "a/b", "x" * 101, ".hidden", "a b"])
def test_a_name_that_is_not_a_slug_is_refused(tmp_path, name):
    with pytest.raises(OutputError, match="is not a folder name"):
        open_run_folder(tmp_path, name)
    assert list(tmp_path.iterdir()) == []


def _race(out: str, who: str, n: int, errors, wrote) -> None:
    for i in range(n):
        try:
            write_folder(Path(out) / "run", artifacts(f"{who}{i}"), force=True)
            wrote.put(f"{who}{i}")
        except OutputError as exc:      # the other is writing the folder right now: refused before any work
            if "another agrisynth run is writing" not in str(exc):
                errors.put(f"{who}{i}: {exc!r}")
        except Exception as exc:        # noqa: BLE001 -- counted by the test
            errors.put(f"{who}{i}: {exc!r}")


def test_two_processes_racing_into_one_folder_leave_one_whole_run(tmp_path):
    """150 --force writes each, at once: each is either refused before any work (the other is writing) or leaves
    the folder whole; the folder ends as one process's last write, with no staging or .old folder left."""
    errors, wrote = multiprocessing.Queue(), multiprocessing.Queue()
    procs = [multiprocessing.Process(target=_race, args=(str(tmp_path), who, 150, errors, wrote)) for who in "ab"]
    for p in procs:
        p.start()
    for p in procs:
        p.join(120)
        assert p.exitcode == 0
    failed = []
    while not errors.empty():
        failed.append(errors.get())
    assert failed == []
    written = []
    while not wrote.empty():
        written.append(wrote.get())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]        # no staging, no .old folders
    run = tmp_path / "run"
    token = json.loads((run / "result.json").read_text())["token"]
    last = {who: max((int(t[1:]) for t in written if t[0] == who), default=None) for who in "ab"}
    assert (run / "report.html").read_text() == token and token in (f"{who}{i}" for who, i in last.items())
    assert sorted(p.name for p in run.iterdir()) == sorted([RUN_MARKER, "result.json", "report.html"])


def test_compare_output_follows_the_run_folder_rules(tmp_path):
    """`compare --out DIR` writes DIR as an agrisynth output (marker): a second compare there needs --force,
    a folder agrisynth did not write is never touched (compare once wrote into any folder)."""
    from synthesis import kinds
    from synthesis.report.compare import load_candidates, open_output_folder, write_comparison
    from synthesis.result import result_text
    from synthesis.spec import load_spec

    loaded = load_spec(PLANTING.parent / "comb_finger" / "peanut_baseline.toml")     # a page without figures: fast
    run = tmp_path / "run"
    run.mkdir()
    (run / "result.json").write_text(result_text(kinds.checker(loaded.kind)(loaded)))
    cands = load_candidates([run])
    page = write_comparison(cands, tmp_path / "cmp")
    assert page.is_file() and is_run_folder(tmp_path / "cmp")
    with pytest.raises(OutputError, match="holds an earlier agrisynth run; give --force"):
        write_comparison(cands, tmp_path / "cmp")
    write_comparison(cands, tmp_path / "cmp", force=True)
    assert page.is_file() and sorted(p.name for p in tmp_path.iterdir()) == ["cmp", "run"]
    # a page changed since agrisynth wrote it is no longer provably its own: --force keeps it
    page.write_text("old")
    with pytest.raises(OutputError, match=r"cannot prove it wrote there \(compare.html \(changed since agrisynth "
                                          r"wrote it\)\)"):
        write_comparison(cands, tmp_path / "cmp", force=True)
    assert page.read_text() == "old"
    page.unlink()
    write_comparison(cands, tmp_path / "cmp", force=True)
    assert page.read_text() != "old" and sorted(p.name for p in tmp_path.iterdir()) == ["cmp", "run"]
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    for force in (False, True):
        with pytest.raises(OutputError, match="a folder agrisynth did not write"):
            open_output_folder(mine, force)
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]


def cli_in_process(*args: str) -> tuple[int, str]:
    """``agrisynth ARGS`` in this process (no interpreter start-up): exit code and stderr."""
    proc = agrisynth(*args)
    return proc.returncode, proc.stderr


@pytest.mark.slow
def test_bench_output_follows_the_run_folder_rules(tmp_path):
    from synthesis.bench import write_bench

    folder = write_bench(tmp_path, [], {"repeats": 1})
    assert folder == tmp_path / "bench" and is_run_folder(folder) and (folder / "bench.json").is_file()
    with pytest.raises(OutputError, match="holds an earlier agrisynth run; give --force"):
        write_bench(tmp_path, [], {"repeats": 2})
    write_bench(tmp_path, [], {"repeats": 2}, force=True)
    assert json.loads((folder / "bench.json").read_text())["settings"] == {"repeats": 2}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bench"]
    mine = tmp_path / "other"
    (mine / "bench").mkdir(parents=True)
    code, err = cli_in_process("bench", "guide_tube", "--out", str(mine), "--force")
    assert code == 2 and "a folder agrisynth did not write" in err, err
    assert [p.name for p in mine.iterdir()] == ["bench"] and list((mine / "bench").iterdir()) == []


@pytest.mark.slow
def test_check_solve_compare_and_check_of_solved_toml_need_no_flag_and_keep_every_result(tmp_path):
    """The natural order of work on one spec, in a folder holding only that spec: check it, solve it, compare the two,
    check the solved design.  Each command writes its own run folder (check OUT/<name>-check/, solve OUT/<name>/,
    compare OUT/compare/<A>_vs_<B>/; solved.toml is named <name>_solved), so none needs --force and none replaces another's
    result.  Running the same command of the same spec again still keeps the earlier run (exit 2 before any work)."""
    spec = tmp_path / "arm.toml"
    spec.write_text((PLANTING.parent / "steering" / "steering_redesign_27.toml").read_text()
                    .replace('name = "steering_redesign_27"', 'name = "arm"'))
    results = tmp_path / "results"

    proc = agrisynth("check", "arm.toml", cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    checked_text = (results / "arm-check" / "result.json").read_text()
    checked = json.loads(checked_text)
    assert checked["status"] == "evaluated" and checked["design"]["arm_length"] == 150.0

    proc = agrisynth("solve", "arm.toml", "--starts", "2", "--workers", "1", cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    solved = json.loads((results / "arm" / "result.json").read_text())
    assert solved["status"] == "optimal" and solved["objective"]["value"] == pytest.approx(0.1365449746, rel=1e-6)
    assert (results / "arm-check" / "result.json").read_text() == checked_text      # the check's run is kept

    proc = agrisynth("compare", "results/arm-check", "results/arm", cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    page = (results / "compare" / "arm-check_vs_arm" / "compare.html").read_text()
    assert "arm (arm-check)" in page and "arm (arm)" in page        # the two runs of one name told apart

    proc = agrisynth("check", "results/arm/solved.toml", cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    again = json.loads((results / "arm_solved-check" / "result.json").read_text())
    assert again["design"] == solved["design"]
    assert [(r["name"], r["satisfied"]) for r in again["rules"]] == [(r["name"], r["satisfied"]) for r in solved["rules"]]
    assert sorted(p.name for p in results.iterdir()) == ["arm", "arm-check", "arm_solved-check", "compare"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.toml", "results"]

    kept = {p: p.read_bytes() for p in results.rglob("*") if p.is_file()}
    for command in (["check", "arm.toml"], ["solve", "arm.toml", "--starts", "2", "--workers", "1"]):
        proc = agrisynth(*command, cwd=tmp_path, timeout=120)
        assert proc.returncode == 2 and "holds an earlier agrisynth run; give --force" in proc.stderr, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1
    assert {p: p.read_bytes() for p in results.rglob("*") if p.is_file()} == kept


@pytest.mark.parametrize("command", [["check"], ["solve", "--starts", "1", "--workers", "1"]])
@pytest.mark.parametrize("force", [[], ["--force"]])
def test_a_users_folder_where_a_command_would_write_is_kept_with_or_without_force(tmp_path, command, force):
    """Each command's own folder name (OUT/<name>-check/ for check, OUT/<name>/ for solve) is refused, as any
    OUT/<name>/ was, when agrisynth did not write what is there: exit 2 before any work, nothing touched."""
    spec = PLANTING.parent / "steering" / "steering_redesign_27.toml"
    mine = tmp_path / ("steering_redesign_27-check" if command[0] == "check" else "steering_redesign_27")
    mine.mkdir()
    (mine / "notes.txt").write_text("field trial, 2026")
    proc = agrisynth(command[0], str(spec), *command[1:], "--out", str(tmp_path), *force, timeout=120)
    assert proc.returncode == 2 and "a folder agrisynth did not write" in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert [p.name for p in tmp_path.iterdir()] == [mine.name] and [p.name for p in mine.iterdir()] == ["notes.txt"]


def test_a_refused_out_leaves_none_of_the_folders_it_made(tmp_path):
    """--out mk1/mk2/<300 characters>: refused (exit 2), but mk1/mk2 stayed, made on the way to the name the file
    system refused."""
    from synthesis.errors import OutputError
    from synthesis.result import open_run_folder

    with pytest.raises(OutputError, match="cannot create the output folder"):
        open_run_folder(tmp_path / "mk1" / "mk2" / ("f" * 300), "spec")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_force_keeps_a_file_changed_since_agrisynth_wrote_it(tmp_path):
    """DESIGN: a run "never deletes anything it cannot prove agrisynth wrote".  The marker listed names only, so an
    edited solved.toml (the file the README invites you to check and edit) or a listed file replaced by a link was
    deleted by `solve --force`; the marker now holds each file's sha256."""
    spec = PLANTING.parent / "picker" / "cai2020_crank_rocker_synthesis.toml"
    args = ("solve", str(spec), "--starts", "2", "--workers", "1", "--out", str(tmp_path))
    assert agrisynth(*args, cwd=tmp_path).returncode in (0, 1)
    run = tmp_path / "cai2020_crank_rocker_synthesis"
    marker = json.loads((run / RUN_MARKER).read_text())
    assert set(marker["sha256"]) == {n for n in marker["contents"] if (run / n).is_file()}
    solved = run / "solved.toml"
    solved.write_text(solved.read_text() + "# tuned by hand\n")
    again = agrisynth(*args, "--force", cwd=tmp_path)
    assert again.returncode == 2 and "solved.toml (changed since agrisynth wrote it)" in again.stderr, again.stderr
    assert solved.read_text().endswith("# tuned by hand\n")
    solved.unlink()
    (run / "result.json").unlink()
    (run / "result.json").symlink_to(tmp_path / "elsewhere.json")
    again = agrisynth(*args, "--force", cwd=tmp_path)
    assert again.returncode == 2 and "result.json (changed since agrisynth wrote it)" in again.stderr, again.stderr
    (run / "result.json").unlink()
    assert agrisynth(*args, "--force", cwd=tmp_path).returncode in (0, 1)      # deleted files are no one's work


def test_a_second_run_into_a_folder_being_written_is_refused_before_any_work(tmp_path):
    """Two runs started into one new folder: the second is refused at once (exit 2, naming the first's staging
    folder), not after its work, with --force too (the first would do all its work and then find its folder taken);
    a killed run's staging folder holds no lock, so it does not stop the next run (a --resume reads it)."""
    first = open_run_folder(tmp_path, "run")
    with pytest.raises(OutputError, match=r"another agrisynth run is writing .*run now \(its files are in "
                                          rf".*{re.escape(first.staging.name)}\)"):
        open_run_folder(tmp_path, "run")
    assert sorted(p.name for p in tmp_path.iterdir()) == [first.staging.name]      # nothing made by the refusal
    with pytest.raises(OutputError, match="another agrisynth run is writing"):
        open_run_folder(tmp_path, "run", force=True)
    with pytest.raises(OutputError, match="another agrisynth run is writing"):
        open_run_folder(tmp_path, "run", replaceable=tmp_path / "run")
    other = open_run_folder(tmp_path, "other")          # another name is another folder
    other.discard()
    first.release()                                     # as a SIGKILL leaves it: the folder, no lock
    later = open_run_folder(tmp_path, "run")
    assert first.staging.is_dir() and later.staging != first.staging
    later.write(artifacts("b"))
    assert later.commit() is False and (tmp_path / "run" / "report.html").read_text() == "b"
    assert later.held is None


def _started_then_asleep(started) -> None:
    started.set()
    time.sleep(30)


def test_the_live_run_lock_is_its_own_name_s_and_not_held_by_a_forked_child(tmp_path):
    """A run named "a.run-x" (staging .a.run-x.run-XXXX) does not block runs of "a"; a process forked from a run (a
    pool worker, a figure's drawing) does not keep the run's lock once the run lets it go (it closes its copy)."""
    other = open_run_folder(tmp_path, "a.run-x")
    mine = open_run_folder(tmp_path, "a")
    mine.discard()
    other.discard()
    run = open_run_folder(tmp_path, "run")
    ctx = multiprocessing.get_context("fork")
    started = ctx.Event()
    child = ctx.Process(target=_started_then_asleep, args=(started,))
    child.start()
    try:
        assert started.wait(30)             # past the fork's handlers: the child's own code runs
        run.release()                       # the run lets go (it ended) while the forked process lives on
        later = open_run_folder(tmp_path, "run")
        later.discard()
    finally:
        child.kill()
        child.join()
    run.discard()
