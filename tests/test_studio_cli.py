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

from solving import cli_run
from studio_fixtures import STUDIO_SPECS

pytest.importorskip("starlette")


def test_bad_input_is_one_line_and_exit_2(tmp_path):
    missing = cli_run("studio", str(tmp_path / "nowhere.toml"), cwd=tmp_path)
    assert missing.returncode == 2 and "nowhere.toml" in missing.stderr
    assert "Traceback" not in missing.stderr and len(missing.stderr.strip().splitlines()) == 1
    (tmp_path / "a_file").write_text("x")
    out_is_file = cli_run("studio", str(STUDIO_SPECS["crank_rocker"]), "--out", str(tmp_path / "a_file"), cwd=tmp_path)
    assert out_is_file.returncode == 2 and "Traceback" not in out_is_file.stderr
    assert out_is_file.stderr.strip().splitlines()[-1].startswith("Error: Invalid value for '--out'")   # click's usage error
    port = cli_run("studio", str(STUDIO_SPECS["crank_rocker"]), "--port", "70000", cwd=tmp_path)
    assert port.returncode == 2 and "--port" in port.stderr


def test_prints_the_address_serves_it_and_stops_on_ctrl_c(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "synthesis.cli", "studio", str(STUDIO_SPECS["crank_rocker"]),
                             "--out", str(tmp_path / "studio")], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        url = None
        for _ in range(5):
            line = proc.stdout.readline()
            match = re.search(r"http://127\.0\.0\.1:(\d+)/\?token=([A-Za-z0-9_-]{32})", line)
            if match:
                url = match.group(0)
                break
        assert url, "no address printed"
        for _ in range(200):          # the address is printed just before the server listens
            try:
                page = urllib.request.urlopen(url, timeout=10).read().decode()
                break
            except urllib.error.URLError:
                time.sleep(0.05)
        assert "agrisynth studio" in page
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(url.split("?")[0], timeout=10)
        assert refused.value.code == 403
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip() == "interrupted", err     # Ctrl-C: the CLI's exit 130
