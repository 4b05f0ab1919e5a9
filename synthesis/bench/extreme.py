"""The extreme-case matrix of ``agrisynth bench``: tests/extreme/ run as they are, one row per case.

:func:`extreme_matrix` runs ``pytest tests/extreme`` (its benchmark-marked cases too, all but the full scale
study) in a subprocess with this module as a plugin
(``-p synthesis.bench.extreme``), which writes one JSON row per test: the file (its kind), the case
(test name and parameters), what was tried (the docstring, or the name), passed/failed/skipped, the
time, and any figure the test records (``record_property("figure", ...)``).  Without a tests/extreme
folder (an installed copy) the matrix is empty and bench.md says so.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from synthesis.library import checkout

#: the source checkout this agrisynth runs from (None installed: a wheel ships no tests) and its extreme cases
ROOT = checkout()
EXTREME = None if ROOT is None else ROOT / "tests" / "extreme"
FULL_STUDY = "test_every_library_problem_every_start"
_ROWS: list[dict] = []
_DOCS: dict[str, str] = {}


def pytest_addoption(parser) -> None:
    parser.addoption("--extreme-json", default=None, help="agrisynth bench: write the extreme-case rows here")


def pytest_collection_modifyitems(session, config, items) -> None:
    for item in items:
        doc = getattr(getattr(item, "function", None), "__doc__", None) or ""
        _DOCS[item.nodeid] = " ".join(doc.split())


def pytest_runtest_logreport(report) -> None:
    if report.when == "call" or (report.when == "setup" and report.outcome != "passed"):
        name = report.nodeid.split("::", 1)[-1]
        figure = "; ".join(str(v) if k == "figure" else f"{k} {v}" for k, v in report.user_properties)
        # a strict xfail (a known failure with its measured cause) reads "skipped" in pytest's report: say what it is
        xfail = getattr(report, "wasxfail", None)
        outcome = "known failure (xfail)" if xfail is not None and report.outcome == "skipped" else report.outcome
        if xfail:
            figure = f"{figure}; cause: {xfail}" if figure else f"cause: {xfail}"
        _ROWS.append({"file": report.nodeid.split("::", 1)[0].rsplit("/", 1)[-1],
                      "case": name.replace("test_", "", 1).replace("_", " "),
                      "tried": _DOCS.get(report.nodeid) or name.replace("test_", "", 1).replace("_", " "),
                      "outcome": outcome, "seconds": round(report.duration, 2),
                      "figure": figure or ("assertions held" if report.outcome == "passed" else
                                           (str(report.longrepr).splitlines() or ["?"])[-1][:200])})


def pytest_sessionfinish(session, exitstatus) -> None:
    target = session.config.getoption("--extreme-json")
    if target:
        Path(target).write_text(json.dumps(_ROWS))


def extreme_matrix(timeout_s: float = 1200.0) -> list[dict]:
    """Run tests/extreme/ and return its rows ([] when there is no such folder).  The timeout leaves room for
    the scale case's row per library problem (three units x 4 starts each, about as long as the rest)."""
    if EXTREME is None or not EXTREME.is_dir():
        return []
    fd, out = tempfile.mkstemp(prefix="agrisynth-extreme.", suffix=".json")
    os.close(fd)
    try:
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
        subprocess.run([sys.executable, "-m", "pytest", str(EXTREME), "-q", "-p", "no:cacheprovider",
                        "-p", "synthesis.bench.extreme", f"--extreme-json={out}", "-W", "ignore",
                        # the benchmark-marked cases too (the scale case's row per library problem), but not
                        # the full scale study (every start of every problem: minutes; pytest -m benchmark)
                        "-m", "not fuzz", "--deselect", f"tests/extreme/test_scale.py::{FULL_STUDY}"],
                       cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=timeout_s)
        text = Path(out).read_text()
        return json.loads(text) if text else []
    except (subprocess.TimeoutExpired, OSError, json.JSONDecodeError) as exc:
        return [{"file": "tests/extreme", "case": "the matrix", "tried": "run tests/extreme", "outcome": "error",
                 "seconds": None, "figure": f"{type(exc).__name__}: {exc}"}]
    finally:
        os.remove(out)
