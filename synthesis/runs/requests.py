"""What each run is asked to do (requests) and what it answers (outcomes): plain records, no parsing.

The command line builds a request from its options; the studio's worker from the page's values.  An outcome's
``exit_code`` is the command's (docs/ARCHITECTURE.md, "Exit codes"): 0 every rule satisfied, 1 a rule violated,
3 infeasible or failed (``error`` says why), 128 + the signal for a stopped run.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from synthesis.errors import AgrisynthError


class BadRequest(AgrisynthError):
    """A request that names something the run cannot use, said against one of its fields (``field``: the
    command-line name of it, e.g. ``PROBLEM``): the caller says it as bad input of that field (exit 2)."""

    def __init__(self, message: str, field: str):
        super().__init__(message)
        self.field = field


@dataclass(frozen=True)
class CheckRequest:
    spec: Path
    out: Path = Path("results")
    force: bool = False


@dataclass(frozen=True)
class SolveRequest:
    spec: Path
    out: Path | None = None             # None: results/, or where ``resume`` is
    force: bool = False
    resume: Path | None = None
    starts: int | str | None = None     # None: the spec's [solver] starts (resumed: the interrupted run's); "auto"
    seed: int | None = None
    workers: int | None = None          # None: every core
    scheduler: str | None = None        # a dask.distributed address instead of local workers
    verbose: bool = False               # hand IPOPT's output over (SolverLog)
    max_starts: int | None = None       # starts "auto": its budget of starts (None: AutoStarts' default)
    time_limit: float | None = None     # starts "auto": its budget of seconds (None: none)
    compiled: bool = False              # IPOPT's functions compiled to C, cached in OUT/.compiled/ (core.compiled_code)


@dataclass(frozen=True)
class ToleranceRequest:
    target: Path                        # a spec, a run folder (its solved.toml) or a run's result.json
    out: Path = Path("results")
    length: float | None = None
    angle: float | None = None
    per_variable: dict[str, float] = field(default_factory=dict)
    samples: int | None = None
    seed: int | None = None
    force: bool = False


@dataclass(frozen=True)
class BenchRequest:
    problems: tuple[str, ...] = ()      # kind names or spec files; none: every kind with a bench
    spec_files: tuple[Path, ...] = ()
    out: Path = Path("results")
    repeats: int | None = None          # None: 3 (quick: 1)
    quick: bool = False
    no_extreme: bool = False
    force: bool = False
    compiled: bool = False              # the generic studies add ipopt_compiled (libraries in OUT/.compiled/)


@dataclass(frozen=True)
class CompareRequest:
    results: tuple[Path, ...]
    #: None: results/compare/<the results' folder names joined by "_vs_"> (:func:`synthesis.runs.comparing.default_out`)
    out: Path | None = None
    force: bool = False


@dataclass(frozen=True)
class CheckWritten:
    """What check's summary says beside the result: the spec file and the operating ranges it holds."""

    spec_path: Path
    ranged: list[str]
    headline: list[str]                 # Kind.headline: the figures an engineer looks at first


@dataclass(frozen=True)
class SolveWritten:
    """What solve's summary says beside the result."""

    baseline: list[dict] | None
    workers: int
    scheduler: str | None
    resumed: int                        # finished starts read from ``resumed_from``
    resumed_from: Path | None
    headline: list[str]


@dataclass(frozen=True)
class ToleranceFacts:
    """The tolerance analysis (``synthesis.tolerance.analysis.analyse``'s facts) and the rows that failed."""

    facts: dict
    failed: list[dict]


@dataclass(frozen=True)
class BenchRows:
    """Each benched problem's results, the IPOPT methods' repeats and the settings bench.json records."""

    results: list[dict]
    repeats: int
    settings: dict


@dataclass(frozen=True)
class Comparison:
    """The candidates compared (the first is the baseline) and the page written."""

    candidates: list
    page: Path


@dataclass(frozen=True)
class Stopped:
    """A run a signal stopped: ``kept`` the folder holding its finished starts (None: nothing had finished,
    nothing written)."""

    signal_name: str
    finished: int
    total: int
    kept: Path | None
    spec: Path
    #: --starts auto stopped in a batch whose starts so far did no better than the batch before, which is the one
    #: kept: (that batch's total, its finished starts, kept in starts.jsonl for --resume); None otherwise
    begun: tuple[int, int] | None = None


@dataclass(frozen=True)
class Outcome:
    """A run's answer: ``exit_code`` as above; ``result`` (check, solve), ``folder`` where it was written,
    ``error`` (exit 3: raise it), ``stopped`` (a signal ended it), ``details`` (per run: :class:`ToleranceFacts`,
    :class:`BenchRows`, :class:`Comparison`)."""

    exit_code: int
    result: Any = None
    folder: Path | None = None
    error: AgrisynthError | None = None
    stopped: Stopped | None = None
    details: Any = None
