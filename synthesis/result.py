"""The Result of a run, its JSON form (docs/ARCHITECTURE.md, "result.json") and the atomic writing of a run folder."""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
import platform
import shutil
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable

from synthesis import __version__
from synthesis.core import interrupt
from synthesis.errors import OutputError, ResultError
from synthesis.files import read_json

STATUSES = ("optimal", "feasible", "infeasible", "failed", "evaluated", "interrupted")
#: version of the result.json layout; readers refuse a newer one rather than misread it
SCHEMA_VERSION = 5
#: version 2 moved the kind's own facts under "facts" and gave every solve the same tail:
#: "starts", "elastic", "baseline_design", "fine_grid_worst_violation" (version 1 had them all at the
#: top level, mixed with the kind's facts); version 3: every ``design`` entry is a number (mm / deg) or a list of
#: numbers -- a design no longer holds ``branch`` as the assembly's name (a string), which its
#: ``facts.branch`` holds (as it did in version 2); version 4: ``facts.dynamics`` (the inverse dynamics of a spec with a
#: ``[dynamics]`` table, docs/ARCHITECTURE.md "result.json"), nothing else changed; version 5: ``solver.confidence``
#: (how sure the best is the global optimum) and, for ``--starts auto``, ``solver.auto``.  Every version from 1 is
#: read (:meth:`Result.from_json`).  Keys added without a version change (a reader ignores a key it does not know):
#: ``elastic.fixed_by`` (the spec field fixing a rule no design variable moves)
RUN_KEYS = ("starts", "elastic", "baseline_design", "fine_grid_worst_violation")


def versions() -> dict[str, str]:
    import casadi       # here, not above: reading a result must not load CasADi

    return {"agrisynth": __version__, "casadi": casadi.__version__, "python": platform.python_version()}


@dataclass
class Result:
    kind: str
    name: str
    spec_sha256: str
    status: str
    design: dict[str, float]
    rules: list[dict[str, Any]]
    objective: dict[str, Any] | None = None
    trajectory: dict[str, Any] | None = None
    solver: dict[str, Any] | None = None
    versions: dict[str, str] = field(default_factory=versions)
    starts: list[dict[str, Any]] | None = None           # solve: one row per start (core.solve.starts_table)
    elastic: dict[str, Any] | None = None                # solve: the elastic diagnosis when no start satisfied every rule
    baseline_design: dict[str, Any] | None = None        # solve: the spec's given design
    fine_grid_worst_violation: float | None = None       # solve: of the returned design
    extra: dict[str, Any] = field(default_factory=dict)   # the kind's facts (precision points, ...): "facts"
    #: design name -> {path (TOML), unit, bounds [lo, hi] or null, free}: what the spec said of each variable
    #: (synthesis.spec.design_info); reports show units, bounds, free/fixed and at-bound marks from it
    design_variables: dict[str, Any] | None = None

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"status {self.status!r} is not one of {STATUSES}")

    @property
    def all_satisfied(self) -> bool:
        return all(r["satisfied"] for r in self.rules)

    def violated(self) -> list[dict[str, Any]]:
        return [r for r in self.rules if not r["satisfied"]]

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        if data["objective"] is None:
            del data["objective"]
        if data["solver"] is None:
            del data["solver"]
        if data["trajectory"] is None:
            del data["trajectory"]
        elif isinstance(data["trajectory"], dict):
            data["trajectory"] = with_units(data["trajectory"])
        if data["design_variables"] is None:
            del data["design_variables"]
        for key in RUN_KEYS:
            if data[key] is None and self.solver is None:      # a check has no run tail
                del data[key]
        data["facts"] = data.pop("extra")
        data["schema_version"] = SCHEMA_VERSION
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "Result":
        known = {"kind", "name", "spec_sha256", "status", "design", "rules", "objective", "trajectory",
                 "solver", "versions", "design_variables"}
        args = {k: data[k] for k in (*known, *RUN_KEYS) if k in data}
        # a file that records no versions says nothing of them: not this reader's own (the default of a new result)
        args["versions"] = dict(data["versions"]) if isinstance(data.get("versions"), dict) else {}
        version = data.get("schema_version", 1)
        if version >= 2:
            args["extra"] = dict(data.get("facts") or {})
        else:       # version 1: the kind's facts and the run's tail side by side at the top level
            args["extra"] = {k: v for k, v in data.items()
                             if k not in known and k not in RUN_KEYS and k != "schema_version"}
        design = args.get("design")
        if version < 3 and isinstance(design, dict) and isinstance(design.get("branch"), str):
            # before version 3 the assembly's name could sit in the design too; facts.branch holds it now
            args["design"] = {k: v for k, v in design.items() if k != "branch"}
            args["extra"].setdefault("branch", design["branch"])
        return cls(**args)


#: the units of result.json's trajectory keys that hold numbers; a nested frame (``machine``) has the same (the
#: text keys -- ``frame``, ``point``, ``note`` -- have none)
TRAJECTORY_UNITS = {"t": "s", "crank_deg": "deg", "x": "mm", "y": "mm", "vx": "mm/s", "vy": "mm/s",
                    "ax": "mm/s^2", "ay": "mm/s^2", "crank_ab_deg": "deg", "speed_m_s": "m/s",
                    "crank_speed_rpm": "r/min"}


def with_units(trajectory: dict[str, Any]) -> dict[str, Any]:
    """The trajectory with ``units``: key -> unit of each trajectory key it holds (an additive key of schema
    version 2: the keys and their units are unchanged, the file now says them)."""
    units = {k: u for k, u in TRAJECTORY_UNITS.items() if k in trajectory}
    return {**trajectory, "units": units} if units else trajectory


REQUIRED_KEYS = ("kind", "name", "spec_sha256", "status", "design", "rules")
#: a result.json larger than this is refused rather than read
MAX_RESULT_BYTES = 512 * 1024**2


#: longest name (the result's, a rule's) or string design value a result may hold (a run name is <= 100)
MAX_NAME = 200


def load_result(path: str | Path) -> Result:
    """Read a run folder's result.json (or the file itself); ResultError (exit 2) says what is wrong."""
    path = Path(path)
    if path.is_dir():
        path = path / "result.json"
    data = read_json(path, MAX_RESULT_BYTES, "result file (give a run folder or its result.json)", ResultError,
                     "a result.json", hint=" (give a run folder or its result.json)",
                     redo="re-run the check or solve that wrote it")
    if not isinstance(data, dict):
        raise ResultError(f"{path}: expected a JSON object, got {type(data).__name__}")
    version = data.get("schema_version", 1)     # results written before the key existed are version 1
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise ResultError(f"{path}: schema_version {version!r} is not a positive integer")
    if version > SCHEMA_VERSION:
        raise ResultError(f"{path}: schema_version {version} is newer than this agrisynth reads "
                          f"({SCHEMA_VERSION}); upgrade agrisynth to read it")
    missing = [k for k in REQUIRED_KEYS if k not in data]
    if missing:
        raise ResultError(f"{path}: missing required key(s) {', '.join(missing)}; not an agrisynth result.json")
    problem = _shape_problem(data)
    if problem:
        raise ResultError(f"{path}: {problem}; not a result.json agrisynth wrote (or edited by hand)")
    try:
        return Result.from_json(data)
    except (TypeError, ValueError) as exc:
        raise ResultError(f"{path}: {exc}") from None


def _numbers_only(value) -> bool:
    """A number (not a boolean), null, or a list of such (nested lists too): a design entry of version 3 on."""
    if isinstance(value, list):
        return all(_numbers_only(v) for v in value)
    return value is None or _number(value)


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _shape_problem(data: dict) -> str | None:
    """What is wrong with the types of a parsed result.json, or None: readers rely on these."""
    for key in ("kind", "name", "spec_sha256", "status"):
        if not isinstance(data[key], str):
            return f"{key} must be a string, got {type(data[key]).__name__}"
    if data["status"] not in STATUSES:
        return f"status {data['status']!r} is not one of {', '.join(STATUSES)}"
    if len(data["name"]) > MAX_NAME:
        return f"name is {len(data['name'])} characters long (at most {MAX_NAME})"
    for key in ("design", "versions", "objective", "solver", "trajectory", "facts", "elastic", "baseline_design",
                "design_variables"):
        if key in data and data[key] is not None and not isinstance(data[key], dict):
            return f"{key} must be an object, got {type(data[key]).__name__}"
    if "versions" in data and data["versions"] is None:
        return "versions must be an object, got null"
    if "starts" in data and not isinstance(data["starts"], (list, type(None))):
        return f"starts must be a list, got {type(data['starts']).__name__}"
    objective = data.get("objective")
    if isinstance(objective, dict):
        value = objective.get("value")
        if value is not None and not _number(value):
            return "objective value must be a number or null"
        if not isinstance(objective.get("name"), str) or not isinstance(objective.get("unit"), (str, type(None))):
            return "objective needs a name (a string), and its unit must be a string"
    numeric_design = isinstance(data.get("schema_version"), int) and data["schema_version"] >= 3
    for name, value in (data.get("design") or {}).items():
        if numeric_design and not _numbers_only(value):
            # version 3 on: every entry a number (null where not finite) or a list of them (README, "Version 3")
            return f"design[{name[:60]!r}] must be a number or a list of numbers, got {_shown(value)}"
        if isinstance(value, dict) or (isinstance(value, str) and len(value) > MAX_NAME):
            return f"design[{name[:60]!r}] must be a number, a short string or a list"
    for name, info in (data.get("design_variables") or {}).items():
        if not isinstance(info, dict):
            return f"design_variables[{name[:60]!r}] must be an object"
        bounds = info.get("bounds")
        if bounds is not None and not (isinstance(bounds, list) and len(bounds) == 2 and all(map(_number, bounds))):
            # the reports read [lo, hi] (the design table's at-bound marks): a fuzzed [0] crashed compare
            return f"design_variables[{name[:60]!r}].bounds must be [lo, hi] (two numbers) or null, got {_shown(bounds)}"
        if not isinstance(info.get("free", False), bool) or not isinstance(info.get("unit", ""), (str, type(None))):
            return f"design_variables[{name[:60]!r}]: free must be true/false and unit a string"
    problem = _solver_problem(data.get("solver"))
    if problem:
        return problem
    if not isinstance(data["rules"], list):
        return f"rules must be a list, got {type(data['rules']).__name__}"
    for i, rule in enumerate(data["rules"]):
        if not isinstance(rule, dict):
            return f"rules[{i}] must be an object"
        if not isinstance(rule.get("name"), str) or not isinstance(rule.get("satisfied"), bool):
            return f"rules[{i}] needs a string name and a true/false satisfied"
        if len(rule["name"]) > MAX_NAME:
            return f"rules[{i}]: name is {len(rule['name'])} characters long (at most {MAX_NAME})"
        for key in ("value", "margin", "normalised_margin"):
            v = rule.get(key)
            if v is not None and not _number(v):
                return f"rules[{i}] ({rule['name'][:60]}): {key} must be a number or null"
        for key in ("unit", "where", "note"):
            if not isinstance(rule.get(key), (str, type(None))):
                return f"rules[{i}] ({rule['name'][:60]}): {key} must be a string"
        limit = rule.get("limit")
        if not (isinstance(limit, list) and len(limit) == 2 and all(v is None or _number(v) for v in limit)):
            return f"rules[{i}] ({rule['name'][:60]}): limit must be [lower, upper] with numbers or null"
    return None


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _whole(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


#: the solver's counts the reports read as whole numbers, and the confidence statement's counts and figures
_SOLVER_COUNTS = ("starts", "starts_run", "best_start", "iterations", "seed", "starts_needed", "starts_reaching_best")
_CONFIDENCE_COUNTS = ("starts_counted", "distinct_optima", "starts_at_best", "distinct_designs")
_CONFIDENCE_FIGURES = ("expected_optima", "expected_unseen_optima", "unseen_basin_share",
                       "probability_all_optima_found", "probability_best_is_global")


def _solver_problem(solver: Any) -> str | None:
    """What is wrong with the types of ``solver`` the reports read (counts whole numbers, figures numbers, each
    or null), or None: a hand-edited ``"starts": "8"`` crashed compare."""
    if not isinstance(solver, dict):
        return None
    for key in _SOLVER_COUNTS:
        if solver.get(key) is not None and not _whole(solver[key]):
            return f"solver.{key} must be a whole number or null, got {_shown(solver[key])}"
    if solver.get("wall_s") is not None and not _number(solver["wall_s"]):
        return f"solver.wall_s must be a number or null, got {_shown(solver['wall_s'])}"
    stated = solver.get("confidence")
    if stated is None:
        return None
    if not isinstance(stated, dict):
        return f"solver.confidence must be an object or null, got {type(stated).__name__}"
    for key in _CONFIDENCE_COUNTS:
        if stated.get(key) is not None and not _whole(stated[key]):
            return f"solver.confidence.{key} must be a whole number or null, got {_shown(stated[key])}"
    for key in _CONFIDENCE_FIGURES:
        if stated.get(key) is not None and not _number(stated[key]):
            return f"solver.confidence.{key} must be a number or null, got {_shown(stated[key])}"
    return None


#: the file that proves a folder is an agrisynth run (written first, into every run folder)
RUN_MARKER = ".agrisynth-run"
#: a run folder's name: the spec's ``name``, a file-name-safe slug
RUN_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,99}$")
#: one run folder per spec and command, so that the natural order (check, solve, compare, check solved.toml)
#: never meets an earlier run and none replaces another: solve writes OUT/<name>/, check OUT/<name>-check/
#: (tolerance OUT/<name>-tolerance/); running the same command of the same spec again still needs --force
CHECK_SUFFIX = "-check"


#: a marker larger than this is no agrisynth marker (it names the run and lists the folder's contents: a run of
#: a thousand files of 200-character names is 200 KB)
MAX_MARKER_BYTES = 1024**2


def _marker(folder: Path) -> Any:
    """The parsed marker of ``folder`` (ResultError when it is not a regular file, too large, not JSON ...)."""
    return read_json(folder / RUN_MARKER, MAX_MARKER_BYTES, "run folder marker", ResultError, "a run folder marker")


def is_run_folder(path: Path) -> bool:
    """Is ``path`` a folder agrisynth wrote (a real directory, not a link, holding a valid marker)?"""
    try:
        if path.is_symlink() or not path.is_dir() or (path / RUN_MARKER).is_symlink():
            return False
        data = _marker(path)
    except (OSError, ResultError):
        return False
    return isinstance(data, dict) and data.get("agrisynth_run") == 1


def folder_contents(folder: Path) -> list[str]:
    """Every file, folder and link under ``folder`` (relative POSIX paths, sorted; links not followed), but the
    marker: what a run folder's marker lists at its commit, so a later run replaces only what agrisynth wrote."""
    out = []
    for root, dirs, files in os.walk(folder):
        rel = Path(root).relative_to(folder)
        out += [(rel / n).as_posix() for n in dirs + files]
    return sorted(n for n in out if n != RUN_MARKER)


#: files an operating system or a file browser leaves in any folder it shows: metadata, not a user's work; a run
#: replacing its folder deletes them with it rather than refusing
OS_CLUTTER = frozenset({".DS_Store", "Thumbs.db", "desktop.ini"})
#: what a run folder written before its marker listed its contents may hold and still be replaced: the files
#: agrisynth writes at a run folder's top level, by name, and its figures (any name: bench's samples_<problem>.png)
LEGACY_FILES = frozenset({
    "result.json", "report.html", "report.md", "ipopt.log", "warnings.log", "starts.jsonl", "solved.toml",
    "compare.html", "bench.json", "bench.md", "paths.csv", "profile.csv", "centre_line.csv", "walls.csv",
    "linkage.dxf", "profile.dxf", "guide_way.dxf"})
LEGACY_FIGURES = (".png", ".svg", ".gif")


def file_sums(folder: Path, names: list[str]) -> dict[str, str]:
    """sha256 of each regular file (not a link) among ``names`` under ``folder``: what a run folder's marker records
    at its commit, so a later run can tell a file it wrote from one a user changed since (an edited solved.toml)."""
    sums = {}
    for name in names:
        path = folder / name
        if path.is_file() and not path.is_symlink():
            with open(path, "rb") as fh:
                sums[name] = hashlib.file_digest(fh, "sha256").hexdigest()
    return sums


#: how a listed file that is no longer provably agrisynth's is named in a refusal
_NOT_PROVEN = ("(changed since agrisynth wrote it)", "(cannot be read, so not proven agrisynth's)")


def _changed(final: Path, sums) -> list[str]:
    """The files of ``final`` its marker records a sum of (``sums``) that are now something else: another content, a
    link, a folder (one deleted since is no one's work to keep).  A marker without sums (an earlier version's):
    none."""
    if not isinstance(sums, dict):
        return []
    changed = []
    for name, digest in sums.items():
        path = final / str(name)
        if not os.path.lexists(path):
            continue
        try:
            same = file_sums(final, [str(name)]).get(str(name)) == digest
        except OSError:
            changed.append(f"{name} {_NOT_PROVEN[1]}")
            continue
        if not same:
            changed.append(f"{name} {_NOT_PROVEN[0]}")
    return changed


def _read_marker(final: Path) -> dict:
    """The parsed marker of ``final``, or {} where it cannot be read as an object."""
    try:
        data = _marker(final)
    except (OSError, ResultError):
        return {}
    return data if isinstance(data, dict) else {}


def _foreign(final: Path) -> list[str]:
    """The entries of the run folder ``final`` agrisynth cannot prove it wrote: those its marker does not list, and
    the files it lists whose content changed since (:func:`_changed`); for a marker that lists none (an earlier
    version's), anything but a top-level regular file named as agrisynth names its outputs (LEGACY_FILES,
    LEGACY_FIGURES).  OS metadata files (OS_CLUTTER) are never counted."""
    marker = _read_marker(final)
    listed = marker.get("contents")
    have = [n for n in folder_contents(final) if Path(n).name not in OS_CLUTTER]
    if isinstance(listed, list):        # (none: a folder of an earlier version)
        known = set(listed)
        return [n for n in have if n not in known] + _changed(final, marker.get("sha256"))

    def ours(name: str) -> bool:
        path = final / name
        return ("/" not in name and path.is_file() and not path.is_symlink()
                and (name in LEGACY_FILES or name.endswith(LEGACY_FIGURES)))
    return [n for n in have if not ours(n)]


def _refusal(final: Path, spec: Path | None) -> str:
    """Why ``final`` (which exists and is not an agrisynth run) is not replaced."""
    what = "a file" if final.is_file() else ("a link" if final.is_symlink() else
                                              "a folder agrisynth did not write" if final.is_dir() else "something")
    try:
        if spec is not None and final.resolve() == Path(spec).resolve():
            what = "the spec file itself"
    except OSError:
        pass
    return (f"{final} is {what} (no {RUN_MARKER} marker): agrisynth never replaces or deletes it; "
            f"use another --out folder or rename it")


@dataclass
class RunFolder:
    """A run folder being written: ``staging`` (``OUT/.<name>.run-XXXX/``, with the marker from the start)
    while the run lasts, moved to ``final`` (``OUT/<name>/``) by :meth:`commit`.

    ``final`` is replaced only when it is an agrisynth run folder (marker) and either ``force`` was
    given or it is ``replaceable`` (the folder a ``--resume`` continues); anything else there is an
    :class:`OutputError` (exit 2), checked when the folder is opened (before any solving) and again,
    under a lock on ``OUT``, when it is moved into place.
    """

    final: Path
    staging: Path
    force: bool = False
    replaceable: Path | None = None
    spec: Path | None = None
    created: list[Path] = field(default_factory=list)     # folders of OUT this run made (deepest first)
    #: the folder a ``--resume`` read its starts from; when that is a killed run's staging folder, it is removed
    #: once this run's complete result is in place (:meth:`commit` with ``retire``)
    resumed_from: Path | None = None
    #: a descriptor of ``staging`` holding a flock on it while this process writes there: another run into the same
    #: folder sees a live writer (:func:`_live_writer`), and the kernel drops the lock with a killed process
    held: int | None = None

    def permitted(self) -> bool:
        """May ``final`` be written now?  Raises OutputError when something there must be kept."""
        if not os.path.lexists(self.final):
            return False
        if not is_run_folder(self.final):
            # both checks run under the commits' lock, but where the platform has no flock they do not: another
            # run's commit may have moved the old run away (and perhaps its own in) between the looks -- look again
            # before refusing
            if not os.path.lexists(self.final):
                return False                # nothing there now; the locked commit looks again
            if not is_run_folder(self.final):
                raise OutputError(_refusal(self.final, self.spec))
        if self.force or (self.replaceable is not None and _same(self.final, self.replaceable)):
            foreign = _foreign(self.final)
            if foreign:
                # a file not listed by its top-level entry; a listed one changed since, by its own name and why
                tops = list(dict.fromkeys(n if n.endswith(_NOT_PROVEN) else
                                          n.split("/")[0] + ("/" if (self.final / n.split("/")[0]).is_dir() else "")
                                          for n in foreign))
                shown = ", ".join(tops[:3]) + (f" and {len(tops) - 3} more" if len(tops) > 3 else "")
                raise OutputError(f"{self.final} holds what agrisynth cannot prove it wrote there ({shown}): "
                                  f"agrisynth never deletes it; move it out of that folder and run again")
            return True
        raise OutputError(f"{self.final} holds an earlier agrisynth run; give --force to replace it, "
                          f"or --out another folder")

    def write(self, artifacts: dict[str, Callable[[Path], None]]) -> None:
        for filename, writer in artifacts.items():
            writer(self.staging / filename)

    def fill(self, write: Callable[[Path], None], *, retire: bool = False) -> bool:
        """The one writer of run folders (check, solve, tolerance, bench, compare): ``write(staging)`` puts the run's
        files into the staging folder, then :meth:`commit` moves it into place; returns whether an earlier run was
        replaced.  Any failure but an OutputError discards the staging folder (an OutputError keeps it: its message
        names where the run is kept)."""
        try:
            write(self.staging)
            return self.commit(retire=retire)
        except OutputError:
            raise
        except BaseException:
            self.discard()
            raise

    def commit(self, retire: bool = False) -> bool:
        """Move the staging folder to ``final``; returns whether an earlier run was replaced.  ``retire`` (a
        complete result): remove the killed run's staging folder a ``--resume`` read its starts from
        (:func:`_retire_staging`), now that this folder holds them and the answer.

        Under an exclusive lock on the output folder and with SIGINT/SIGTERM deferred, so two runs racing
        into one folder take turns (the folder is always one run's, whole) and no half-moved folder or
        ``.old`` leftover remains."""
        with _locked(self.final.parent), interrupt.deferred():
            try:
                replace = self.permitted()
            except OutputError as exc:
                self.release()          # kept, not written any more: a --resume may read it
                raise OutputError(f"{exc} (this run is kept in {self.staging})") from None
            # the marker lists what this run wrote: a later run may replace the folder only while it holds no more
            marker = self.staging / RUN_MARKER
            data = _marker(self.staging)
            contents = folder_contents(self.staging)
            atomic_write_text(marker, json.dumps({**data, "contents": contents,
                                                  "sha256": file_sums(self.staging, contents)}) + "\n")
            if not replace:
                os.rename(self.staging, self.final)
            else:
                old = Path(tempfile.mkdtemp(prefix=f".{self.final.name}.old-", dir=self.final.parent))
                os.rename(self.final, old / "run")
                os.rename(self.staging, self.final)
                shutil.rmtree(old, ignore_errors=True)
            if retire and self.resumed_from is not None:
                _retire_staging(Path(self.resumed_from), self.final)
            self.release()
            return replace

    def release(self) -> None:
        """Let go of the staging folder's lock (the run there is finished or gone)."""
        if self.held is not None:
            if self.held in _HELD:          # not already closed by a fork's child
                _HELD.discard(self.held)
                with contextlib.suppress(OSError):
                    os.close(self.held)
            self.held = None

    def discard(self) -> None:
        """Remove the staging folder (only ever one this process made), and the output folders this run
        created when they are empty again."""
        self.release()
        if self.staging != Path():
            shutil.rmtree(self.staging, ignore_errors=True)
        for folder in self.created:
            with contextlib.suppress(OSError):
                folder.rmdir()


#: the staging folder of a run (``OUT/.<name>.run-XXXX``, tempfile.mkdtemp's suffix), left behind by a SIGKILL
STAGING_NAME = re.compile(r"^\.[A-Za-z0-9][A-Za-z0-9_.-]{0,99}\.run-[A-Za-z0-9_]+$")


def _retire_staging(staging: Path, final: Path) -> bool:
    """Remove ``staging``, a killed run's staging folder whose starts a resumed run read and whose answer is now in
    ``final`` (beside it), when everything says it is that and nothing else: a folder (not a link) named as staging
    folders are, in the same output folder, holding agrisynth's marker and only files agrisynth writes (its outputs
    and their temporary files, no folder, no link), of a process that is not running any more (the marker's pid: a
    run still writing there is left alone).  Returns whether it was removed; anything else is kept, untouched."""
    try:
        if (not STAGING_NAME.match(staging.name) or staging.is_symlink() or not staging.is_dir()
                or not _same(staging.parent, final.parent) or _same(staging, final) or not is_run_folder(staging)):
            return False
        pid = _marker(staging).get("pid")
        if isinstance(pid, int) and pid != os.getpid() and _running(pid):
            return False
        for entry in os.scandir(staging):
            if not entry.is_file(follow_symlinks=False) or not _agrisynths_file(entry.name):
                return False
    except (OSError, ResultError, AttributeError):
        return False
    shutil.rmtree(staging, ignore_errors=True)
    return not os.path.lexists(staging)


def _agrisynths_file(name: str) -> bool:
    """A file name agrisynth writes into a run folder: the marker, an output, or an output's temporary file
    (``.<name>.XXXXXXXX<suffix>``, left when a write was cut off)."""
    if name == RUN_MARKER or name in LEGACY_FILES or name.endswith(LEGACY_FIGURES):
        return True
    return name.startswith(".") and any(name.startswith(f".{known}.") for known in (*LEGACY_FILES, RUN_MARKER))


#: how a folder is opened to be locked (flock takes a descriptor; a folder opens read-only)
_FOLDER_FLAGS = os.O_RDONLY | getattr(os, "O_DIRECTORY", 0)
#: the descriptors holding a staging folder's lock in this process (:func:`_hold`)
_HELD: set[int] = set()


def _not_in_children() -> None:
    """A process forked from a run (a pool worker, a figure's drawing) closes its copies of the lock's descriptors:
    the lock is the run's, and goes with it even where such a process outlives it."""
    for fd in list(_HELD):
        with contextlib.suppress(OSError):
            os.close(fd)
    _HELD.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_not_in_children)


def _hold(folder: Path) -> int | None:
    """A descriptor of ``folder`` with an exclusive flock on it (None where flock or the descriptor is not had)."""
    try:
        import fcntl
        fd = os.open(folder, _FOLDER_FLAGS)
    except (ImportError, OSError):
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return None
    _HELD.add(fd)
    return fd


def _live_writer(out_root: Path, name: str) -> Path | None:
    """The staging folder of a run writing ``out_root/name`` now: one named as this name's staging folders are
    whose flock (:attr:`RunFolder.held`) is taken.  A killed run's staging folder holds no lock (a ``--resume``
    reads it)."""
    try:
        import fcntl
        entries = list(os.scandir(out_root))
    except (ImportError, OSError):
        return None
    # this name's staging folders only: ".a.run-x.run-XXXX" is a run named "a.run-x"'s, not "a"'s
    own = re.compile(rf"^\.{re.escape(name)}\.run-[A-Za-z0-9_]+$")
    for entry in entries:
        if not (own.match(entry.name) and entry.is_dir(follow_symlinks=False)):
            continue
        try:
            fd = os.open(entry.path, _FOLDER_FLAGS)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return Path(entry.path)
        except OSError:
            pass
        finally:
            os.close(fd)
    return None


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:             # it exists (another user's): running
        return True
    return True


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


@contextlib.contextmanager
def _locked(folder: Path):
    """An exclusive flock on ``folder`` (a directory file descriptor); no lock where flock is unsupported."""
    try:
        import fcntl
        fd = os.open(folder, _FOLDER_FLAGS)
    except (ImportError, OSError):
        yield
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:
            pass
        yield
    finally:
        os.close(fd)


def open_run_folder(out_root: Path, name: str, *, force: bool = False, spec: Path | None = None,
                    replaceable: Path | None = None, suffix: str = "", resumed_from: Path | None = None) -> RunFolder:
    """Check that ``out_root/<name><suffix>`` may be written and make the run's staging folder (with its marker).
    ``suffix``: the command's part of the folder name (:data:`CHECK_SUFFIX`), after the spec's ``name``.
    ``resumed_from``: the RUN_DIR of a ``--resume`` (:attr:`RunFolder.resumed_from`).

    OutputError (exit 2), before any work is done, when ``name`` is not a slug, ``out_root`` cannot be
    created or written, or ``out_root/<name><suffix>`` holds something that must be kept."""
    if not isinstance(name, str) or not RUN_NAME.match(name):
        raise OutputError(f"name {str(name)[:60]!r} is not a folder name (letters, digits and _ . - only, "
                          f"at most 100 characters, starting with a letter or digit)")
    name += suffix
    out_root = Path(out_root)
    created = []
    missing = out_root
    while not os.path.lexists(missing) and missing != missing.parent:
        created.append(missing)
        missing = missing.parent
    folder = RunFolder(out_root / name, Path(), force, replaceable, spec, created, resumed_from)
    try:
        out_root.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        folder.discard()
        raise OutputError(f"--out {out_root}: not a folder") from None
    except OSError as exc:
        folder.discard()        # the parents made before the one that could not be (a name too long)
        raise OutputError(f"--out {out_root}: cannot create the output folder ({exc.strerror})") from None
    if not out_root.is_dir():
        raise OutputError(f"--out {out_root}: not a folder")
    try:
        # under the commits' lock: a run committing meanwhile swaps the folder and its marker between two reads, and
        # a file's sum would then be checked against another run's marker; a run opening the same folder meanwhile
        # finds this one's staging folder locked
        with _locked(out_root):
            folder.permitted()
            # --force and --resume too: the run writing there would do all its work and then find its folder taken
            live = _live_writer(out_root, name)
            if live is not None:
                raise OutputError(f"another agrisynth run is writing {folder.final} now (its files are in {live}); "
                                  f"wait for it to finish (then --force replaces it), or --out another folder")
            try:
                folder.staging = Path(tempfile.mkdtemp(prefix=f".{name}.run-", dir=out_root))
            except OSError as exc:
                raise OutputError(f"--out {out_root}: cannot write there ({exc.strerror})") from None
            folder.held = _hold(folder.staging)
    except OutputError:
        folder.discard()
        raise
    try:
        os.chmod(folder.staging, 0o777 & ~_UMASK)    # mkdtemp makes it private; a run folder is an ordinary one
        atomic_write_text(folder.staging / RUN_MARKER, json.dumps(
            {"agrisynth_run": 1, "name": name, "pid": os.getpid(), "written_by": "agrisynth"}) + "\n")
    except OSError as exc:
        folder.discard()
        raise OutputError(f"--out {out_root}: cannot write there ({exc.strerror})") from None
    return folder


def finite_only(data: Any, path: str = "", found: list[str] | None = None) -> Any:
    """``data`` with every non-finite float replaced by None; ``found`` collects where (JSON paths)."""
    if isinstance(data, float):
        if math.isfinite(data):
            return data
        if found is not None:
            found.append(path or "$")
        return None
    if isinstance(data, dict):
        return {k: finite_only(v, f"{path}.{k}" if path else str(k), found) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [finite_only(v, f"{path}[{i}]", found) for i, v in enumerate(data)]
    return data


def finite_json_text(data: dict) -> str:
    """A result file's JSON text: never NaN or infinity (JSON has neither); a figure that is not a number is
    written as null and listed under ``not_finite`` (its JSON path)."""
    found: list[str] = []
    data = finite_only(data, "", found)
    if found:
        data["not_finite"] = found
    return json.dumps(data, indent=1, allow_nan=False) + "\n"


def result_text(result: Result) -> str:
    """result.json's text (:func:`finite_json_text` of the result)."""
    return finite_json_text(result.to_json())


def write_run(out_root: Path, result: Result, artifacts: dict[str, Callable[[Path], None]], *,
              force: bool = False, folder: RunFolder | None = None) -> tuple[Path, bool]:
    """Write ``out_root/<name>/``: result.json plus each artifact writer's file, into the run's staging
    folder (``folder``, or one opened here), then moved into place (:meth:`RunFolder.commit`).

    Returns (folder, replaced_previous_run)."""
    def result_json(path: Path) -> None:
        atomic_write_text(path, result_text(result))

    if folder is None:
        return write_folder(Path(out_root) / result.name, {"result.json": result_json, **artifacts}, force=force)
    opened = folder
    replaced = opened.fill(lambda staging: opened.write({"result.json": result_json, **artifacts}),
                           retire=result.status != "interrupted")
    return opened.final, replaced


def write_folder(final: Path, artifacts: dict[str, Callable[[Path], None]], *, force: bool = False,
                 spec: Path | None = None) -> tuple[Path, bool]:
    """Write the run folder ``final`` (one file per artifact writer, called in order) through a staging
    folder; replaces an earlier agrisynth run there only with ``force``.  Returns (final, replaced)."""
    folder = open_run_folder(final.parent, final.name, force=force, spec=spec)
    return final, folder.fill(lambda staging: folder.write(artifacts))


def atomic_write_text(path: Path, text: str) -> None:
    """Write a file via a temporary file and rename."""
    atomic_write_drawn(path, lambda tmp: tmp.write_text(text))


def create_new_text(path: Path, text: str) -> None:
    """Write ``text`` as the new file ``path``, whole or not at all, never over a file already there: written to a
    temporary file, then hard-linked to its name (FileExistsError when another process -- a second studio writing
    into the same folder -- took the name first).  Where the file system has no hard links, the name is claimed by
    an exclusive create instead."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        Path(tmp).write_text(text)
        os.chmod(tmp, 0o666 & ~_UMASK)
        try:
            os.link(tmp, path)
        except FileExistsError:
            raise
        except (AttributeError, NotImplementedError, OSError):      # no hard links here (EPERM, EOPNOTSUPP, ...)
            # claim the name by an exclusive create (FileExistsError as above), then put the whole text in its place;
            # a failed put removes the empty claim (still ours: the same file), so nothing half-made keeps the name
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
            claim = os.fstat(fd)
            os.close(fd)
            try:
                os.replace(tmp, path)
            except BaseException:
                with contextlib.suppress(OSError):
                    now = os.stat(path)
                    if (now.st_dev, now.st_ino) == (claim.st_dev, claim.st_ino):
                        os.unlink(path)
                raise
    finally:
        Path(tmp).unlink(missing_ok=True)


def atomic_write_drawn(path: Path, draw: Callable[[Path], None]) -> None:
    """A file ``draw(path)`` makes (a text, a plot) written via a temporary file and rename, with the usual mode."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        draw(Path(tmp))
        os.chmod(tmp, 0o666 & ~_UMASK)       # mkstemp makes it private; give it the usual mode
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _read_umask() -> int:
    mask = os.umask(0)      # the only portable way to read it; done once, at import, before any threads
    os.umask(mask)
    return mask


_UMASK = _read_umask()
