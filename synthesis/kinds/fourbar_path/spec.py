"""Spec model of kind ``fourbar_path``: a four-bar whose coupler point passes through target points.

::

    [targets]  points = [[x, y], ...]  (mm, 3 to 1000)   crank_deg = [...]  (optional: timing)
    [linkage]  r1 r2 r3 r4 rcx rcy x0 y0 theta0: a number fixes a variable, {init, bounds} frees it
               (as in every kind); branch = 1 | -1
    [design]   crank_deg = [...]  (free timing: the given design's crank angle at each target)
    [rules]    grashof = "crank_rocker" | "double_crank" | "any";  transmission_angle = [lo, hi];
               order = true | false;  direction = "either" | "counter_clockwise" | "clockwise"
    [solver]   starts = 64, seed = 0, stop_at_objective, max_iter, mu_strategy, samples, dynamics_samples
    [dynamics] optional: mass properties and limits of the inverse dynamics at crank_speed (dynamics.py)

The kind's first spec form wrote the variables in a ``[bounds]`` table (``[lo, hi]`` frees, a number fixes, the given
design in ``[design]``), the branch as "open"/"crossed", the Grashof classes with hyphens and the
crank direction as "ccw"/"cw"; those forms are refused with a line each that spells the user's own
values the new way (:func:`old_form_message`).  Internally, and in result.json, the branch keeps its assembly name
("open" / "crossed"), the class its hyphenated name and the direction its short one (``spec.branch``,
``spec.rules.grashof``, ``spec.rules.direction``).

Angles: theta0 and crank_deg in degrees; crank_deg is the crank angle measured from the frame line
O -> O', counter-clockwise (see synthesis.kinds.fourbar_path.kinematics).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, ValidationInfo, field_validator, model_validator

from synthesis.kinds.fourbar_path.kinematics import VARIABLES
from synthesis.spec.dynamics import DynamicsSection
from synthesis.spec.common import (Starts,
    POSITIVE, Sign, FreeVariable, MultistartSettings, ProblemSpec, StrictModel, Variable, bounds_of, documented_range,
    is_free, max_iter_field, require_positive_fields, starts_field, value_of, within_a_turn,
)

KIND = "fourbar_path"
#: the most targets a spec may give: a digitised curve or a high-speed video's trace has hundreds of points; every
#: part of a solve grows no faster than linearly with their number (problems/fourbar_path/INEXACT.md, "Many targets")
MAX_POINTS = 1000
#: largest |coordinate|, |bound|, |design value| (mm or deg): beyond it the squared errors and closure
#: polynomials overflow a float (1e300^2), and no machine of the field is a kilometre long
MAX_MAGNITUDE = 1e6


def _number(v: Any, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{what}: expected a number, got {v!r}")
    if not math.isfinite(v):
        raise ValueError(f"{what}: expected a finite number, got {v}")
    if abs(v) > MAX_MAGNITUDE:
        raise ValueError(f"{what}: expected a magnitude of at most {MAX_MAGNITUDE:g} (mm or deg), got {v:g}")
    return float(v)


def _point(v: Any) -> tuple[float, float]:
    if not isinstance(v, (list, tuple)) or len(v) != 2:
        raise ValueError(f"expected a point [x, y] in mm, got {v!r}")
    return _number(v[0], "x"), _number(v[1], "y")


def _angle(v: Any) -> float:
    return _number(v, "angle")


Point = Annotated[tuple[float, float], BeforeValidator(_point)]
Angle = Annotated[float, BeforeValidator(_angle)]
Finite = Annotated[float, BeforeValidator(lambda v: _number(v, "value"))]


class TargetsSection(StrictModel):
    """The points the coupler point must pass through, and optionally when (the crank angles)."""

    points: list[Point] = Field(description="target points [[x, y], ...], mm; 3 to 1000, at least 3 distinct")
    crank_deg: list[Angle] | None = Field(
        None, description="prescribed crank angle of each point (deg, from the frame line O -> O', "
                          "counter-clockwise); omit to leave the timing free")

    @field_validator("points", mode="after")
    @classmethod
    def _count(cls, points: list) -> list:
        if not 3 <= len(points) <= MAX_POINTS:
            raise ValueError(f"expected 3 to {MAX_POINTS} points, got {len(points)}")
        return points

    @field_validator("crank_deg", mode="after")
    @classmethod
    def _one_per_point(cls, angles: list | None, info: ValidationInfo) -> list | None:
        points = info.data.get("points")
        if angles is not None and points is not None and len(angles) != len(points):
            raise ValueError(f"expected one angle per point ({len(points)}), got {len(angles)}")
        return angles

    @model_validator(mode="after")
    def _three_distinct_points(self) -> "TargetsSection":
        """At least 3 distinct targets (at distinct crank angles, when the timing is prescribed): fewer leave the
        synthesis nothing to fit.  Targets closer than :data:`SAME_TARGET` of the set's size are one
        (:func:`same_targets`).  A point may repeat: published sets repeat a closed loop's first point as its
        last (literature.py's ellipse10), which weighs it twice, as their objectives do."""
        distinct = len(self.points) - len(_merged(self.points, self.crank_deg))
        if distinct < 3:
            raise ValueError(f"points: expected at least 3 distinct target points, got {distinct} among the "
                             f"{len(self.points)} given (points closer than {SAME_TARGET:g} of the set's size, "
                             f"{same_target_mm(self.points):.3g} mm here, are one target)")
        return self

    def same_targets_note(self) -> str | None:
        """What a run says of targets that are one (:func:`same_targets`), or None when every target is its own."""
        return same_targets_note(self.points, self.crank_deg)


#: targets closer together than this share of the target set's size (the diagonal of the box around the points)
#: are one target.  1e-6 of a 100 mm set is 0.1 um = 1e-4 mm: a thousand times finer than a workshop tolerance (the
#: library's tolerance boxes are 0.1-0.2 mm) and no coarser than the accuracy to which an answer passes through its
#: targets (arc5_timed's best sum of squares, 7.4e-7 mm^2 over 5 points, is 3.8e-4 mm RMS), so no answer can pass
#: through one and not the other -- yet billions of times coarser than float rounding (about 2e-14 mm at 100 mm),
#: so a point typed twice with other digits, or converted twice, is caught.  Two such targets
#: fitted as two gave a degenerate set (3 targets, 2 of them 1e-9 mm apart) "optimal" with no word.
SAME_TARGET = 1e-6
#: prescribed crank angles closer than this (deg, around the turn) are one (the sequence rule's shared angle)
SAME_ANGLE_DEG = 1e-6


def same_target_mm(points) -> float:
    """The distance (mm) under which two of ``points`` are one target: :data:`SAME_TARGET` of the diagonal of the
    box around them."""
    xs, ys = [float(p[0]) for p in points], [float(p[1]) for p in points]
    return SAME_TARGET * math.hypot(max(xs) - min(xs), max(ys) - min(ys)) if len(xs) else 0.0


def same_targets(points, crank_deg=None) -> list[tuple[int, int, float]]:
    """(i, j, distance in mm), i < j in that order, of every two targets that are one: at most
    :func:`same_target_mm` apart and, when the timing is prescribed, at one crank angle (within
    :data:`SAME_ANGLE_DEG`).  Only the pairs in neighbouring cells of a grid twice that distance wide are measured
    (:func:`_near_pairs`), so a set of 1,000 points costs milliseconds, not the half a million pairs of them all."""
    limit = same_target_mm(points)
    out = []
    for i, j in _near_pairs(points, limit):
        d = math.hypot(float(points[i][0]) - float(points[j][0]), float(points[i][1]) - float(points[j][1]))
        if d > limit:
            continue
        if crank_deg is not None:
            turn = abs(float(crank_deg[i]) - float(crank_deg[j])) % 360.0
            if min(turn, 360.0 - turn) > SAME_ANGLE_DEG:
                continue
        out.append((i, j, d))
    return out


def _near_pairs(points, limit: float) -> list[tuple[int, int]]:
    """(i, j), i < j, sorted, a superset of the pairs of ``points`` at most ``limit`` apart: those whose cells of a
    grid 2 x ``limit`` wide (from the points' lowest corner, so the cell numbers stay below 1e6) touch.  Two points
    that close differ by less than one cell in x and in y whatever the rounding of their cell numbers; a
    ``limit`` of 0 (every point at one place) groups equal points."""
    xy = [(float(p[0]), float(p[1])) for p in points]
    if not xy:
        return []
    x_min, y_min = min(x for x, _ in xy), min(y for _, y in xy)
    cell = 2.0 * limit
    cells: dict[tuple, list[int]] = {}
    for k, (x, y) in enumerate(xy):
        key = (math.floor((x - x_min) / cell), math.floor((y - y_min) / cell)) if cell > 0 else (x, y)
        cells.setdefault(key, []).append(k)
    steps = [(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1)] if cell > 0 else [(0, 0)]
    pairs = []
    for (cx, cy), members in cells.items():
        for a, b in steps:
            others = cells.get((cx + a, cy + b), ()) if cell > 0 else members
            pairs += [(i, j) for i in members for j in others if i < j]
    return sorted(pairs)


def _merged(points, crank_deg=None) -> set[int]:
    """The targets that are one with an earlier one (the later of each group, through chains of pairs)."""
    first = list(range(len(points)))

    def root(k: int) -> int:
        while first[k] != k:
            k = first[k]
        return k

    for i, j, _ in same_targets(points, crank_deg):
        a, b = root(i), root(j)
        if a != b:
            first[max(a, b)] = min(a, b)
    return {k for k in range(len(points)) if root(k) != k}


def same_targets_note(points, crank_deg=None, shown: int = 3) -> str | None:
    """The note a run gives a target set with targets that are one (:func:`same_targets`, the first ``shown``
    pairs named), or None when every target is its own."""
    pairs = same_targets(points, crank_deg)
    if not pairs:
        return None
    said = ", ".join(f"{i} and {j} ({d:.3g} mm apart)" for i, j, d in pairs[:shown])
    more = f" and {len(pairs) - shown} more pair(s)" if len(pairs) > shown else ""
    return (f"targets {said}{more} (numbered from 0) are closer than {SAME_TARGET:g} of the target set's size "
            f"({same_target_mm(points):.3g} mm), so each pair is one target: one point of the path, weighed in the "
            f"objective as often as it is given")


class LinkageSection(StrictModel):
    """The four-bar and its coupler point: a number fixes a variable, ``{init, bounds}`` frees it (mm, deg).
    ``init`` is the given design: what ``check`` evaluates and the first start of ``solve``."""

    r1: Variable = Field(json_schema_extra=POSITIVE, description="frame O -> O', mm")
    r2: Variable = Field(json_schema_extra=POSITIVE, description="input crank O -> A, mm")
    r3: Variable = Field(json_schema_extra=POSITIVE, description="coupler A -> B, mm")
    r4: Variable = Field(json_schema_extra=POSITIVE, description="output link O' -> B, mm")
    rcx: Variable = Field(description="coupler point along A -> B, mm")
    rcy: Variable = Field(description="coupler point normal to A -> B (90 deg counter-clockwise), mm")
    x0: Variable = Field(description="input pivot O, x, mm")
    y0: Variable = Field(description="input pivot O, y, mm")
    theta0: Variable = Field(FreeVariable(init=180.0, bounds=(0.0, 360.0)),
                             json_schema_extra=documented_range(">= -360, <= 360"), description="frame angle, direction of O -> O' from +x, deg (-360 to 360)")
    _angles_within_a_turn = field_validator("theta0")(within_a_turn)
    branch: Sign = Field(1, description="assembly: B left (+1, the open assembly) or right (-1, the "
                                                  "crossed one) of the line A -> O'")

    @model_validator(mode="after")
    def _sizes(self) -> "LinkageSection":
        for name in VARIABLES:
            v = getattr(self, name)
            for what, x in ((f"{name}", value_of(v)),) if not is_free(v) else \
                    ((f"{name}.init", v.init), (f"{name}.bounds", v.bounds[0]), (f"{name}.bounds", v.bounds[1])):
                if abs(x) > MAX_MAGNITUDE:
                    raise ValueError(f"{what}: expected a magnitude of at most {MAX_MAGNITUDE:g} (mm or deg), "
                                     f"got {x:g}")
        require_positive_fields(self)
        return self


class DesignSection(StrictModel):
    """Free timing: the crank angle of each target in the given design (``check`` and start 0)."""

    crank_deg: list[Angle] | None = Field(None, description="crank angle of each target, deg (free timing only; "
                                                            "default: the nearest point of the coupler curve)")


class RulesSection(StrictModel):
    """The design rules besides passing through the targets: Grashof class, transmission angle, order."""

    grashof_class: Literal["crank_rocker", "double_crank", "any"] = Field(
        "crank_rocker", alias="grashof",
        description="crank_rocker: r2 shortest and s + l <= p + q (the crank turns fully); "
                    "double_crank: r1 shortest and s + l <= p + q; any: no Grashof rule, "
                    "the loop must close at every target and between them")
    transmission_angle: tuple[Finite, Finite] | None = Field(
        None, description="[lo, hi] deg: the transmission angle over the crank's motion")
    order: bool = Field(True, description="free timing: the crank meets the targets in the given order "
                                          "within one turn (the `sequence` rule)")
    crank_turns: Literal["either", "counter_clockwise", "clockwise"] = Field(
        "either", alias="direction",
        description="free timing: the crank turns counter_clockwise, clockwise, or either way (chosen per start) "
                    "through the targets (spelled as clamp_cam's rotation)")

    @property
    def direction(self) -> str:
        """The turning sense as the start generator and result.json's ``crank_direction`` name it ("ccw", "cw",
        "either")."""
        return TURNING[self.crank_turns]

    @property
    def grashof(self) -> str:
        """The class as :mod:`synthesis.kinds.fourbar_path.rules.grashof_class`, the start generator and result.json's ``grashof``
        name it ("crank-rocker", "double-crank", "any"): the spec's spelling changed, those did not."""
        return self.grashof_class.replace("_", "-")

    @field_validator("transmission_angle", mode="after")
    @classmethod
    def _angle_range(cls, v):
        if v is not None:
            lo, hi = v
            if not 0.0 <= lo <= hi <= 180.0:
                raise ValueError(f"expected 0 <= lo <= hi <= 180 deg, got [{lo:g}, {hi:g}]")
        return v


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(64)
    stop_at_objective: float | None = Field(
        None, ge=0, description="end the multistart at the first start (in start order) whose objective "
                                "is at most this many mm^2 and that satisfies every rule; reported as "
                                "starts needed")
    max_iter: int = max_iter_field(1000, " (free timing, >= 12 targets: a start stopped there within the best screened "
                                           "start's path error is resumed once, for up to 150 more; 250 on an open "
                                           "target arc with grashof = \"any\")")
    mu_strategy: Literal["monotone", "adaptive"] = Field(
        "monotone", description="IPOPT's barrier update: monotone (default: more starts reach the optimum "
                                "when the targets go round the whole coupler curve) or adaptive (with "
                                "max_iter = 3000, recovers targets on a 120 deg arc that monotone misses)")
    samples: int = Field(36, ge=4, le=3600, description="samples of the crank motion per gap for the check of "
                                                         "the sampled rules (grashof = \"any\"; the solve holds "
                                                         "them exactly); the re-check is 10x finer")
    dynamics_samples: int = Field(72, ge=36, le=3600, multiple_of=2,
                                  description="crank angles over a turn at which the NLP holds the [dynamics.limits] "
                                              "(even: includes the crank along and against the frame; at least 36, "
                                              "as the NLP holds each peak 2 % x (72 / N)^2 of its limit inside it to "
                                              "cover the miss between samples, 8 % at 36); check and the re-check "
                                              "evaluate them on 10x as many")


class FourbarPathSpec(ProblemSpec):
    kind: Literal["fourbar_path"] = Field(description="the problem kind (fourbar_path)")
    crank_speed: float = Field(60.0, gt=0, le=10000,
                               description="r/min; the time scale of the trajectory and, with a [dynamics] table "
                                           "(which then needs it written here), the constant crank speed of the "
                                           "inverse dynamics")
    targets: TargetsSection
    linkage: LinkageSection
    design: DesignSection = Field(default_factory=DesignSection)
    rules: RulesSection = Field(default_factory=RulesSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    dynamics: DynamicsSection | None = Field(
        None, description="mass properties and limits for the inverse dynamics over a crank turn at crank_speed "
                          "(docs/ARCHITECTURE.md \"Dynamics\"; the coupler's bar is AB and the arm AP to the traced "
                          "point, of one section); left out: no dynamics, no dynamics rules")

    @model_validator(mode="after")
    def _free_timing_rules_need_free_timing(self) -> "FourbarPathSpec":
        # with targets.crank_deg every crank angle is given, so the order they are met in and the sense the crank
        # turns are too: a rule that asks otherwise would be dropped without a word
        if self.targets.crank_deg is None:
            return self
        if not self.rules.order:
            raise ValueError("rules.order = false: only read with free timing; targets.crank_deg gives every target's "
                             "crank angle, and so the order they are met in (leave order out, or drop crank_deg)")
        if self.rules.crank_turns != "either":
            raise ValueError(f"rules.direction = {json_text(self.rules.crank_turns)}: only read with free timing; "
                             f"targets.crank_deg gives every target's crank angle, and so the sense the crank turns "
                             f"in (leave direction out, or drop crank_deg)")
        return self

    @model_validator(mode="after")
    def _dynamics_fits_the_kind(self) -> "FourbarPathSpec":
        table = self.dynamics
        if table is None:
            return self
        if table.crank_speed is not None:
            raise ValueError("dynamics.crank_speed: a fourbar_path turns at its own crank_speed (r/min, at the top of "
                             "the spec); leave it out here")
        if "crank_speed" not in self.model_fields_set:
            # the inertia forces grow with its square: the default, a time scale of the trajectory only, would be a
            # speed nobody chose
            raise ValueError("crank_speed: a spec with a [dynamics] table gives its crank speed (r/min) at the top of "
                             "the spec; the default 60 r/min sets only the trajectory's time scale")
        if any(pm.at == "tip" and pm.link != "coupler" for pm in table.point_masses):
            raise ValueError("dynamics.point_masses: at = \"tip\" is the traced coupler point P, on the coupler")
        weight = table.counterweight
        if weight is not None and not all(isinstance(v, (int, float)) for v in (weight.mass, weight.radius)):
            raise ValueError("dynamics.counterweight: a fourbar_path's solve frees only its linkage; give the "
                             "counterweight's mass (kg) and radius (mm) as numbers")
        if table.rocker_counterweight is not None:
            raise ValueError("dynamics.rocker_counterweight: a fourbar_path reads a counterweight on its crank only; "
                             "leave the field out")
        return self

    @classmethod
    def old_forms(cls, data: dict) -> str:
        """The first spec forms ([bounds], [design] values, branch "open"/"crossed", hyphenated Grashof
        classes), each with the new spelling of the user's own values; read by spec.common.validate
        before the model (a before-validator would cost the strict JSON validation its arrays)."""
        return old_form_message(data)

    @field_validator("design", mode="after")
    @classmethod
    def _design_fits(cls, design: DesignSection, info: ValidationInfo) -> DesignSection:
        targets = info.data.get("targets")
        if design.crank_deg is not None and targets is not None:
            if targets.crank_deg is not None:
                raise ValueError("crank_deg: the timing is already prescribed by targets.crank_deg; remove one")
            if len(design.crank_deg) != len(targets.points):
                raise ValueError(f"crank_deg: expected one angle per target ({len(targets.points)}), "
                                 f"got {len(design.crank_deg)}")
        return design

    @property
    def timed(self) -> bool:
        """True when targets.crank_deg prescribes the crank angle of every point."""
        return self.targets.crank_deg is not None

    @property
    def branch(self) -> str:
        """The assembly as kinematics.coupler_point and result.json name it ("open" = +1, "crossed" = -1)."""
        return ASSEMBLIES[self.linkage.branch]

    def variables(self) -> dict[str, Variable]:
        """The design variables by result.json name (r1 .. theta0): a number or a free variable."""
        return {n: getattr(self.linkage, n) for n in VARIABLES}

    def list_variables(self) -> dict[str, tuple[str, bool]]:
        """result.json design values that are lists, by name -> (TOML path, free): the crank angle of each target,
        prescribed (targets.crank_deg, fixed) or, with free timing, solved (written to [design] crank_deg, free) --
        unless every linkage variable is fixed: solve refuses such a spec, so its crank angles are only check's."""
        if self.timed:
            return {"crank_deg": ("targets.crank_deg", False)}
        return {"crank_deg": ("design.crank_deg", any(isinstance(v, FreeVariable) for v in self.variables().values()))}

    def bounds_array(self) -> list[tuple[float, float]]:
        return [bounds_of(v) for v in self.variables().values()]

    def design_values(self) -> dict[str, float]:
        """The given design: each fixed value and each free variable's init."""
        return {n: value_of(v) for n, v in self.variables().items()}


#: [rules] direction -> the turning sense's short name inside and in result.json
TURNING = {"either": "either", "counter_clockwise": "ccw", "clockwise": "cw"}

#: linkage.branch -> the assembly's name in kinematics.coupler_point.BRANCHES and result.json
ASSEMBLIES = {1: "open", -1: "crossed"}


def _free_text(name: str, bound: Any, given: Any) -> str:
    """``r1 = {init = 110, bounds = [20, 200]}`` (or ``r1 = 75``) from an old [bounds] entry and [design] value."""
    if isinstance(bound, (list, tuple)) and len(bound) == 2 and all(isinstance(b, (int, float)) for b in bound):
        lo, hi = bound
        init = given if isinstance(given, (int, float)) and not isinstance(given, bool) else 0.5 * (lo + hi)
        return f"{name} = {{init = {init:g}, bounds = [{lo:g}, {hi:g}]}}"
    return f"{name} = {bound:g}" if isinstance(bound, (int, float)) and not isinstance(bound, bool) else \
        f"{name} = {{init = ..., bounds = [lo, hi]}}"


def old_form_message(data: dict) -> str:
    """A line per first-spec form in ``data``, naming it and its new spelling ("" when there is none)."""
    fixes: list[str] = []
    bounds = data.get("bounds")
    given_design = data.get("design")
    design: dict = given_design if isinstance(given_design, dict) else {}
    moved = [n for n in VARIABLES if n in design]
    if bounds is not None:
        entries = bounds.items() if isinstance(bounds, dict) else ()
        example = "; ".join(_free_text(n, b, design.get(n)) for n, b in entries) or \
            "r2 = {init = 30, bounds = [25, 45]}"
        fixes.append(f"bounds: [bounds] is no longer read; write each variable under [linkage], a number fixes it, "
                     f"{{init, bounds}} frees it: {example}")
    elif moved:
        given = design[moved[0]]
        init = f"{given:g}" if isinstance(given, (int, float)) and not isinstance(given, bool) else "..."
        fixes.append(f"design.{moved[0]}: [design] holds only crank_deg now; write the given value as the init of "
                     f"the variable under [linkage]: {moved[0]} = {{init = {init}, bounds = [lo, hi]}}")
    if "branch" in data:
        old = data["branch"]
        numbered: dict[str | int, int] = {"open": 1, "crossed": -1}
        new = numbered.get(old, old) if isinstance(old, (str, int)) else old
        fixes.append(f"branch: {json_text(old)} is no longer read at the top; write branch = {json_text(new)} under "
                     f"[linkage] (+1: B left of A -> O', the open assembly; -1: the crossed one)")
    linkage = data.get("linkage")
    if isinstance(linkage, dict) and linkage.get("branch") in ("open", "crossed"):
        fixes.append(f"linkage.branch: {json_text(linkage['branch'])} is no longer read; write branch = "
                     f"{ {'open': 1, 'crossed': -1}[linkage['branch']]} (+1: B left of A -> O', the open assembly; "
                     f"-1: the crossed one)")
    rules = data.get("rules")
    if isinstance(rules, dict) and rules.get("grashof") in ("crank-rocker", "double-crank"):
        fixes.append(f"rules.grashof: {json_text(rules['grashof'])} is no longer read; write grashof = "
                     f"{json_text(rules['grashof'].replace('-', '_'))}")
    if isinstance(rules, dict) and rules.get("direction") in ("ccw", "cw"):
        spelled = {"ccw": "counter_clockwise", "cw": "clockwise"}[rules["direction"]]
        fixes.append(f"rules.direction: {json_text(rules['direction'])} is no longer read; write direction = "
                     f"{json_text(spelled)}")
    return "\n".join(fixes)


def json_text(v: Any) -> str:
    return f'"{v}"' if isinstance(v, str) else str(v)
