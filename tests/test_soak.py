"""The soak (marked ``fuzz``, run with the fuzz campaign: ``pytest -m fuzz``): many solves of every kind that
solves, back to back and two at a time into one results folder, with seeded random SIGINT, SIGTERM and SIGKILL
and ``--resume``; every result must equal the uninterrupted run's (design and objective, bit for bit), no
staging folder may be left, and neither the runs' peak memory nor the test process's open files may grow from
the first tenth of the runs to the last.

Each run is its own process (``python -m synthesis.program``, what ``agrisynth`` runs) with ``--workers 1``:
the solve is that one process, so its peak resident memory is the ``ru_maxrss`` its parent reads when it
reaps it.
"""

from __future__ import annotations

import json
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from conftest import LIBRARY
from solving import strict_json

pytestmark = [pytest.mark.fuzz, pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs /proc")]

#: every kind that solves, with its quickest library spec (seconds for --starts 2 --workers 1 on one busy core,
#: figures included)
SOAK_SPECS = {
    "comb_finger": "comb_finger/redesign_max_combing.toml",                     # 4 s
    "combing_chain": "combing_chain/redesign_window_80_100.toml",               # 5 s
    "crank_rocker": "picker/cai2020_crank_rocker_synthesis.toml",               # 6 s
    "clamp_cam": "clamp_cam/opening_cam_redesign_modified_sine.toml",           # 6 s
    "guide_tube": "guide_tube/uniform_spacing_mu_envelope.toml",                # 9 s
    "picker_double_crank": "picker/picker_double_crank_redesign.toml",          # 9 s
    "fourbar_path": "fourbar_path/picking_arc.toml",                            # 10 s
    "steering_linkage": "steering/steering_redesign_40.toml",                   # 13 s
    "tillage_linkage": "tillage/tillage_redesign.toml",                         # 18 s
    "planting_fourbar": "planting_arm/redesign_from_example1.toml",             # 19 s
    "guide_way": "guide_way/smooth_redesign.toml",                              # 63 s
}
#: the kinds quick enough to be soaked in every round; the others once (the soak stays within about 5 minutes)
QUICK = ("comb_finger", "combing_chain", "crank_rocker", "clamp_cam", "guide_tube")
ROUNDS = 3
STARTS = 2
SEED = 20240611
#: what the interrupted runs get (None: left alone)
SIGNALS = [None, signal.SIGINT, signal.SIGTERM, signal.SIGKILL]
RUN_SECONDS = 240


@dataclass
class Job:
    kind: str
    spec: Path
    name: str
    signal: int | None
    events: list[str] = field(default_factory=list)
    peak_kb: int = 0                   # of the process that completed the result
    exits: list[int] = field(default_factory=list)
    resumes: int = 0
    restarts: int = 0
    signalled: bool = False
    fds_after: int = 0


def run_process(args: list[str], cwd: Path, on_start=None) -> tuple[int, int, str]:
    """(exit code, peak RSS in KB, stderr) of ``agrisynth ARGS``; ``on_start(proc)`` runs while it runs."""
    err_path = cwd / f"stderr-{threading.get_ident()}-{time.monotonic_ns()}.txt"
    with open(err_path, "wb") as err:
        proc = subprocess.Popen([sys.executable, "-m", "synthesis.program", *map(str, args)], cwd=cwd,
                                stdout=subprocess.DEVNULL, stderr=err)
        timer = threading.Timer(RUN_SECONDS, lambda: None if _exited(proc) else os.kill(proc.pid, signal.SIGKILL))
        timer.start()
        try:
            if on_start is not None:
                on_start(proc)
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            timer.cancel()
    proc.returncode = os.waitstatus_to_exitcode(status)
    text = err_path.read_text(errors="replace")
    err_path.unlink()
    return proc.returncode, usage.ru_maxrss, text


def logged_starts(out: Path, name: str) -> int:
    files = list(out.glob(f".{name}.run-*/starts.jsonl")) + list(out.glob(f"{name}/starts.jsonl"))
    counts = []
    for f in files:
        try:
            counts.append(len(f.read_text().splitlines()) - 1)
        except OSError:                 # the staging folder became the run folder as we looked
            pass
    return max(counts + [0])


def _exited(proc: subprocess.Popen) -> bool:
    """Whether the child has exited, without reaping it: run_process reaps it with wait4 for its peak memory
    (Popen.poll or send_signal would reap it first, and wait4 would find no child)."""
    return os.waitid(os.P_PID, proc.pid, os.WEXITED | os.WNOHANG | os.WNOWAIT) is not None


def signal_after_a_start(job: Job, out: Path, rng: random.Random):
    """Deliver ``job.signal`` a random moment after the run's first finished start (if it is still running)."""
    delay = rng.uniform(0.0, 1.5)

    def act(proc: subprocess.Popen) -> None:
        deadline = time.monotonic() + RUN_SECONDS
        while logged_starts(out, job.name) < 1 and time.monotonic() < deadline:
            if _exited(proc):
                return
            time.sleep(0.05)
        time.sleep(delay)
        if not _exited(proc):
            os.kill(proc.pid, job.signal)      # the pid is still this child's: it is not reaped before wait4
            job.signalled = True
            job.events.append(f"{signal.Signals(job.signal).name} {delay:.2f} s after start 1")
    return act


def soak_one(job: Job, out: Path, cwd: Path, rng: random.Random) -> Job:
    code, peak, err = run_process(["solve", job.spec, "--out", out, "--starts", STARTS, "--workers", 1], cwd,
                                  signal_after_a_start(job, out, rng) if job.signal else None)
    job.exits.append(code)
    assert "Traceback" not in err, (job.name, err[-2000:])
    for _ in range(3):                  # a resume is itself left alone
        if code in (0, 1):
            break
        assert job.signalled and code in (130, 143, -9), (job.name, code, err[-2000:])
        staged = sorted(out.glob(f".{job.name}.run-*"))
        run = out / job.name
        if (run / "result.json").is_file() and json.loads((run / "result.json").read_text())["status"] != "interrupted":
            job.events.append("complete before the signal took effect")
            break                                      # killed after the answer was in place: nothing to redo
        if (run / "result.json").is_file() and (run / "starts.jsonl").is_file():
            target = run                               # an interrupted result: status interrupted
        elif staged and (staged[-1] / "starts.jsonl").is_file():
            target = staged[-1]                        # SIGKILL: the staging folder holds the finished starts
        else:
            target = None                              # nothing to resume: no start had finished
        if target is None:
            job.restarts += 1
            job.events.append("run again")
            code, peak, err = run_process(["solve", job.spec, "--out", out, "--starts", STARTS, "--workers", 1], cwd)
        else:
            job.resumes += 1
            job.events.append(f"resume {target.name}")
            code, peak, err = run_process(["solve", job.spec, "--resume", target, "--workers", 1], cwd)
        job.exits.append(code)
        assert "Traceback" not in err, (job.name, err[-2000:])
    assert code in (0, 1) or (out / job.name / "result.json").is_file(), (job.name, job.exits, err[-2000:])
    job.peak_kb = peak
    job.fds_after = len(os.listdir("/proc/self/fd"))
    return job


def answer(folder: Path) -> tuple:
    data = json.loads((folder / "result.json").read_text())
    return data["status"], data["design"], data["objective"]


def renamed_spec(kind: str, name: str, folders: Path) -> Path:
    """The kind's soak spec named ``name``, in a copy of its library folder (specs it names come along)."""
    source = LIBRARY / SOAK_SPECS[kind]
    folder = folders / kind
    if not folder.exists():
        shutil.copytree(source.parent, folder, ignore=shutil.ignore_patterns("*.md"))
    text = source.read_text()
    old = f'name = "{source.stem}"'
    assert old in text, source
    path = folder / f"{name}.toml"
    path.write_text(text.replace(old, f'name = "{name}"', 1))
    return path


def test_soak_many_solves_signals_and_resumes_lose_nothing_and_grow_nothing(tmp_path):
    began = time.monotonic()
    rng = random.Random(SEED)
    specs, out, cwd = tmp_path / "specs", tmp_path / "results", tmp_path / "cwd"
    out.mkdir()
    cwd.mkdir()

    # round 0, uninterrupted: the reference answer of every kind (and the first tenth of the soak's runs)
    reference_jobs = [Job(kind, renamed_spec(kind, f"{kind}_ref", specs), f"{kind}_ref", None) for kind in SOAK_SPECS]
    soak_jobs: list[Job] = []
    for r in range(1, ROUNDS + 1):
        for kind in SOAK_SPECS:
            if r == 1 or kind in QUICK:
                name = f"{kind}_r{r}"
                soak_jobs.append(Job(kind, renamed_spec(kind, name, specs), name, rng.choice(SIGNALS[1:] if r == 1
                                                                                                else SIGNALS)))
    fds_before = len(os.listdir("/proc/self/fd"))

    def run_all(jobs: list[Job]) -> list[Job]:
        seeds = [rng.randrange(2**32) for _ in jobs]
        with ThreadPoolExecutor(max_workers=2) as pool:         # two runs at a time into the one folder
            return list(pool.map(lambda js: soak_one(js[0], out, cwd, random.Random(js[1])), zip(jobs, seeds)))

    run_all(reference_jobs)
    reference = {job.kind: answer(out / job.name) for job in reference_jobs}
    run_all(soak_jobs)
    # the last round again, uninterrupted: the last tenth of the runs are the same specs as the first tenth
    last_jobs = [Job(kind, renamed_spec(kind, f"{kind}_last", specs), f"{kind}_last", None) for kind in QUICK]
    run_all(last_jobs)
    took = time.monotonic() - began

    every = reference_jobs + soak_jobs + last_jobs
    identical = 0
    for job in every:
        status, design, objective = answer(out / job.name)
        ref_status, ref_design, ref_objective = reference[job.kind]
        assert (status, design, objective) == (ref_status, ref_design, ref_objective), (job.name, job.events)
        strict_json(out / job.name / "result.json")        # no NaN or infinity written
        identical += 1
    assert not list(out.glob(".*.run-*")), "a staging folder outlived its run"
    assert sorted(p.name for p in out.iterdir()) == sorted(job.name for job in every)

    # flat: the first tenth (reference runs of the quick kinds) against the last (the same specs, at the end)
    tenth = max(1, math.ceil(len(every) / 10))
    first = {j.kind: j.peak_kb for j in reference_jobs if j.kind in QUICK}
    last = {j.kind: j.peak_kb for j in last_jobs}
    assert len(last) >= tenth
    growth = {k: last[k] / first[k] for k in last}
    fds = [j.fds_after for j in every]
    signals = [j for j in soak_jobs if j.signalled]
    print(f"\nsoak: {len(every)} runs ({sum(len(j.exits) for j in every)} processes) in {took:.0f} s; "
          f"signals {len(signals)} ({', '.join(sorted(signal.Signals(j.signal).name for j in signals))}); "
          f"resumes {sum(j.resumes for j in every)}, runs again {sum(j.restarts for j in every)}; "
          f"results identical {identical}/{len(every)}; peak RSS MB first vs last, per kind: "
          + ", ".join(f"{k} {first[k] / 1024:.0f}/{last[k] / 1024:.0f}" for k in last)
          + f"; open files before {fds_before}, after each run {min(fds)}..{max(fds)}, at the end "
            f"{len(os.listdir('/proc/self/fd'))}")
    for job in every:
        if job.events:
            print(f"  {job.name}: {'; '.join(job.events)} -> exits {job.exits}")
    assert len(signals) >= len(SOAK_SPECS)         # round 1 signals every kind (unless its run ended first)
    # each kind's run is the same work at the start and at the end: a leak that fills with the folder shows here
    assert all(g < 1.15 for g in growth.values()), growth
    assert max(fds[-tenth:]) <= max(fds[:tenth]) + 2 and len(os.listdir("/proc/self/fd")) <= fds_before + 2, fds
