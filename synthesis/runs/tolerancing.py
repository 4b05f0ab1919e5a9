"""``tolerance``: exact sensitivities, the linear stack-up and a seeded Monte-Carlo of a design, written to
OUT/<name>-tolerance/."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from synthesis import kinds
from synthesis.errors import ResultError, SpecError
from synthesis.files import read_json
from synthesis.result import MAX_RESULT_BYTES
from synthesis.runs.events import MonteCarloPlan, Subscriber
from synthesis.runs.output import RunOutput
from synthesis.runs.requests import Outcome, ToleranceFacts, ToleranceRequest
from synthesis.runs.specs import (followers_named, named_model, spec_file, tolerance_names_known, unknown_design_variables,
                                   within_option_ranges, zero_tolerance_box)
from synthesis.spec import design_info, load_spec
from synthesis.tolerance.analysis import analyse
from synthesis.tolerance.design import spec_keys
from synthesis.tolerance.envelope import grid_of
from synthesis.tolerance.output import artifacts, verdict_rows


def no_solved_design(folder: Path) -> str:
    """Why a folder given to `tolerance` has no solved design, from its result.json where it has one (read as
    `compare` reads one: a FIFO, a device or a hostile file there is no status, never a hang or a traceback)."""
    try:
        data = read_json(folder / "result.json", MAX_RESULT_BYTES, "result.json", ResultError)
    except ResultError:
        data = None
    status = data.get("status") if isinstance(data, dict) else None
    if status == "interrupted":
        return (f"{folder}: an interrupted run, with no solved design (solved.toml) yet: finish it with "
                f"`agrisynth solve SPEC --resume {folder}`, then give this folder again")
    if status == "evaluated":
        # a check and a tolerance analysis both evaluate a design; the analysis' result carries facts.tolerance
        if isinstance(data, dict) and isinstance(data.get("facts"), dict) and "tolerance" in data["facts"]:
            return (f"{folder}: a tolerance analysis' folder, with no solved design: give the run folder or the "
                    f"spec file it analysed")
        return f"{folder}: a check's folder, with no solved design: give the spec file it checked"
    return f"{folder}: no solved.toml in this folder (give a solve's run folder or a spec file)"


def design_file(target: Path, emit: Subscriber) -> Path:
    """The spec file of RESULT|SPEC: a spec (or the library's of that name), or a run folder's solved.toml (a run
    given as its result.json: its folder's)."""
    target = spec_file(target, emit)
    if target.is_file() and target.suffix == ".json":      # a run's result.json: its folder's solved design
        target = target.parent
    if target.is_dir():
        if not (target / "solved.toml").is_file():
            raise SpecError(no_solved_design(target))
        target = target / "solved.toml"
    return target


def _spec_variables(spec, variables: dict[str, float], request: ToleranceRequest) -> dict[str, float]:
    """The spec's [tolerance] half-widths of single variables that the command line leaves standing: --length
    replaces those of the lengths and --angle those of the angles (the command line over the spec, as its help
    says; --tol NAME=VALUE over both)."""
    given = {unit for unit, width in (("mm", request.length), ("deg", request.angle)) if width is not None}
    if not given or not variables:
        return variables
    info = design_info.describe(spec)
    return {name: variables[name] for name, key in zip(variables, spec_keys(list(variables), info))
            if (info.get(key) or {}).get("unit") not in given}


def tolerance(request: ToleranceRequest, emit: Subscriber) -> Outcome:
    """Analyse and write result.json, report.md, tornado.png.  Exit code 0 when the design and every Monte-Carlo
    sample pass every rule (--samples 0: every linear worst case holds), 1 otherwise; ``details``:
    :class:`ToleranceFacts` (the analysis' facts, the rows that decided a failure)."""
    loaded = load_spec(design_file(request.target, emit))
    spec: Any = loaded.model        # the kind's own spec model: a kind that analyses tolerances has [tolerance]
    tol = spec.tolerance
    # the variables by result.json's names (a guide way's fitted control points written out): once, a convex fit
    named = named_model(loaded) if (tol and tol.variables) or request.per_variable else spec
    tolerance_names_known(loaded, named)
    kind = kinds.solving_kind(loaded.kind)
    length = request.length if request.length is not None else (tol.length if tol else None)
    angle = request.angle if request.angle is not None else (tol.angle if tol else None)
    per_variable = {**_spec_variables(named, dict(tol.variables) if tol else {}, request), **request.per_variable}
    if request.per_variable:               # an unknown name is bad input, said before any analysis
        unknown_design_variables(named, list(request.per_variable), "--tol")
        followers_named(loaded.kind, list(request.per_variable), "--tol")
        within_option_ranges(named, request.per_variable)
    if not (length or angle or any(per_variable.values())) and request.samples != 0:
        given = [f"--{what} 0" for what, width in (("length", request.length), ("angle", request.angle))
                 if width == 0]
        if given:
            raise SpecError(f"tolerance: every half-width given is 0 ({', '.join(given)}): give one above 0, or "
                            f"--samples 0 for the sensitivities alone")
        zeros = zero_tolerance_box(loaded)
        if zeros is not None:
            raise SpecError(f"{loaded.path}: [tolerance] gives no half-width above 0 ({zeros}): give one there or "
                            f"with --length, --angle or --tol NAME=VALUE, or --samples 0 for the sensitivities alone")
        raise SpecError("tolerance: give --length and/or --angle (or a [tolerance] table in the spec)")
    samples = request.samples if request.samples is not None else (tol.samples if tol else 1000)
    seed = request.seed if request.seed is not None else (tol.seed if tol else 0)
    design = kinds.checker(loaded.kind)(loaded).design
    points = len(grid_of(spec))
    if points > 1:        # an envelope: every sample is re-checked at every point of the range's grid
        emit(MonteCarloPlan(samples, points))
    try:
        facts = analyse(kind, spec, design, length=length, angle=angle, per_variable=per_variable, samples=samples,
                        seed=seed)
    except ArithmeticError as exc:
        # a design the analysis cannot linearise (its mechanism does not assemble, its auxiliaries do not converge):
        # nothing to stack up, said in one line with what shows why
        raise SpecError(f"{loaded.path}: tolerance: the design cannot be linearised: {exc}; `agrisynth check` shows "
                        f"its rules there") from None
    name = spec.name.removesuffix("_solved")
    with RunOutput(request.out, f"{name}-tolerance", force=request.force) as output:
        folder, _ = output.write_files(artifacts(kind.name, name, loaded.sha256, facts))
    # the rows result.json holds decide, so a reader of it sees why: the design's own rules and, per rule, every
    # Monte-Carlo sample holding it (--samples 0: its linearised worst case in the box)
    failed = [r for r in facts["nominal_rules"] + verdict_rows(facts) if not r["satisfied"]]
    return Outcome(1 if failed else 0, folder=folder, details=ToleranceFacts(facts, failed))
