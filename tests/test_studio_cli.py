"""`agrisynth studio` on the command line: it prints the page's address and serves it until Ctrl-C; bad
input is one line and exit 2."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request

import pytest

from solving import agrisynth
from studio_fixtures import STUDIO_SPECS

pytest.importorskip("starlette")


def _from_a_terminal() -> None:
    """The signal dispositions of a studio started from a terminal (SIGINT, SIGHUP, SIGTERM at their defaults).
    A process inherits ignored signals: a suite run in the background (`pytest &` ignores SIGINT, `nohup`
    SIGHUP) would otherwise start the studio with them ignored."""
    for sig in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM):
        signal.signal(sig, signal.SIG_DFL)


def _studio(tmp_path, preexec=_from_a_terminal) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "synthesis.cli", "studio", str(STUDIO_SPECS["crank_rocker"]),
                             "--out", str(tmp_path / "studio")], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=preexec)


def _address(proc: subprocess.Popen) -> re.Match:
    """The page's address the studio prints (port: group 1, token: group 2), from its first lines."""
    for _ in range(5):
        match = re.search(r"http://127\.0\.0\.1:(\d+)/\?token=([A-Za-z0-9_-]{32})", proc.stdout.readline())
        if match:
            return match
    raise AssertionError("no address printed")


def _page(url: str) -> str:
    """The page at ``url``, asked once: the address is printed once the server listens."""
    return urllib.request.urlopen(url, timeout=30).read().decode()


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_bad_input_is_one_line_and_exit_2(tmp_path):
    missing = agrisynth("studio", str(tmp_path / "nowhere.toml"), cwd=tmp_path)
    assert missing.returncode == 2 and "nowhere.toml" in missing.stderr
    assert "Traceback" not in missing.stderr and len(missing.stderr.strip().splitlines()) == 1
    (tmp_path / "a_file").write_text("x")
    out_is_file = agrisynth("studio", str(STUDIO_SPECS["crank_rocker"]), "--out", str(tmp_path / "a_file"),
                            cwd=tmp_path)
    assert out_is_file.returncode == 2 and "Traceback" not in out_is_file.stderr
    assert out_is_file.stderr.strip().splitlines() == [out_is_file.stderr.strip()]      # one line
    assert out_is_file.stderr.startswith("error: Invalid value for '--out'")   # click's usage error
    port = agrisynth("studio", str(STUDIO_SPECS["crank_rocker"]), "--port", "70000", cwd=tmp_path)
    assert port.returncode == 2 and "--port" in port.stderr


def test_a_port_in_use_is_one_line_and_leaves_no_folder(tmp_path):
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        busy = agrisynth("studio", str(STUDIO_SPECS["crank_rocker"]), "--port", str(port), "--out",
                         str(tmp_path / "new" / "studio"), cwd=tmp_path)
    assert busy.returncode == 2 and busy.stderr.strip().splitlines() == [busy.stderr.strip()], busy.stderr
    assert f"--port {port}: cannot listen on 127.0.0.1" in busy.stderr and "Traceback" not in busy.stderr
    assert not (tmp_path / "new").exists()


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_prints_the_address_serves_it_and_stops_on_ctrl_c(tmp_path):
    proc = _studio(tmp_path)
    try:
        url = _address(proc).group(0)
        assert "agrisynth studio" in _page(url)
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(url.split("?")[0], timeout=10)
        assert refused.value.code == 403
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip() == "interrupted", err     # Ctrl-C: the CLI's exit 130


def _children(pid: int) -> set[int]:
    """Pids of the direct children of ``pid`` (Linux /proc: every thread's list)."""
    from pathlib import Path

    out = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        out |= {int(c) for c in (task / "children").read_text().split()}
    return out


def _alive(pid: int) -> bool:
    import os

    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
@pytest.mark.slow
def test_a_signal_to_the_studio_cancels_its_solve_and_keeps_the_finished_starts(tmp_path, sig):
    """SIGTERM (or a closed terminal's SIGHUP) to `agrisynth studio` while a solve runs: the worker stops too,
    and the run folder keeps the starts finished so far, with status interrupted."""
    import json

    from solving import strict_json

    proc = _studio(tmp_path)
    try:
        match = _address(proc)
        base, token = f"http://127.0.0.1:{match.group(1)}", match.group(2)

        def call(path, body=None):
            headers = {"X-Studio-Token": token, "Content-Type": "application/json"}
            req = urllib.request.Request(base + path, headers=headers,
                                         data=None if body is None else json.dumps(body).encode())
            return json.loads(urllib.request.urlopen(req, timeout=30).read())     # printed once it listens

        call("/api/solve", {"starts": 256})
        while (answer := call("/api/solve"))["done"] < 1:      # a start finished, so there is something to keep
            assert answer["state"] == "running", answer
            time.sleep(0.1)
        (worker,) = _children(proc.pid)
        proc.send_signal(sig)
        proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == -sig
    assert not _alive(worker), f"the solve's worker {worker} outlived the studio"
    (run,) = [p for p in (tmp_path / "studio").iterdir() if p.is_dir()]
    result = strict_json(run / "result.json")
    assert result["status"] == "interrupted" and 1 <= len((run / "starts.jsonl").read_text().splitlines()) < 256


@pytest.mark.parametrize("sig", [signal.SIGHUP, signal.SIGINT])
@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_signal_the_studio_was_started_ignoring_leaves_it_serving(tmp_path, sig):
    """`nohup agrisynth studio ... &` ignores SIGHUP so that the studio outlives its terminal, and a script's
    `agrisynth studio ... &` ignores SIGINT: that signal then leaves the studio serving (SIGHUP once stopped it, and
    SIGINT ended it with exit 0 and no word), and SIGTERM still stops it."""
    def ignoring():
        _from_a_terminal()
        signal.signal(sig, signal.SIG_IGN)

    proc = _studio(tmp_path, ignoring)
    try:
        url = _address(proc).group(0)
        assert "agrisynth studio" in _page(url)
        proc.send_signal(sig)
        with pytest.raises(subprocess.TimeoutExpired):       # a studio that took the signal ends well within this
            proc.wait(timeout=3)
        assert "agrisynth studio" in _page(url)
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == -signal.SIGTERM
