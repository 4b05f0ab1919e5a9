"""Hostile input that once hung agrisynth or ended it in a traceback, each with its reproducer: a FIFO, a device
or deeply nested JSON where a file is read; a peer that is no dask scheduler; a spec with thousands of bad entries;
a studio client that sends nested JSON or never sends its body; targets that coincide.  Every one now ends in one
line and an exit code, within a deadline."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest

from conftest import LIBRARY
from solving import agrisynth, spec_with


def _one_line_error(proc, code: int = 2) -> str:
    assert proc.returncode == code, (proc.returncode, proc.stdout[-800:], proc.stderr[-800:])
    assert "Traceback" not in proc.stderr and "Traceback" not in proc.stdout, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    return lines[0]


# --- every file read through the one guarded reader --------------------------------------------------------------

def _hostile_result_json(folder: Path, what: str) -> Path:
    """``folder/result.json`` as a FIFO (open() blocks for ever), a link to /dev/zero (read() never ends) or JSON
    nested 100,000 deep (json's parser recursion)."""
    folder.mkdir()
    path = folder / "result.json"
    if what == "fifo":
        os.mkfifo(path)
    elif what == "dev_zero":
        path.symlink_to("/dev/zero")
    else:
        path.write_text("[" * 100_000 + "]" * 100_000)
    return path


@pytest.mark.parametrize("what", ["fifo", "dev_zero", "nested"])
def test_tolerance_of_a_folder_with_a_hostile_result_json_says_there_is_no_solved_design(tmp_path, what):
    """`agrisynth tolerance DIR` without DIR/solved.toml reads DIR/result.json to say why: it read it unguarded (a
    FIFO hung it for over 120 s, /dev/zero ate memory until MemoryError, the nested file was a RecursionError
    traceback); now through the reader `compare` uses: exit 2, one line, at once, nothing written."""
    folder = tmp_path / "run"
    _hostile_result_json(folder, what)
    t0 = time.perf_counter()
    proc = agrisynth("tolerance", folder, "--length", "0.1", "--out", tmp_path / "out", timeout=30)
    assert time.perf_counter() - t0 < 10
    assert _one_line_error(proc) == f"error: {folder}: no solved.toml in this folder (give a solve's run folder or a " \
                                    f"spec file)"
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("what", ["fifo", "dev_zero", "nested"])
def test_the_guarded_reader_refuses_each_in_one_line(tmp_path, what):
    from synthesis.errors import ResultError
    from synthesis.result import load_result

    path = _hostile_result_json(tmp_path / "run", what)
    with pytest.raises(ResultError) as err:
        load_result(path.parent)
    expected = {"fifo": "not a regular file (a pipe, socket or device", "dev_zero": "not a regular file",
                "nested": "nested too deeply"}[what]
    assert str(err.value).startswith(f"{path}: {expected}") and "\n" not in str(err.value)


def test_json_nested_deeper_than_agrisynth_writes_is_refused_before_any_reader_recurses(tmp_path):
    """200 levels parse (Python's parser allows about 1000), but the readers of a parsed file recurse over it."""
    from synthesis.errors import ResultError
    from synthesis.files import MAX_JSON_DEPTH, parse_json

    assert parse_json(b'{"a": ' + b"[" * (MAX_JSON_DEPTH - 1) + b"]" * (MAX_JSON_DEPTH - 1) + b"}", "f", ResultError)
    with pytest.raises(ResultError, match=rf"^f: nested more than {MAX_JSON_DEPTH} levels deep; not a x agrisynth"):
        parse_json(b"[" * 200 + b"]" * 200, "f", ResultError, "a x")


@pytest.mark.parametrize("what", ["fifo", "dev_zero"])
def test_a_run_folder_whose_marker_or_start_log_is_a_fifo_or_device(tmp_path, what):
    """The marker (is this agrisynth's folder?) and starts.jsonl (--resume) are read by the same reader: a FIFO or
    a device there is no marker / an unreadable start log (exit 2, one line), never a hang."""
    from synthesis.core import startlog
    from synthesis.errors import OutputError
    from synthesis.result import RUN_MARKER, is_run_folder

    def hostile(path: Path) -> None:
        os.mkfifo(path) if what == "fifo" else path.symlink_to("/dev/zero")

    marked = tmp_path / "marker"
    marked.mkdir()
    hostile(marked / RUN_MARKER)
    t0 = time.perf_counter()
    assert not is_run_folder(marked)
    run = tmp_path / "run"
    run.mkdir()
    (run / RUN_MARKER).write_text(json.dumps({"agrisynth_run": 1}))
    hostile(run / startlog.FILENAME)
    assert startlog.settings_of(run) == {}
    with pytest.raises(OutputError, match=r"starts\.jsonl: not a regular file"):
        startlog.read(run, "fingerprint")
    assert time.perf_counter() - t0 < 5


# --- validation linear in the number of bad entries --------------------------------------------------------------

def _many_bad_hold_near(tmp_path: Path, n: int) -> Path:
    """problems/clamp_cam/opening_cam.toml with hold_near = n copies of [{value = 0.0}, 146.0] (n = 8,000: 190 KB)."""
    text = (LIBRARY / "clamp_cam" / "opening_cam.toml").read_text()
    assert "hold_near = [[0.0, 146.0]]" in text
    spec = tmp_path / f"bad_{n}.toml"
    spec.write_text(text.replace("hold_near = [[0.0, 146.0]]",
                                 "hold_near = [" + ", ".join(["[{value = 0.0}, 146.0]"] * n) + "]"))
    return spec


def test_a_spec_with_8000_bad_list_entries_is_refused_in_seconds(tmp_path):
    """Refusing it took 137 s (the union-noise pruning compared every error line with every other); now about
    1.5 s on the 2-core CI machine.  The timeout is generous (60 s) rather than tight: the linearity itself is the
    deterministic count of the next test."""
    spec = _many_bad_hold_near(tmp_path, 8000)
    t0 = time.perf_counter()
    proc = agrisynth("check", spec, "--out", tmp_path / "out", timeout=60)
    took = time.perf_counter() - t0
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    lines = proc.stderr.strip().splitlines()
    assert lines[0] == f"error: {spec}: clamp_cam.timing.hold_near.0.0: expected a number, got {{'value': 0.0}}"
    assert lines[-1] == "... and 7996 more problem(s) in the spec (fix these first)" and len(lines) == 5
    assert took < 60


def _python_lines_run(function, *args) -> int:
    """How many lines of Python ``function(*args)`` executes (its own and every function it calls): a measure of
    its work that does not depend on the machine or its load."""
    import sys
    import threading

    count = 0

    def trace(frame, event, arg):
        nonlocal count
        if event == "line":
            count += 1
        return trace

    assert threading.current_thread() is threading.main_thread()
    previous = sys.gettrace()
    sys.settrace(trace)
    try:
        function(*args)
    finally:
        sys.settrace(previous)
    return count


def test_pruning_the_error_lines_is_linear_in_their_number():
    """The lines a "number | table" union yields for n bad entries (each entry's number branch, given a table,
    and the table's own complaints; half of them with the table branch too): 4 times the lines, about 4 times the
    work -- the pairwise search did 16 times (it ran about 3 lines of Python per pair)."""
    from synthesis.spec.common import _prune_union_noise

    def lines(n: int) -> list[str]:
        out = []
        for i in range(n):
            out += [f"s.hold_near.{i}.0: expected a number, got {{'value': 0.0}}",
                    f"s.hold_near.{i}.0.value: unknown field"]
            if i % 2:
                out += [f"s.hold_near.{i}.1: expected a number in mm, written without a unit, got 'x'",
                        f"s.hold_near.{i}.1: expected a table, got 'x'"]
        return out

    small, large = (_python_lines_run(_prune_union_noise, lines(n)) for n in (500, 2000))
    assert 3.5 < large / small < 4.5, (small, large)
    pruned = _prune_union_noise(lines(4))
    assert pruned == ["s.hold_near.0.0.value: unknown field",
                      "s.hold_near.1.0.value: unknown field",
                      "s.hold_near.1.1: expected a number in mm, written without a unit, got 'x'",
                      "s.hold_near.2.0.value: unknown field",
                      "s.hold_near.3.0.value: unknown field",
                      "s.hold_near.3.1: expected a number in mm, written without a unit, got 'x'"]


# --- a deadline on every read of the scheduler's handshake -------------------------------------------------------

#: the handshake a dask scheduler (distributed 2026.8) sends first: its length, then one frame, msgpack of
#: {"compression": None, "python": [3, 11, 7], "pickle-protocol": 5}
DASK_HANDSHAKE = (bytes.fromhex("3a00000000000000")          # 58 bytes follow
                  + bytes.fromhex("0100000000000000")        # one frame
                  + bytes.fromhex("2a00000000000000")        # of 42 bytes
                  + b"\x83\xabcompression\xc0\xa6python\x93\x03\x0b\x07\xafpickle-protocol\x05")


class _Peer:
    """A TCP server on a free loopback port sending ``greetings[i]`` on its i-th connection (the last one for every
    later connection), then holding the connection open and silent."""

    def __init__(self, *greetings: bytes):
        import socket
        import threading

        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.greetings, self.held = greetings, []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            conn.sendall(self.greetings[min(len(self.held), len(self.greetings) - 1)])
            self.held.append(conn)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for conn in self.held:
            conn.close()
        self.sock.close()


@pytest.mark.parametrize("greeting, complaint", [
    (DASK_HANDSHAKE[:8], "announced a 58-byte message and did not send it within 0.5 s"),
    (DASK_HANDSHAKE[:8] + b"\xff" * 58, "does not speak the dask protocol (its first message announces "
                                        "18446744073709551615 frames)"),
    (DASK_HANDSHAKE[:8] + DASK_HANDSHAKE[8:24] + b"\xc1" * 42, "does not speak the dask protocol (its first frame is "
                                                               "not msgpack"),
    (DASK_HANDSHAKE[:8] + DASK_HANDSHAKE[8:20], "announced a 58-byte message and did not send it"),
], ids=["length_then_silence", "length_then_garbage", "frames_then_not_msgpack", "part_then_silence"])
def test_a_peer_sending_a_plausible_length_then_silence_or_garbage_is_refused_by_the_deadline(greeting, complaint):
    """A plausible 8-byte length passed the probe: dask then waited for ever for the rest (over 120 s), or unpacked
    the garbage into a struct.error traceback.  Now the probe reads and checks the whole handshake by its deadline."""
    from synthesis.core.cluster import probe_scheduler
    from synthesis.errors import AgrisynthError

    with _Peer(greeting) as peer:
        t0 = time.perf_counter()
        with pytest.raises(AgrisynthError) as err:
            probe_scheduler(peer.address, timeout=0.5)
        assert time.perf_counter() - t0 < 2.0
    message = str(err.value)
    assert err.value.exit_code == 2 and complaint in message and "\n" not in message, message


def test_a_real_dask_handshake_passes_the_probe():
    from synthesis.core.cluster import handshake_problem, probe_scheduler

    assert handshake_problem(DASK_HANDSHAKE[8:]) is None
    with _Peer(DASK_HANDSHAKE) as peer:
        probe_scheduler(peer.address, timeout=0.5)


@pytest.mark.parametrize("second", [DASK_HANDSHAKE[:8], DASK_HANDSHAKE], ids=["length_only", "handshake_then_silence"])
@pytest.mark.slow
def test_a_peer_that_passes_the_probe_then_stops_answering_dask_is_refused_by_the_deadline(second):
    """dask's own connection reads the scheduler's handshake with no deadline: a peer that greets the probe and then
    sends a length and nothing more would hold Client() for ever; one that greets and then never answers is dask's
    own timeout.  Both: exit 2, one line, within twice the connect timeout."""
    pytest.importorskip("distributed")
    from synthesis.core.cluster import _connected_client, probe_scheduler
    from synthesis.errors import AgrisynthError

    with _Peer(DASK_HANDSHAKE, second) as peer:
        probe_scheduler(peer.address, timeout=1.0)
        t0 = time.perf_counter()
        with pytest.raises(AgrisynthError) as err:
            _connected_client(peer.address, timeout=1.0)
        assert time.perf_counter() - t0 < 4.0
    message = str(err.value)
    assert err.value.exit_code == 2 and "\n" not in message and message.startswith(f"--scheduler {peer.address}: ")
    assert ("no dask handshake within 2 s" if second == DASK_HANDSHAKE[:8] else "cannot reach a dask scheduler") \
        in message, message


@pytest.mark.slow
def test_solve_with_a_scheduler_sending_a_length_then_garbage_exits_2_in_one_line(tmp_path):
    with _Peer(DASK_HANDSHAKE[:8] + b"\xff" * 58) as peer:
        proc = agrisynth("solve", LIBRARY / "planting_arm" / "redesign_from_example1.toml", "--starts", "2",
                         "--out", tmp_path, "--scheduler", peer.address, timeout=60)
    line = _one_line_error(proc)
    assert line.startswith(f"error: --scheduler {peer.address}: the peer does not speak the dask protocol")
    assert list(tmp_path.iterdir()) == []


# --- the studio: nested JSON is bad input, a body that never comes has a deadline -----------------------------------

@pytest.fixture(scope="module")
def studio(tmp_path_factory):
    pytest.importorskip("starlette")
    from studio_fixtures import STUDIO_SPECS, running_studio

    with running_studio(STUDIO_SPECS["crank_rocker"], tmp_path_factory.mktemp("studio")) as studio:
        yield studio


@pytest.mark.parametrize("body, reason", [
    (b"[" * 30000 + b"]" * 30000, "nested too deeply"),                 # the parser's recursion: was a 500
    (b'{"values": ' + b"[" * 100 + b"]" * 100 + b"}", "nested more than 64 levels deep"),
], ids=["30000_deep", "100_deep"])
def test_the_studio_answers_deeply_nested_json_400(studio, body, reason):
    from studio_fixtures import request

    status, _, raw = request(studio, "POST", "/api/evaluate", body)
    assert (status, json.loads(raw)) == (400, {"error": f"request: not JSON ({reason})"})


def test_the_studio_answers_a_body_that_never_comes_within_its_deadline(studio):
    """A client that declares 100 bytes and sends none was held with no answer for over 70 s: now 408 at the
    deadline (0.5 s here, 10 s by default) and the connection closed."""
    import socket

    studio.body_seconds = 0.5
    try:
        with socket.create_connection(("127.0.0.1", studio.port), timeout=10) as conn:
            conn.sendall(f"POST /api/evaluate HTTP/1.1\r\nHost: 127.0.0.1:{studio.port}\r\nX-Studio-Token: "
                         f"{studio.token}\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n".encode())
            t0 = time.perf_counter()
            answer = b""
            while chunk := conn.recv(65536):          # until the server closes the connection
                answer += chunk
            took = time.perf_counter() - t0
    finally:
        from synthesis.studio.server import BODY_SECONDS

        studio.body_seconds = BODY_SECONDS
    head, _, body = answer.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 408 ") and b"connection: close" in head.lower(), head
    assert json.loads(body) == {"error": "request: the body did not arrive within 0.5 s"}
    assert 0.4 < took < 5, took
    from studio_fixtures import api

    assert api(studio, "/api/session")["kind"] == "crank_rocker"        # the studio serves on


# --- a signal in the first moments of start-up -------------------------------------------------------------------

def _signalled_at_import(tmp_path: Path, module: str, signum: int, *args: str):
    """``agrisynth ARGS`` through the program's entry point, with ``signum`` sent to itself the moment ``module`` is
    first imported (an import finder): a signal landing exactly there, every time."""
    import subprocess
    import sys

    script = tmp_path / "signalled_import.py"
    script.write_text(
        "import os, sys\n"
        "class Signalling:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        f"        if name == {module!r}:\n"
        "            sys.meta_path.remove(self)\n"
        f"            os.kill(os.getpid(), {int(signum)})\n"
        "        return None\n"
        "sys.meta_path.insert(0, Signalling())\n"
        "from synthesis.program import main\n"
        f"sys.argv = ['agrisynth', *{list(args)!r}]\n"
        "main()\n")
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=60, cwd=tmp_path)


@pytest.mark.parametrize("module", ["synthesis.cli", "casadi", "synthesis.kinds"])
def test_a_sigterm_during_start_up_is_exit_143_and_one_line(tmp_path, module):
    """A SIGTERM before the command's handlers existed ended the run silently (killed by the signal, no word, exit
    -15): at the command line's import (0.1 s in), at casadi's (the rules'), at the kind registry's (the check
    command's own imports, before it installs its handlers).  The entry point now installs them first."""
    import signal

    proc = _signalled_at_import(tmp_path, module, signal.SIGTERM, "check",
                                str(LIBRARY / "planting_arm" / "taiwan_example1.toml"), "--out", str(tmp_path / "out"))
    assert proc.returncode == 143 and proc.stderr.strip() == "interrupted", (proc.returncode, proc.stderr[-2000:])
    assert not (tmp_path / "out").exists()


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_the_studio_through_the_entry_point_keeps_its_signals(tmp_path):
    """The start-up handlers give way when the studio serves: started ignoring SIGINT (a script's `&`), SIGINT leaves
    it serving, and SIGTERM ends it by the signal, as `agrisynth studio` documents."""
    import signal
    import subprocess
    import sys
    import urllib.request

    from studio_fixtures import STUDIO_SPECS

    def ignoring_sigint():
        for sig in (signal.SIGHUP, signal.SIGTERM):
            signal.signal(sig, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.SIG_IGN)

    pytest.importorskip("starlette")
    proc = subprocess.Popen([sys.executable, "-m", "synthesis.program", "studio", str(STUDIO_SPECS["crank_rocker"]),
                             "--out", str(tmp_path / "studio")], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=ignoring_sigint)
    try:
        url = next(word for _ in range(5) for word in proc.stdout.readline().split() if word.startswith("http://"))
        for _ in range(200):
            try:
                assert b"agrisynth studio" in urllib.request.urlopen(url, timeout=10).read()
                break
            except OSError:
                time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        with pytest.raises(subprocess.TimeoutExpired):
            proc.wait(timeout=2)
        assert b"agrisynth studio" in urllib.request.urlopen(url, timeout=10).read()
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == -signal.SIGTERM


# --- a signal during the Monte-Carlo -----------------------------------------------------------------------------

def test_a_signal_inside_a_casadi_call_of_a_monte_carlo_sample_stops_the_run_after_that_sample(monkeypatch):
    """SIGTERM during the Monte-Carlo that checks a robust solve's answer: raised inside a CasADi call it came out
    as a NotImplementedError traceback (CasADi reads a failed argument conversion so), or was swallowed and the
    remaining samples ran on (17-23 s).  Here the signal lands inside CasADi's conversion of an argument in sample
    5: the sample finishes, and KeyboardInterrupt -- the interruption the solve keeps its starts on -- follows."""
    import signal
    from types import SimpleNamespace

    import casadi as ca
    import numpy as np

    from synthesis.core import interrupt
    from synthesis.spec import load_spec
    from synthesis.tolerance import analysis

    x = ca.SX.sym("x")
    square = ca.Function("square", [x], [x ** 2])

    class SignalledWhileConverted:
        """An argument CasADi converts by calling its __DM__ (Python code, so the signal's handler runs there)."""

        def __DM__(self):
            os.kill(os.getpid(), signal.SIGTERM)
            return ca.DM(3.0)

    done = []

    def recheck(setting, outcome):
        value = float(square(SignalledWhileConverted() if outcome.start == 5 else 3.0))
        done.append(outcome.start)
        return SimpleNamespace(rules=[SimpleNamespace(record=lambda: SimpleNamespace(name="r", margin=value,
                                                                                      satisfied=True))])

    solving = SimpleNamespace(prepare=lambda spec: None, recheck=recheck)
    monkeypatch.setattr(analysis, "envelope_kind", lambda kind, spec: SimpleNamespace(solving=lambda: solving))
    spec = load_spec(LIBRARY / "planting_arm" / "robust_redesign_from_example1.toml").model
    dmap = SimpleNamespace(keys=["a", "b"], n=2, followers={})
    interrupt.install()
    try:
        with pytest.raises(KeyboardInterrupt):
            analysis.monte_carlo(None, spec, {"a": 1.0, "b": 2.0}, dmap, np.array([0.1, 0.1]), 1000, 0)
        assert interrupt.pending() == signal.SIGTERM
    finally:
        interrupt.uninstall()
    assert done == [0, 1, 2, 3, 4, 5]


@pytest.mark.long
@pytest.mark.slow
def test_sigterm_during_a_robust_solves_monte_carlo_keeps_the_starts_and_exits_143_within_5_s(tmp_path):
    """The reproducer itself: a tolerance-robust solve (2 starts, one worker; 5,000 Monte-Carlo samples, minutes of
    checking) gets SIGTERM 3 s after its last start is logged, in its answer's check.  It was a NotImplementedError
    traceback with nothing written (1 of 4 tries) or exit 143 17-23 s later: now 143 within 5 s, the two starts kept
    (status interrupted) for --resume, no figures drawn (the page says so), no traceback.  About 40 s."""
    import signal
    import subprocess
    import sys

    spec = tmp_path / "robust.toml"
    spec.write_text((LIBRARY / "planting_arm" / "robust_redesign_from_example1.toml").read_text()
                    .replace("samples = 2000", "samples = 5000"))
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "synthesis.program", "solve", str(spec), "--starts", "2",
                             "--workers", "1", "--out", str(out)], cwd=tmp_path, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.monotonic()
        while not any(len(log.read_text().splitlines()) >= 3 for log in out.glob(".*.run-*/starts.jsonl")):
            assert proc.poll() is None and time.monotonic() - t0 < 240, "the starts did not finish"
            time.sleep(0.1)
        time.sleep(3)
        assert proc.poll() is None
        signalled = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - signalled
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 143 and "Traceback" not in err, err
    # the promise is 5 s (about 0.1 s on an idle machine); on a machine whose two cores the rest of the suite keeps
    # busy it took 8 s: 15 s still fails the 17-120 s it took before the Monte-Carlo obeyed signals between samples
    assert took < 15, took
    assert "interrupted by SIGTERM after 2 of 2 starts" in err and "--resume" in err
    run = out / "robust_redesign_from_example1"
    result = json.loads((run / "result.json").read_text())
    assert result["status"] == "interrupted" and result["solver"]["starts_run"] == 2
    assert result["facts"]["tolerance"]["monte_carlo"]["samples"] == 0
    assert len((run / "starts.jsonl").read_text().splitlines()) == 3           # the header and both starts
    assert sorted(p.name for p in run.iterdir()) == [".agrisynth-run", "ipopt.log", "report.html", "result.json",
                                                     "starts.jsonl"]
    assert "no figures: the run was interrupted" in (run / "report.html").read_text()


# --- a killed run's staging folder, once its --resume is complete --------------------------------------------------

def _killed_run(tmp_path: Path, starts: int = 3, kept: int = 2) -> tuple[Path, Path, dict]:
    """What a SIGKILL after ``kept`` of ``starts`` starts leaves (OUT/.<name>.run-XXXX: the marker, with the dead
    process's pid, and starts.jsonl's header and first ``kept`` starts), from an uninterrupted run of the same starts;
    returns (OUT, the staging folder, the uninterrupted result)."""
    import subprocess
    import sys

    from synthesis.result import RUN_MARKER

    whole = tmp_path / "whole"
    proc = agrisynth("solve", LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml", "--starts", starts,
                     "--workers", "1", "--out", whole)
    assert proc.returncode == 0, proc.stderr
    run = whole / "cai2020_crank_rocker_synthesis"
    out = tmp_path / "out"
    staging = out / ".cai2020_crank_rocker_synthesis.run-k1ll3d_x"
    staging.mkdir(parents=True)
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    (staging / RUN_MARKER).write_text(json.dumps({"agrisynth_run": 1, "name": "cai2020_crank_rocker_synthesis",
                                                  "pid": int(gone.stdout), "written_by": "agrisynth"}) + "\n")
    lines = (run / "starts.jsonl").read_text().splitlines(keepends=True)
    (staging / "starts.jsonl").write_text("".join(lines[:1 + kept]))
    return out, staging, json.loads((run / "result.json").read_text())


def _comparable(result: dict) -> dict:
    result = json.loads(json.dumps(result))
    for key in ("wall_s", "workers"):
        result["solver"].pop(key, None)
    for row in result["starts"]:
        row.pop("wall_s")
    return result


@pytest.mark.slow
def test_a_killed_runs_staging_folder_is_removed_once_its_resume_is_complete(tmp_path):
    """After a SIGKILL, `--resume OUT/.<name>.run-XXXX` wrote the answer to OUT/<name>/ and left the staging folder
    with its stale starts.jsonl (3 of 3 trials): now it is removed, the answer being the uninterrupted run's."""
    out, staging, whole = _killed_run(tmp_path)
    proc = agrisynth("solve", LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml", "--resume", staging,
                     "--workers", "1")
    assert proc.returncode == 0, proc.stderr
    assert f"resumed: 2 finished start(s) read from {staging}/starts.jsonl" in proc.stdout
    assert sorted(p.name for p in out.iterdir()) == ["cai2020_crank_rocker_synthesis"]
    resumed = json.loads((out / "cai2020_crank_rocker_synthesis" / "result.json").read_text())
    assert _comparable(resumed) == _comparable(whole)


@pytest.mark.parametrize("why", ["running", "foreign_file", "sub_folder"])
@pytest.mark.slow
def test_a_staging_folder_that_may_still_be_in_use_or_holds_anything_else_is_kept(tmp_path, why):
    """Removed only when everything says it is a dead run's staging folder and nothing else: a marker naming a
    running process (a run still writing there), a file agrisynth does not write, or a folder in it: kept."""
    out, staging, _ = _killed_run(tmp_path)
    from synthesis.result import RUN_MARKER

    if why == "running":
        marker = json.loads((staging / RUN_MARKER).read_text())
        (staging / RUN_MARKER).write_text(json.dumps({**marker, "pid": os.getppid()}))
    elif why == "foreign_file":
        (staging / "notes.txt").write_text("mine")
    else:
        (staging / "figures").mkdir()
    before = sorted(p.name for p in staging.iterdir())
    proc = agrisynth("solve", LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml", "--resume", staging,
                     "--workers", "1")
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in staging.iterdir()) == before
    assert (out / "cai2020_crank_rocker_synthesis" / "result.json").is_file()


# --- fourbar_path targets closer than a tolerance are one target -------------------------------------------------

def _picking_arc_with(tmp_path: Path, name: str, points: list[list[float]], starts: int = 2) -> Path:
    import re

    text = (LIBRARY / "fourbar_path" / "picking_arc.toml").read_text()
    text = re.sub(r"points = \[.*?\n\]", "points = " + json.dumps(points), text, count=1, flags=re.S)
    text = text.replace('name = "picking_arc"', f'name = "{name}"').replace("starts = 64", f"starts = {starts}")
    spec = tmp_path / f"{name}.toml"
    spec.write_text(text)
    return spec


def test_three_targets_two_of_them_1e9_mm_apart_are_refused_as_two(tmp_path):
    """They counted as three distinct targets and the degenerate set solved "optimal" with no word."""
    spec = _picking_arc_with(tmp_path, "degenerate", [[376.0, 123.7], [205.0, 258.0], [205.0, 258.000000001]])
    proc = agrisynth("check", spec, "--out", tmp_path / "out")
    assert _one_line_error(proc) == (
        f"error: {spec}: fourbar_path.targets: points: expected at least 3 distinct target points, got 2 among the 3 "
        f"given (points closer than 1e-06 of the set's size, 0.000217 mm here, are one target)")


@pytest.mark.slow
def test_targets_1e7_mm_apart_are_one_target_and_the_run_says_so(tmp_path):
    """Four targets, the last two 1e-7 mm apart (the set 217 mm across: under its 2.17e-4 mm): check and solve name
    them one target in result.json (facts.same_targets, the note) and on the terminal; the solve is still optimal."""
    spec = _picking_arc_with(tmp_path, "near_duplicate", [[376.0, 123.7], [294.7298981903177, 216.36242801169448],
                                                          [205.0, 258.0], [205.0, 258.0000001]])
    said = ("targets 2 and 3 (1e-07 mm apart) (numbered from 0) are closer than 1e-06 of the target set's size "
            "(0.000217 mm), so each pair is one target: one point of the path, weighed in the objective as often as "
            "it is given")
    check = agrisynth("check", spec, "--out", tmp_path / "out")
    assert check.returncode in (0, 1) and f"note: {said}" in " ".join(check.stdout.split()), check.stdout
    facts = json.loads((tmp_path / "out" / "near_duplicate-check" / "result.json").read_text())["facts"]
    assert facts["same_targets"] == [[2, 3]] and facts["note"] == said
    solve = agrisynth("solve", spec, "--out", tmp_path / "out", "--workers", "1")
    assert solve.returncode == 0 and f"note: {said}" in " ".join(solve.stdout.split()), solve.stdout + solve.stderr
    result = json.loads((tmp_path / "out" / "near_duplicate" / "result.json").read_text())
    assert result["status"] == "optimal" and result["solver"]["status_note"] == said
    assert result["facts"]["same_targets"] == [[2, 3]]


def test_which_targets_are_one():
    from synthesis.kinds.fourbar_path.spec import SAME_TARGET, same_target_mm, same_targets

    arc = [[0.0, 0.0], [30.0, 40.0], [60.0, 80.0]]          # 100 mm across: one target within 1e-4 mm
    assert same_target_mm(arc) == pytest.approx(100 * SAME_TARGET)
    assert same_targets(arc + [[0.0, 0.99e-4]]) == [(0, 3, pytest.approx(0.99e-4))]
    assert same_targets(arc + [[0.0, 1.01e-4]]) == []
    assert same_targets(arc + [[0.0, 0.0]]) == [(0, 3, 0.0)]                     # a repeated point: one target
    # prescribed timing: the same point at another crank angle is another target (a double point of the curve)
    assert same_targets(arc + [[0.0, 0.0]], [0.0, 90.0, 180.0, 270.0]) == []
    assert same_targets(arc + [[0.0, 0.0]], [0.0, 90.0, 180.0, 360.0]) == [(0, 3, 0.0)]


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_signal_inside_a_casadi_call_of_any_command_is_interrupted_not_a_traceback(tmp_path):
    """With the handlers installed at start-up a signal reaches every command; inside a CasADi call its
    KeyboardInterrupt comes out as NotImplementedError.  Here it lands in `agrisynth tolerance`'s linearisation:
    "interrupted", exit 143, nothing written -- not a NotImplementedError traceback (exit 1)."""
    import subprocess
    import sys

    script = tmp_path / "signalled_in_casadi.py"
    script.write_text(
        "import os, signal, sys\n"
        "import casadi as ca\n"
        "import synthesis.tolerance.analysis as analysis\n"
        "def linearise(*args, **kwargs):\n"
        "    x = ca.SX.sym('x')\n"
        "    class Signalled:\n"
        "        def __DM__(self):\n"
        "            os.kill(os.getpid(), signal.SIGTERM)\n"
        "            return ca.DM(1.0)\n"
        "    ca.Function('f', [x], [x])(Signalled())\n"
        "analysis.linearise = linearise\n"
        "from synthesis.program import main\n"
        f"sys.argv = ['agrisynth', 'tolerance', {str(LIBRARY / 'planting_arm' / 'taiwan_example1.toml')!r}, "
        f"'--length', '0.1', '--samples', '10', '--out', {str(tmp_path / 'out')!r}]\n"
        "main()\n")
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 143 and proc.stderr.strip() == "interrupted", (proc.returncode, proc.stderr[-2000:])
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("name", ['"a\\u0000b.toml"', '""', '"   "'])
def test_a_picker_part_file_that_names_no_file_is_refused_on_one_line(tmp_path, name):
    """The fuzz campaign's find: a NUL in the drive's file name reached the operating system as 'embedded null byte'
    from pathlib, a traceback; it is the spec's field now, named, at load."""
    import re

    from synthesis.errors import SpecError
    from synthesis.spec import load_spec

    text = (LIBRARY / "picker" / "cai2020_picker.toml").read_text()
    path = tmp_path / "picker.toml"
    path.write_text(re.sub(r'crank_rocker = "[^"]*"', lambda m: f"crank_rocker = {name}", text, count=1))
    with pytest.raises(SpecError) as refused:
        load_spec(path)
    message = str(refused.value)
    assert "picker.crank_rocker" in message and "spec file" in message and "\n" not in message.strip()


# --- rule limits the solver cannot be handed ------------------------------------------------------------------------

@pytest.mark.slow
def test_a_rule_range_narrower_than_the_solvers_back_off_is_refused_in_one_line(tmp_path):
    """[rules] depth = [24.95, 25.05] mm: the back-off holds each side 0.1 mm inside, which leaves the row a lower limit
    above its upper; every IPOPT start failed on it with CasADi's "Ill-posed problem detected" (exit 3)."""
    spec = tmp_path / "narrow.toml"
    spec.write_text((LIBRARY / "planting_arm" / "redesign_from_example1.toml").read_text()
                    .replace("[objective]", "[rules]\ndepth = [24.95, 25.05]\n\n[objective]", 1))
    line = _one_line_error(agrisynth("solve", str(spec), "--starts", "2", "--workers", "1", "--out",
                                     str(tmp_path / "out"), cwd=tmp_path))
    assert "rule planting_depth: its limits [24.95, 25.05] mm are closer together than the solver's back-off" in line
    assert "0.1 mm" in line and "[solver] backoff" in line
    assert not (tmp_path / "out").exists()
    # evaluating it is fine: check (and the tolerance analysis) hand nothing to IPOPT
    assert agrisynth("check", str(spec), "--out", str(tmp_path / "out"), cwd=tmp_path).returncode in (0, 1)
    assert agrisynth("tolerance", str(spec), "--length", "0.1", "--samples", "0", "--out", str(tmp_path / "out"),
                     cwd=tmp_path).returncode in (0, 1)
    # wide enough for its back-offs, the same spec solves
    spec.write_text(spec.read_text().replace("[24.95, 25.05]", "[24.5, 25.5]"))
    assert agrisynth("solve", str(spec), "--starts", "2", "--workers", "1", "--out", str(tmp_path / "out"),
                     cwd=tmp_path).returncode == 0


def test_a_planting_rule_range_of_one_value_is_refused_at_load(tmp_path):
    """depth = [25, 25]: no computed depth is 25 to the last digit (25.00000000000072 with analysis_depth = 25), so
    check and solve failed it, and solve advised more samples."""
    spec = tmp_path / "single.toml"
    spec.write_text((LIBRARY / "planting_arm" / "redesign_from_example1.toml").read_text()
                    .replace("[objective]", "[rules]\ndepth = [25, 25]\n\n[objective]", 1))
    line = _one_line_error(agrisynth("check", str(spec), "--out", str(tmp_path / "out"), cwd=tmp_path))
    assert "depth: [25, 25] is one value; give a range lo < hi" in line


@pytest.mark.parametrize("spec", ["planting_arm/redesign_from_example1.toml", "rotary_planetary/key_pose_redesign.toml"])
def test_an_entry_angle_minimum_of_90_deg_is_refused_at_load(tmp_path, spec):
    """The angle to the horizontal is at most 90 deg: a minimum of 90 asks for an exactly vertical entry that no
    computed velocity meets to the last digit (a solve failed it, advising more samples)."""
    text = (LIBRARY / spec).read_text()
    path = tmp_path / "vertical.toml"
    path.write_text(text.replace("[rules]\n", "[rules]\nentry_angle_min = 90\n", 1) if "[rules]\n" in text else
                    text.replace("[objective]", "[rules]\nentry_angle_min = 90\n\n[objective]", 1))
    line = _one_line_error(agrisynth("check", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path))
    assert line.endswith("rules.entry_angle_min: expected < 90, got 90"), line


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
@pytest.mark.parametrize("source, replacements, code, said", [
    # the arm does not assemble at the design: nothing to linearise (LAPACK's SVD on NaN, a traceback)
    ("planting_arm/taiwan_example1.toml", [("l2 = 35", "l2 = 200")], 2,
     "tolerance: the design cannot be linearised: the structural rows of planting are not finite at this design"),
    ("picker/cai2020_crank_rocker_synthesis.toml", [("l7 = { init = 50.0, bounds = [5.0, 200.0] }", "l7 = 300")], 2,
     "the structural rows of crank_rocker are not finite at this design"),
    # the tillage linkage's auxiliaries do not converge (an ArithmeticError's traceback)
    ("tillage/tillage_redesign.toml", [("c = { init = 500.0, bounds = [250.0, 900.0] }", "c = 250.0"),
                                       ("height_c = { init = 130.0, bounds = [100.0, 400.0] }", "height_c = 400")], 2,
     "the auxiliary variables of tillage_linkage do not converge onto their structural rows"),
    # corners of the box where the arm does not assemble: no claw path to cross the soil (an IndexError)
    ("planting_arm/taiwan_example1.toml", [("l2 = 35", "l2 = 70")], 1, None),
    # targets the coupler cannot reach: the check's crank angles are null (a TypeError comparing them)
    ("fourbar_path/picking_arc.toml", [("r1 = {init = 110, bounds = [20, 200]}", "r1 = 1000")], 1, None),
])
def test_tolerance_of_a_design_that_does_not_assemble_says_so_in_one_line(tmp_path, source, replacements, code, said):
    spec = spec_with(tmp_path, LIBRARY / source, replacements)
    proc = agrisynth("tolerance", str(spec), "--length", "0.5", "--samples", "20", "--out", str(tmp_path / "out"),
                     cwd=tmp_path)
    assert "Traceback" not in proc.stderr and "DLASCL" not in proc.stdout, proc.stderr[-2000:]
    assert proc.returncode in ((code,) if code == 2 else (0, 1)), proc.stdout + proc.stderr
    if said is not None:
        assert said in proc.stderr and len(proc.stderr.strip().splitlines()) == 1, proc.stderr


@pytest.mark.parametrize("field, value", [
    ("outcome", "x"), ("objective", None), ("objective", "x"), ("start", "0"), ("start", -1), ("start", True),
    ("design", [1, 2]), ("wall_s", "x"), ("details", "x"), ("return_status", 5), ("iterations", "x"),
    ("success", 1), ("log", None),
])
def test_a_damaged_starts_line_is_not_an_outcome(field, value):
    """--resume read each line of starts.jsonl as an outcome: {"outcome": "x"} was an AttributeError, an objective
    of null a TypeError deep in the verdict, a return status of 5 carried into result.json.  Such a line is now no
    outcome (TypeError, which the reader takes as a line to skip: its start is solved again)."""
    from synthesis.core.outcome import StartOutcome
    from synthesis.core.startlog import decode, encode

    good = encode(StartOutcome(3, {"l2": 35.0}, 1.5, "Solve_Succeeded", True, 12, 0.25, "log", None, {"a": 1}))
    assert decode(json.loads(json.dumps(good))) == StartOutcome(3, {"l2": 35.0}, 1.5, "Solve_Succeeded", True, 12,
                                                                0.25, "log", None, {"a": 1})
    bad = {"outcome": value} if field == "outcome" else {"outcome": {**good["outcome"], field: value}}
    with pytest.raises(TypeError):
        decode(bad)


def test_a_steering_table_giving_one_lock_twice_is_refused(tmp_path):
    """[published] inside_lock = [10, 10, 10, 40]: the table's concavity divided by zero (a traceback)."""
    spec = spec_with(tmp_path, LIBRARY / "steering" / "steering_redesign_40.toml",
                     [("inside_lock = [10.0, 20.0, 30.0, 40.0]", "inside_lock = [10.0, 10.0, 10.0, 40.0]")])
    proc = agrisynth("check", str(spec), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.strip() == (
        f"error: {spec}: steering_linkage.published: inside_lock[1] = 10: the same lock as inside_lock[0]; give each "
        f"printed row once")
