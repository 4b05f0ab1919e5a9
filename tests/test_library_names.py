"""The problem library from any folder: `agrisynth problems --copy NAME` copies a library spec out to edit it, and
`check` / `solve` take a library spec by its name where the working folder has no such file."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from conftest import LIBRARY
from solving import agrisynth
from synthesis.library import IMPORT_ROOT, library_names, library_spec, unknown_name_text


def test_the_library_is_read_through_the_package_and_is_the_checkouts_problems_folder():
    """In a checkout synthesis/problems is a link to problems/ (a wheel holds the files there): both name one
    folder, and every spec the checkout holds is a library spec."""
    from importlib.resources import files

    import synthesis.library as library

    assert library.LIBRARY == LIBRARY.resolve() == (IMPORT_ROOT / "problems").resolve()
    assert (files("synthesis") / "problems" / "planting_arm" / "taiwan_example1.toml").is_file()
    assert library_names() == sorted(p.relative_to(LIBRARY).as_posix() for p in LIBRARY.rglob("*.toml"))
    assert len(library_names()) >= 57


@pytest.mark.parametrize("name", ["planting_arm/taiwan_example1.toml", "planting_arm/taiwan_example1",
                                  "problems/planting_arm/taiwan_example1.toml", "./planting_arm/taiwan_example1.toml",
                                  "taiwan_example1", "taiwan_example1.toml"])
def test_a_library_spec_is_named_as_listed_as_the_readme_writes_it_or_by_its_file_name(name):
    assert library_spec(name) == LIBRARY.resolve() / "planting_arm" / "taiwan_example1.toml"


@pytest.mark.parametrize("name", ["../pyproject.toml", "planting_arm/../../pyproject.toml", "/etc/hostname",
                                  "planting_arm", "nope", "", "x" * 400])
def test_a_name_outside_the_library_or_of_no_spec_names_nothing(name):
    assert library_spec(name) is None


def test_an_unknown_name_says_the_closest_library_names_in_one_line():
    text = unknown_name_text("planting_arm/taiwan_exampel1.toml")
    assert text.startswith("planting_arm/taiwan_exampel1.toml: no such library spec; did you mean "
                           "planting_arm/taiwan_example1.toml")
    assert f"lists all {len(library_names())})" in text and "\n" not in text


def test_problems_copy_writes_the_library_file_byte_for_byte_and_never_overwrites_without_force(tmp_path):
    source = LIBRARY / "planting_arm" / "redesign_from_example1.toml"
    proc = agrisynth("problems", "--copy", "planting_arm/redesign_from_example1.toml", cwd=tmp_path, timeout=60)
    assert proc.returncode == 0, proc.stderr
    copy = tmp_path / "redesign_from_example1.toml"
    assert copy.read_bytes() == source.read_bytes()
    assert "wrote redesign_from_example1.toml: a copy of the library's planting_arm/redesign_from_example1.toml" in \
        " ".join(proc.stdout.split())
    copy.write_text("# my edits\n")
    proc = agrisynth("problems", "--copy", "redesign_from_example1", cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and proc.stderr.strip() == (
        "error: redesign_from_example1.toml: already exists; give --force to replace it, or --out another file")
    assert copy.read_text() == "# my edits\n"
    proc = agrisynth("problems", "--copy", "redesign_from_example1", "--force", cwd=tmp_path, timeout=60)
    assert proc.returncode == 0 and copy.read_bytes() == source.read_bytes()
    # a copy the user names anew runs under that name (its runs results/arm2/ and results/arm2-check/, not the
    # library spec's, which the README's first command has written): its name line alone changed
    proc = agrisynth("problems", "--copy", "taiwan_example2", "--out", "arm2.toml", cwd=tmp_path, timeout=60)
    library_text = (LIBRARY / "planting_arm" / "taiwan_example2.toml").read_text()
    assert 'name = "taiwan_example2"' in library_text
    assert proc.returncode == 0 and (tmp_path / "arm2.toml").read_text() == library_text.replace(
        'name = "taiwan_example2"', 'name = "arm2"', 1)
    assert "to edit, named arm2 (its runs: results/arm2/ and results/arm2-check/)" in " ".join(proc.stdout.split())
    (tmp_path / "sub").mkdir()
    proc = agrisynth("problems", "--copy", "taiwan_example3", "--out", "sub", cwd=tmp_path, timeout=60)
    assert proc.returncode == 0 and (tmp_path / "sub" / "taiwan_example3.toml").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm2.toml", "redesign_from_example1.toml", "sub"]


@pytest.mark.slow
def test_problems_copy_of_a_spec_naming_other_spec_files_copies_them_beside_it_and_the_copy_checks(tmp_path):
    proc = agrisynth("problems", "--copy", "picker/cai2020_picker.toml", "--out", "mine.toml", cwd=tmp_path, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cai2020_crank_rocker.toml", "cai2020_double_crank.toml",
                                                          "mine.toml"]
    for part in ("cai2020_crank_rocker.toml", "cai2020_double_crank.toml"):
        assert (tmp_path / part).read_bytes() == (LIBRARY / "picker" / part).read_bytes()
    proc = agrisynth("check", "mine.toml", cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    data = json.loads((tmp_path / "results" / "mine-check" / "result.json").read_text())
    assert data["design_variables"]["crank_rocker.l7"]["file"] == str(tmp_path / "cai2020_crank_rocker.toml")
    # one of the named files exists already: nothing is written (not even the spec), one line naming it
    (tmp_path / "mine.toml").unlink()
    proc = agrisynth("problems", "--copy", "cai2020_picker", "--out", "mine.toml", cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and "cai2020_crank_rocker.toml: already exists" in proc.stderr
    assert not (tmp_path / "mine.toml").exists()


@pytest.mark.parametrize("args, said", [
    (["--copy", "planting_arm/taiwan_exampel1.toml"], "no such library spec; did you mean planting_arm/taiwan_example1"),
    (["--copy", "../pyproject.toml"], "../pyproject.toml: no such library spec"),
    (["--copy", "taiwan_example1", "--out", "nowhere/x.toml"], "nowhere/x.toml: no folder nowhere to write it in"),
    # a name ending in / is a folder (pathlib would drop the / and write a file named newd)
    (["--copy", "taiwan_example1", "--out", "newd/"], "newd/: names a folder (it ends in /) and there is no folder newd"),
    (["--out", "x.toml"], "--out goes with --copy NAME"),
    (["--force"], "--force goes with --copy NAME"),
])
def test_problems_copy_refuses_bad_input_in_one_line(tmp_path, args, said):
    proc = agrisynth("problems", *args, cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and said in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_problems_copy_into_the_library_itself_is_refused(tmp_path):
    here = LIBRARY / "planting_arm"
    before = (here / "taiwan_example1.toml").read_bytes()
    proc = agrisynth("problems", "--copy", "taiwan_example1", "--force", cwd=here, timeout=60)
    assert proc.returncode == 2 and "is the library's own file" in proc.stderr, proc.stderr
    assert (here / "taiwan_example1.toml").read_bytes() == before


@pytest.mark.slow
def test_check_and_solve_take_a_library_name_where_no_such_file_is_here_and_say_which_file(tmp_path):
    proc = agrisynth("check", "steering/steering_redesign_27.toml", cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    used = LIBRARY.resolve() / "steering" / "steering_redesign_27.toml"
    assert (f"note: no file steering/steering_redesign_27.toml here: using the library's "
            f"steering/steering_redesign_27.toml ({used})") in " ".join(proc.stdout.split())
    assert json.loads((tmp_path / "results" / "steering_redesign_27-check" / "result.json").read_text())["status"] \
        == "evaluated"
    proc = agrisynth("solve", "problems/steering/steering_redesign_27.toml", "--starts", "1", "--workers", "1",
                     cwd=tmp_path, timeout=300)
    assert proc.returncode == 0 and "using the library's steering/steering_redesign_27.toml" in proc.stdout
    assert sorted(p.name for p in (tmp_path / "results").iterdir()) == ["steering_redesign_27",
                                                                        "steering_redesign_27-check"]
    # a file of that name in the working folder is the one used, without a note
    mine = tmp_path / "steering" / "steering_redesign_27.toml"
    mine.parent.mkdir()
    mine.write_text(used.read_text().replace('name = "steering_redesign_27"', 'name = "mine"'))
    proc = agrisynth("check", "steering/steering_redesign_27.toml", cwd=tmp_path, timeout=120)
    assert proc.returncode == 0 and "library" not in proc.stdout and (tmp_path / "results" / "mine-check").is_dir()
    proc = agrisynth("check", "nope.toml", cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and proc.stderr.strip() == "error: nope.toml: no such spec file"


def test_the_studio_worker_and_the_extreme_matrix_find_this_agrisynth():
    """The studio's solve worker imports the synthesis this process runs; the extreme matrix is the checkout's."""
    from synthesis.bench import extreme as bench_extreme
    from synthesis.library import checkout
    from synthesis.studio.solver import worker_env

    assert worker_env()["PYTHONPATH"].split(os.pathsep)[0] == str(IMPORT_ROOT)
    assert checkout() == IMPORT_ROOT and bench_extreme.EXTREME == IMPORT_ROOT / "tests" / "extreme"


def test_a_copy_named_as_no_spec_may_be_keeps_its_name_and_says_so(tmp_path):
    """compare.toml, "my arm.toml": no spec may be named so (a run folder's name, reserved for compare): the copy
    keeps the library's name, and the line says its runs would be the library spec's folders."""
    library_text = (LIBRARY / "planting_arm" / "redesign_from_example1.toml").read_text()
    for out in ("compare.toml", "my arm.toml", "arm-check.toml"):
        proc = agrisynth("problems", "--copy", "redesign_from_example1", "--out", out, cwd=tmp_path, timeout=60)
        assert proc.returncode == 0, proc.stderr
        assert (tmp_path / out).read_text() == library_text
        said = " ".join(proc.stdout.split())
        assert f"its name stays redesign_from_example1 ({Path(out).stem!r} is no spec name" in said, said


@pytest.mark.slow
def test_a_copy_named_as_a_file_it_names_is_refused_before_anything_is_written(tmp_path):
    proc = agrisynth("problems", "--copy", "cai2020_picker", "--out", "cai2020_crank_rocker.toml", cwd=tmp_path,
                     timeout=60)
    assert proc.returncode == 2 and proc.stderr.strip() == (
        "error: cai2020_crank_rocker.toml: cai2020_picker.toml and the spec file it names, cai2020_crank_rocker.toml, "
        "would be copied to this one file; give --out another file name")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc (a folder no file can be made in)")
@pytest.mark.parametrize("args", [("problems", "--copy", "taiwan_example1", "--out", "/proc/x.toml"),
                                  ("spec", "planting_fourbar", "--template", "--out", "/proc/t.toml")])
def test_a_copy_or_template_into_a_folder_that_takes_no_file_is_refused_in_one_line(tmp_path, args):
    """problems --copy and spec --template into /proc were the temporary file's FileNotFoundError traceback."""
    proc = agrisynth(*args, cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip() == f"error: {args[-1]}: cannot be written there (No such file or directory)"
