"""Path-synthesis problems of the literature, with the published linkages as competitors.

Three benchmark target sets of the four-bar path-synthesis literature, each with the linkages other
papers published for it.  The numbers are data, problems/fourbar_path/literature.json (DATA), each with where it was
read (nothing there is from memory; see problems/fourbar_path/LITERATURE.md for the search and the readings):

* The targets, timing, variable ranges and the competitors' linkages: the MATLAB code and data that
  Nguyen-Van, Lieu, Xuan-Mung & Nguyen published with their paper (Symmetry 2022, 14(2), 381,
  doi:10.3390/sym14020381; "HCDJ"), GitHub sy-nguyen-van/DE_Jaya_Synthesis_Four_Bar_Mechanisms at
  commit a18dcd43fbeb5ae8f43b0bccf4ce719a9c1eb7a6.  Its CheckCASE*.m scripts hold the
  competitors' published linkages as they transcribed them, labelled by source ("Cabrera", "Kunjur",
  "MUMSA", "IOA", "WYLin", or unlabelled); its x_best_HCDJ_Case*.txt and Records_HCDJ_Case*.txt hold HCDJ's
  own best linkage and the objective recorded for it.  The original papers' tables were not readable
  here: the labels are the repository's, and the only error figures retrieved are HCDJ's records.
* The convention: the repository's Objf*.m (theta3 by the half-angle formula with the minus root, coupler
  point rcx along A -> B and rcy normal to it, the whole turned by theta0 about the input pivot (x0, y0)).
  It is this package's (synthesis.kinds.fourbar_path.kinematics) on the open branch (+1): the coupler points of every
  competitor but one agree to 1e-12 (5e-10 near a toggle) in both (tests/test_fourbar_path_literature.py).

Angles are transcribed as the source writes them (radians) and turned into degrees here.  The sources'
lower bound 0 of the link lengths is LENGTH_FLOOR (a spec's lengths must be > 0).  The problems are
unitless in the sources; the objective is in the problem's units squared ("mm^2" in result.json).

``literature_spec(name)`` is what ``agrisynth solve`` would see; ``evaluate_competitor`` scores a published
linkage with this package's objective and rules.  The bench (``agrisynth bench fourbar_path``) runs each
problem with IPOPT multistart, differential evolution and the best published linkage (bench.literature_cases).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import numpy as np

from synthesis.kinds.fourbar_path.check import Evaluation, evaluate, unwrapped
from synthesis.kinds.fourbar_path.kinematics import VARIABLES
from synthesis.library import LIBRARY
from synthesis.spec import LoadedSpec
from synthesis.spec.common import validate
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

#: the target sets, their published linkages and the best known objectives
DATA = LIBRARY / "fourbar_path" / "literature.json"
_DATA = json.loads(DATA.read_text())
#: the sources' lower bound 0 of a link length, as a spec allows it (lengths > 0); no linkage here is near it
LENGTH_FLOOR = float(_DATA["length_floor"])


@dataclass(frozen=True)
class Competitor:
    """A published linkage: the nine variables as the source writes them (theta0 and crank angles in rad,
    order r1 r2 r3 r4 rcx rcy x0 y0 theta0), where they were read and, if retrieved, the error published for it."""

    label: str
    citation: str
    read_from: str
    values: tuple                          # r1 r2 r3 r4 rcx rcy x0 y0 theta0 (rad)
    crank_rad: tuple | None = None         # free timing: the source's crank angle of each target (rad)
    published_error: float | None = None   # the source's own objective figure, where one was retrieved
    error_read_from: str | None = None
    branch: int = 1                        # the assembly its objective reads (this package's convention)
    note: str | None = None                # what the transcription found about it

    def design(self) -> dict:
        """r1..theta0 as this package writes them (theta0 in degrees)."""
        d = dict(zip(VARIABLES, (float(v) for v in self.values)))
        d["theta0"] = math.degrees(d["theta0"])
        return d

    def crank_deg(self) -> list[float] | None:
        return None if self.crank_rad is None else [math.degrees(a) for a in self.crank_rad]


@dataclass(frozen=True)
class LiteratureProblem:
    name: str
    description: str
    points: tuple
    crank_rad: tuple | None            # prescribed timing (rad), None: free timing
    bounds: dict                       # variable -> [lo, hi] (theta0 in deg) or a fixed number
    read_from: str
    competitors: tuple


def _tuples(x):
    """Lists of the data file as tuples (the frozen dataclasses hold tuples), numbers as written."""
    return tuple(_tuples(v) for v in x) if isinstance(x, list) else x


def _competitor(c: dict) -> Competitor:
    return Competitor(c["label"], c["citation"], c["read_from"], _tuples(c["values"]),
                      _tuples(c["crank_rad"]) if "crank_rad" in c else None, c.get("published_error"),
                      c.get("error_read_from"), c.get("branch", 1), c.get("note"))


def _problems() -> dict[str, LiteratureProblem]:
    return {name: LiteratureProblem(name, p["description"], _tuples(p["points"]),
                                    None if p["crank_rad"] is None else _tuples(p["crank_rad"]), p["bounds"],
                                    p["read_from"], tuple(_competitor(c) for c in p["competitors"]))
            for name, p in _DATA["problems"].items()}


PROBLEMS = _problems()
NAMES = tuple(PROBLEMS)


def literature_data(name: str, solver: dict | None = None) -> dict:
    """The spec (as TOML-like data) of the named problem: the source's ranges, timing and rules."""
    p = PROBLEMS[name]
    targets: dict = {"points": [[float(x), float(y)] for x, y in p.points]}
    if p.crank_rad is not None:
        targets["crank_deg"] = [math.degrees(a) for a in p.crank_rad]
    linkage = {}
    for n in VARIABLES:
        b = p.bounds[n]
        # free variables start at the middle of the box (the given design, start 0), as the inexact set does
        linkage[n] = float(b) if not isinstance(b, list) else {"init": 0.5 * (b[0] + b[1]), "bounds": list(b)}
    timing = "prescribed timing" if p.crank_rad is not None else "free timing"
    return {"kind": "fourbar_path", "name": f"literature_{name}",
            "source": f"literature target set ({timing}): {p.description}; {p.read_from} "
                      f"(synthesis.kinds.fourbar_path.literature)",
            "targets": targets, "linkage": linkage,
            # the sources' constraints: Grashof with the crank shortest, and (free timing) the targets in order
            "rules": {"grashof": "crank_rocker", "order": True}, "solver": dict(solver or {})}


def literature_spec(name: str, solver: dict | None = None) -> LoadedSpec:
    """The named problem as a loaded spec (what ``agrisynth solve`` would see)."""
    data = literature_data(name, solver)
    model = validate(FourbarPathSpec, data, prefix="fourbar_path")
    sha = hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()
    return LoadedSpec(model, Path(f"<{data['name']}>"), sha)


@dataclass
class CompetitorScore:
    """A published linkage scored with this package's objective and rules."""

    competitor: Competitor
    objective: float                 # sum of squared distances, the problem's units^2
    rules_hold: bool                 # every rule of the spec (on the fine re-check grid of the check)
    outside: list[str]               # the variables outside the problem's ranges (the sources' third constraint)
    crank_deg: list[float]           # the crank angle of each target the score uses (deg)
    timing: str                      # "prescribed", "published" (the source's angles) or "nearest"
    evaluation: Evaluation


def evaluate_competitor(name: str, competitor: Competitor | str, timing: str = "published") -> CompetitorScore:
    """Score a published linkage on the named problem with ``check.evaluate`` (the re-check of every solver
    start).  Prescribed timing: the problem's crank angles.  Free timing: the angles the source publishes
    (``timing="published"``, unwrapped in the crank direction: the same crank positions, written to meet the
    order rule's "within one turn") or the nearest point of the coupler curve to each target (``"nearest"``).
    A competitor of the other assembly than the spec's is scored on its own branch (its ``branch``)."""
    p = PROBLEMS[name]
    c = competitor if isinstance(competitor, Competitor) else next(x for x in p.competitors if x.label == competitor)
    spec = cast(FourbarPathSpec, literature_spec(name).model)      # literature_spec validated it with this model
    if c.branch != spec.linkage.branch:
        spec = spec.model_copy(update={"linkage": spec.linkage.model_copy(update={"branch": c.branch})})
    if spec.timed:
        ev, used = evaluate(spec, c.design()), "prescribed"
    elif timing == "published":
        angles = unwrapped(np.array(c.crank_deg()) % 360.0, spec.rules.direction)
        ev, used = evaluate(spec, c.design(), angles), "published"
    elif timing == "nearest":
        ev, used = evaluate(spec, c.design(), None), "nearest"
    else:
        raise ValueError(f"timing: expected 'published' or 'nearest', got {timing!r}")
    holds = bool(np.all(np.isfinite(ev.errors_mm))) and all(r.record().satisfied for r in ev.rules)
    return CompetitorScore(c, ev.sum_sq, holds, outside_ranges(name, c.design()), ev.crank_deg, used, ev)


def outside_ranges(name: str, design: dict) -> list[str]:
    """The variables of ``design`` outside the problem's ranges (a fixed one: not equal to its value)."""
    out = []
    for n, b in PROBLEMS[name].bounds.items():
        v = design[n]
        if isinstance(b, list) and not b[0] <= v <= b[1] or not isinstance(b, list) and abs(v - b) > 1e-12:
            out.append(n)
    return out


def competitor_scores(name: str) -> list[CompetitorScore]:
    """Every published linkage of the named problem, scored (evaluate_competitor, the source's own crank angles)."""
    return [evaluate_competitor(name, c) for c in PROBLEMS[name].competitors]


def best_published(name: str, scores: list[CompetitorScore] | None = None) -> CompetitorScore:
    """The published linkage with the lowest objective among those on the spec's branch, within the problem's
    ranges, whose every rule holds (the bench's ``published`` competitor); free timing: at the source's own crank
    angles.  ``scores``: competitor_scores(name), when already computed."""
    scores = competitor_scores(name) if scores is None else scores
    return min((s for s in scores if s.competitor.branch == 1 and s.rules_hold and not s.outside),
               key=lambda s: s.objective)


#: best objective known for each problem (units^2): the lowest any recorded run found with every rule holding on
#: the fine grid -- the 64-start runs (seed 0, 2 workers) and the 512-start cross-check (seed 7) of
#: problems/fourbar_path/LITERATURE.md, both at or below every published linkage of the problem
BEST_KNOWN: dict[str, float] = {name: float(v) for name, v in _DATA["best_known"].items()}
