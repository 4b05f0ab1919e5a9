"""The ``agrisynth`` program ends its process without the interpreter's teardown (synthesis.program.program): the
exit code stays the command's, every line written reaches its reader, the exit handlers run, and a thread still
running is waited for as Python would."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

PROGRAM = "from synthesis.program import program\nimport sys\nsys.argv = ['agrisynth', *sys.argv[1:]]\n"


#: without PYTHONUNBUFFERED (set where these tests were written): Python then buffers its standard streams into a pipe,
#: so an exit that skipped their flush would lose what was written
BUFFERED = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}


def _run(code: str, *args: str, tmp_path, env=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=120,
                          cwd=tmp_path, env=BUFFERED if env is None else env)


def test_the_commands_exit_code_and_whole_output_reach_the_caller_and_the_exit_handlers_run(tmp_path):
    marker = tmp_path / "atexit.txt"
    code = (f"import atexit, pathlib\n"
            f"atexit.register(lambda: pathlib.Path({str(marker)!r}).write_text('ran'))\n"
            f"{PROGRAM}program()\n")
    done = _run(code, "problems", tmp_path=tmp_path)
    assert done.returncode == 0, done.stderr
    # the same command ended the ordinary way (main() and the interpreter's teardown, which flushes every stream)
    listing = _run("from synthesis.program import main\nimport sys\nsys.argv = ['agrisynth', 'problems']\nmain()\n",
                   tmp_path=tmp_path).stdout
    assert done.stdout == listing and "taiwan_example1" in done.stdout       # every line, to the last
    assert marker.read_text() == "ran"
    bad = _run(code, "check", "no-such-spec.toml", tmp_path=tmp_path)
    assert bad.returncode == 2 and bad.stderr.startswith("error:") and "no-such-spec.toml" in bad.stderr, bad.stderr


@pytest.mark.parametrize(("ending", "code", "stderr"), [
    ("sys.exit(3)", 3, ""),
    ("sys.exit(None)", 0, ""),
    ("sys.exit('a message')", 1, "a message\n"),
])
def test_system_exit_means_what_it_means_to_python(tmp_path, ending, code, stderr):
    script = ("import sys\nimport synthesis.program as program\n"
              f"def main():\n    print('said')\n    {ending}\n"
              "program.main = main\nprogram.program()\n")
    done = _run(script, tmp_path=tmp_path)
    assert (done.returncode, done.stdout, done.stderr) == (code, "said\n", stderr)


def test_a_thread_still_running_is_waited_for(tmp_path):
    """A non-daemon thread left running when the command returns: the process ends the ordinary way, after it."""
    script = ("import sys, threading, time\nimport synthesis.program as program\n"
              "def late():\n    time.sleep(0.3)\n    print('late', flush=True)\n"
              "def main():\n    threading.Thread(target=late).start()\n"
              "program.main = main\nprogram.program()\n")
    done = _run(script, tmp_path=tmp_path)
    assert done.returncode == 0 and done.stdout == "late\n", done.stderr


def test_what_native_code_printed_reaches_a_pipe(tmp_path):
    """C's stdout is block-buffered into a pipe (unless PYTHONUNBUFFERED, which this run leaves out, makes Python
    unbuffer it): os._exit alone would drop what native code printed last."""
    script = ("import ctypes\nimport synthesis.program as program\n"
              "def main():\n    ctypes.CDLL(None).printf(b'from C\\n')\n"
              "program.main = main\nprogram.program()\n")
    done = _run(script, tmp_path=tmp_path)
    assert done.returncode == 0 and done.stdout == "from C\n", (done.stdout, done.stderr)


# --- standard streams: a reader that leaves, a descriptor never there -------------------------------------------------

SPEC = "problems/steering/steering_redesign_27.toml"


def _shell(command: str, tmp_path) -> subprocess.CompletedProcess:
    return subprocess.run(["bash", "-c", f"set -o pipefail; {command}"], capture_output=True, text=True, timeout=180,
                          cwd=tmp_path)


@pytest.mark.slow
def test_a_reader_that_leaves_costs_the_run_nothing(tmp_path):
    """`agrisynth solve ... | head -1`: the broken pipe came out of a progress line inside the run; click made it exit 1
    and the run's folder was discarded.  Now the solve finishes, keeps its folder and exits with its own code."""
    from pathlib import Path

    spec = Path(__file__).resolve().parents[1] / SPEC
    done = _shell(f"{sys.executable} -m synthesis.program solve {spec} --out hp --workers 1 --starts 8 2>err.txt "
                  f"| head -1; echo \"codes ${{PIPESTATUS[@]}}\" >&2", tmp_path)
    assert "codes 0 0" in done.stderr, done.stderr
    assert json.loads((tmp_path / "hp" / "steering_redesign_27" / "result.json").read_text())["status"] == "optimal"
    assert "Traceback" not in (tmp_path / "err.txt").read_text()


@pytest.mark.parametrize("closed, code", [(">&-", 0), ("2>&-", 0), (">&- 2>&-", 0)])
@pytest.mark.slow
def test_a_command_started_without_its_standard_streams_runs_and_exits_with_its_code(tmp_path, closed, code):
    """`>&-` (a daemon, cron): the first isatty() raised a traceback (exit 1, nothing written); a bad spec exited 1,
    not 2.  The closed descriptors are /dev/null."""
    from pathlib import Path

    spec = Path(__file__).resolve().parents[1] / SPEC
    done = _shell(f"{sys.executable} -m synthesis.program check {spec} --out out {closed}; echo \"code $?\" > code.txt",
                  tmp_path)
    assert (tmp_path / "code.txt").read_text() == f"code {code}\n", done.stderr
    assert (tmp_path / "out" / "steering_redesign_27-check" / "result.json").is_file()
    _shell(f"{sys.executable} -m synthesis.program check no-such.toml {closed}; echo \"code $?\" > code.txt", tmp_path)
    assert (tmp_path / "code.txt").read_text() == "code 2\n"


def test_the_resume_line_is_quoted_for_the_shell(capsys):
    """A spec and folder with spaces: the printed line, pasted, was split into more arguments."""
    from pathlib import Path

    from synthesis.cli.views import stopped_message
    from synthesis.runs.requests import Stopped

    stopped_message(Stopped("SIGINT", 3, 8, Path("sp ace/ü 1/my run"), Path("my spec.toml")))
    err = capsys.readouterr().err
    assert "agrisynth solve 'my spec.toml' --resume 'sp ace/ü 1/my run'" in err


def test_a_profiler_running_the_program_gets_its_output(tmp_path):
    """`python -m cProfile -o prof.out -m synthesis.program problems` wrote no prof.out: the profiler saves after the
    program returns, which the fast end never did.  Under a profiler or tracer the process ends the ordinary way."""
    done = subprocess.run([sys.executable, "-m", "cProfile", "-o", "prof.out", "-m", "synthesis.program", "problems"],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0 and (tmp_path / "prof.out").stat().st_size > 1000, done.stderr


def test_an_auto_run_kept_at_its_last_finished_batch_says_the_batch_it_had_begun(capsys):
    """Stopped 3 starts into batch 32, which did no better than batch 16: "after 16 of 16 starts" alone hid that a
    batch had begun and that its finished starts are kept for --resume."""
    from pathlib import Path

    from synthesis.cli.views import stopped_message
    from synthesis.runs.requests import Stopped

    stopped_message(Stopped("SIGINT", 16, 16, Path("results/run"), Path("spec.toml"), begun=(32, 3)))
    err = " ".join(capsys.readouterr().err.split())
    assert ("interrupted by SIGINT after 16 of 16 starts (the batch of 32 starts it had begun, 3 of them finished, "
            "did no better: its starts are kept too): kept them") in err


def test_the_console_script_collects_garbage_fully_once_in_a_hundred_middle_collections(tmp_path):
    """program() sets GC_THRESHOLDS before the command imports anything (no full collection during its imports),
    and full collections still come: a cycle old enough to sit in the oldest generation, dropped, is freed once
    enough new objects have survived (700 x 10 x 100 of them and a quarter of the old ones), with no gc.collect."""
    script = ("import gc, sys, weakref\nimport synthesis.program as program\n"
              "class Node:\n    pass\n"
              "def main():\n"
              "    print(gc.get_threshold())\n"
              "    a, b = Node(), Node()\n    a.other, b.other = b, a\n    gone = weakref.ref(a)\n"
              "    gc.collect()\n    assert gc.is_tracked(a) and gone() is not None\n"
              "    del a, b\n"
              "    before = gc.get_stats()[2]['collections']\n"
              "    kept = [[None] for _ in range(1_500_000)]\n"
              "    print(gone() is None, gc.get_stats()[2]['collections'] - before)\n"
              "program.main = main\nprogram.program()\n")
    done = _run(script, tmp_path=tmp_path)
    assert done.returncode == 0, done.stderr
    threshold, (freed, full) = done.stdout.split("\n")[0], done.stdout.split("\n")[1].split()
    assert threshold == "(700, 10, 100)" and freed == "True" and int(full) >= 1
