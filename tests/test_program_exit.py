"""The ``agrisynth`` program ends its process without the interpreter's teardown (synthesis.program.program): the
exit code stays the command's, every line written reaches its reader, the exit handlers run, and a thread still
running is waited for as Python would."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

PROGRAM = "from synthesis.program import program\nimport sys\nsys.argv = ['agrisynth', *sys.argv[1:]]\n"


def _run(code: str, *args: str, tmp_path, env=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=120,
                          cwd=tmp_path, env=env)


def test_the_commands_exit_code_and_whole_output_reach_the_caller_and_the_exit_handlers_run(tmp_path):
    marker = tmp_path / "atexit.txt"
    code = (f"import atexit, pathlib\n"
            f"atexit.register(lambda: pathlib.Path({str(marker)!r}).write_text('ran'))\n"
            f"{PROGRAM}program()\n")
    done = _run(code, "problems", tmp_path=tmp_path)
    assert done.returncode == 0, done.stderr
    listing = subprocess.run([sys.executable, "-m", "synthesis.program", "problems"], capture_output=True, text=True,
                             timeout=120, cwd=tmp_path).stdout
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
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    done = _run(script, tmp_path=tmp_path, env=env)
    assert done.returncode == 0 and done.stdout == "from C\n", (done.stdout, done.stderr)
