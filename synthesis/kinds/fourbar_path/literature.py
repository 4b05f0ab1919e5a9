"""Path-synthesis problems of the literature, with the published linkages as competitors.

Three benchmark target sets of the four-bar path-synthesis literature, each with the linkages other
papers published for it.  Where the numbers were read (nothing here is from memory; see
problems/fourbar_path/LITERATURE.md for the search and the readings):

* The targets, timing, variable ranges and the competitors' linkages: the MATLAB code and data that
  Nguyen-Van, Lieu, Xuan-Mung & Nguyen published with their paper (Symmetry 2022, 14(2), 381,
  doi:10.3390/sym14020381; "HCDJ"), GitHub sy-nguyen-van/DE_Jaya_Synthesis_Four_Bar_Mechanisms at
  commit a18dcd43fbeb5ae8f43b0bccf4ce719a9c1eb7a6 (below: REPO).  Its CheckCASE*.m scripts hold the
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

import numpy as np

from synthesis.kinds.fourbar_path.check import Evaluation, evaluate, unwrapped
from synthesis.kinds.fourbar_path.kinematics import VARIABLES
from synthesis.spec import LoadedSpec
from synthesis.spec.common import validate
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

REPO = "sy-nguyen-van/DE_Jaya_Synthesis_Four_Bar_Mechanisms"
COMMIT = "a18dcd43fbeb5ae8f43b0bccf4ce719a9c1eb7a6"
HCDJ = ("Nguyen-Van S., Lieu Q.X., Xuan-Mung N., Nguyen T.T.N., A new study on optimization of four-bar "
        "mechanisms based on a hybrid-combined differential evolution and Jaya algorithm, Symmetry 14(2) 381, "
        "2022, doi:10.3390/sym14020381")
#: the sources' lower bound 0 of a link length, as a spec allows it (lengths > 0); no linkage here is near it
LENGTH_FLOOR = 0.01


def _src(path: str) -> str:
    return f"github.com/{REPO} {path} @ {COMMIT[:12]}"


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


def _problems() -> dict[str, LiteratureProblem]:
    pi = math.pi
    link50, link80 = [LENGTH_FLOOR, 50.0], [LENGTH_FLOOR, 80.0]
    arc5 = LiteratureProblem(
        name="arc5_timed",
        description="five points on an arc, prescribed crank angles pi/6 .. pi/2, input pivot at the origin and "
                    "frame along +x (x0 = y0 = theta0 = 0 fixed); six variables",
        points=((3, 3), (2.759, 3.363), (2.372, 3.663), (1.890, 3.862), (1.355, 3.943)),
        crank_rad=(pi / 6, pi / 4, pi / 3, 5 * pi / 12, pi / 2),
        bounds={"r1": link50, "r2": link50, "r3": link50, "r4": link50, "rcx": [-50.0, 50.0], "rcy": [-50.0, 50.0],
                "x0": 0.0, "y0": 0.0, "theta0": 0.0},
        read_from=_src("Case2/CheckCASE2.m, Case2/Objf2.m, Additional-functions/Mechanisms.m ('Case2')"),
        competitors=(
            Competitor("Cabrera et al. 2002", "Cabrera J.A., Simon A., Prado M., Optimal synthesis of mechanisms "
                       "with genetic algorithms, Mech. Mach. Theory 37 (2002) 1165-1177 (label 'Cabrera' of the "
                       "source)",
                       _src("Case2/CheckCASE2.m"), (3.0630424, 1.9959624, 3.305823, 2.524706, 1.645158, 1.708959,
                                                     0, 0, 0)),
            Competitor("Kunjur & Krishnamurty", "Kunjur A., Krishnamurty S., genetic-algorithm mechanism synthesis "
                       "(label 'Kunjur' of the source; a copy of the paper, of which only the abstract was readable "
                       "here: www.ecs.umass.edu/mie/labs/mda/mechanism/papers/genetic.html)",
                       _src("Case2/CheckCASE2.m"), (3.509643, 1.857606, 4.725835, 3.518721, 1.959538, 1.558898,
                                                     0, 0, 0)),
            Competitor("MUMSA", "label 'MUMSA' of the source (its publication is not named there)",
                       _src("Case2/CheckCASE2.m"), (3.77326856, 2.00000403, 4.11697104, 2.74615671, 1.67848787,
                                                     1.67098007, 0, 0, 0)),
            Competitor("IOA", "label 'IOA' of the source (its publication is not named there)",
                       _src("Case2/CheckCASE2.m"), (2.803607, 1.99226, 3.030461, 2.474117, 1.64413, 1.714536,
                                                     0, 0, 0)),
            Competitor("HCDJ (Nguyen-Van et al. 2022)", HCDJ, _src("Case2/x_best_HCDJ_Case2.txt"),
                       (4.2930812, 1.9978324, 4.7374099, 2.9417301, 1.7074051, 1.6441696, 0, 0, 0),
                       published_error=1.9239227e-06,
                       error_read_from=_src("Case2/Records_HCDJ_Case2.txt (row 51: best of 50 runs, run 42)")),
        ))
    semicircle6 = LiteratureProblem(
        name="semicircle6_timed",
        description="six points on a half circle of radius 10, prescribed crank angles pi/6 .. pi; nine variables",
        points=((0, 0), (1.9098, 5.8779), (6.9098, 9.5106), (13.09, 9.5106), (18.09, 5.8779), (20, 0.0)),
        crank_rad=(pi / 6, pi / 3, pi / 2, 2 * pi / 3, 5 * pi / 6, pi),
        bounds={"r1": link50, "r2": link50, "r3": link50, "r4": link50, "rcx": [-50.0, 50.0], "rcy": [-50.0, 50.0],
                "x0": [-50.0, 50.0], "y0": [-50.0, 50.0], "theta0": [0.0, 360.0]},
        read_from=_src("Case4/CheckCASE4.m, Case4/Objf4.m, Additional-functions/Mechanisms.m ('Case4')"),
        competitors=tuple(
            Competitor(f"CheckCASE4 column {k}", "unlabelled column of the source's competitor table "
                       "(its publication is not named there)", _src("Case4/CheckCASE4.m"), v)
            for k, v in ((1, (49.994859, 5, 5.915643, 49.994867, 18.925715, 0, 14.472475, -12.494409, 0.467287)),
                         (2, (50, 5, 5.905345, 50, 18.819312, 0, 14.373772, -12.444295, 0.463633)),
                         (3, (50, 5, 7.031047, 48.134183, 16.976687, 12.952139, 12.197494, -15.998203, 0.0428247)),
                         (4, (49.999217, 1.3476638, 1.3476825, 49.999235, 11.383058, 4.4426855, 10.1944353,
                              -3.6925458, 6.2157809)),
                         (5, (49.968967, 4.785659, 6.491026, 48.393942, 16.444782, 11.988091, 12.046587, -14.774897,
                              0.038678)),
                         (6, (60, 5, 7.06916, 58.1241, 16.8655, 13.0576, 11.8936, -16.0037, 6.28318))))
        + (Competitor("HCDJ (Nguyen-Van et al. 2022)", HCDJ, _src("Case4/x_best_HCDJ_Case4.txt"),
                      (49.99998, 1.3484315, 1.3484507, 50.0, 11.384434, 4.4424357, 10.194752, -3.694134, 6.2158799),
                      published_error=1.2162122,
                      error_read_from=_src("Case4/Records_HCDJ_Case4.txt (row 51: best of 50 runs, run 23)")),))
    ellipse10 = LiteratureProblem(
        name="ellipse10",
        description="ten points on an ellipse, the first repeated as the last (a closed loop); free timing, the "
                    "targets met in order within one turn",
        points=((20, 10), (17.66, 15.142), (11.736, 17.878), (5, 16.928), (0.60307, 12.736), (0.60307, 7.2638),
                (5, 3.0718), (11.736, 2.1215), (17.66, 4.8577), (20, 10)),
        crank_rad=None,
        bounds={"r1": link80, "r2": link80, "r3": link80, "r4": link80, "rcx": [-80.0, 80.0], "rcy": [-80.0, 80.0],
                "x0": [-80.0, 80.0], "y0": [-80.0, 80.0], "theta0": [0.0, 360.0]},
        read_from=_src("Case5/CheckCase5.m, Case5/Objf5.m, Case5/Cons5.m, Additional-functions/Mechanisms.m ('Case5')"),
        competitors=tuple(
            Competitor(f"CheckCase5 column {k}", "column of the source's competitor table headed '%   MUMSA IOA "
                       "WYLin' (three labels for four columns: which is which is not certain; Case1/Check.m names "
                       "'WY Lin and KM Hsiao: A new differential evolution algorithm with a combined mutation "
                       "strategy for optimum synthesis of path-generating four-bar mechanisms')",
                       _src("Case5/CheckCase5.m"), v[:9], v[9:], branch=b)
            for k, b, v in (
                (1, 1, (79.516068, 9.723973, 45.842524, 51.432848, 8.213922, -2.9539575, 2.021109, 13.2165878,
                        5.5969445, 0.6376873, 1.3255329, 2.0080339, 2.6955659, 3.3845794, 4.08293762, 4.79845482,
                        5.51170565, 6.2127919, 0.6371866)),
                (2, 1, (65.428771, 8.016387, 47.221655, 44.13656, -11.570858, -1.904914, 10.635414, -1.675477,
                        3.86733, 2.419931, 3.109267, 3.81295, 4.50644, 5.181139, 5.88342, 0.296263, 0.991153,
                        1.707787, 2.418865)),
                (3, 1, (80.0, 8.045662, 50.81902, 42.20801, -10.63697, -2.29109, 8.494813, -0.7579678, 3.88921,
                        2.449437, 3.153969, 3.837114, 4.520171, 5.204799, 5.898536, 0.316204, 1.023555, 1.738992,
                        2.449437)),
                # the crossed assembly: with the source's formula (open) it is 436 units^2 off, with the crossed
                # one 0.00297 -- a linkage of the other branch (the spec's is open), scored on its own
                (4, -1, (54.7218, 8.53201, 31.4848, 33.2131, 0.423061, 5.9996, 7.30574, 4.88892, 0.0965143, 0.0,
                         0.714643, 1.42348, 2.1297, 2.80325, 3.4741, 4.14885, 4.85494, 5.56444, 6.28318))))
        + (Competitor("HCDJ (Nguyen-Van et al. 2022)", HCDJ, _src("Case5/x_best_HCDJ_Case5.txt"),
                      (79.999856, 8.1232008, 50.870344, 42.360533, -10.853763, 0.091433127, 7.5379031, -0.52254141,
                       4.0121195),
                      (2.3428599, 3.0535127, 3.7417464, 4.4255457, 5.1086716, 5.7983829, 0.21286893, 0.91658554,
                       1.6304135, 2.3428152),
                      published_error=4.2014375e-04,
                      error_read_from=_src("Case5/Data_best_25_2/Records_HCDJ_Case5.txt (row 51: best of 50 runs, "
                                           "run 3; its column 4 is this linkage)")),))
    return {p.name: p for p in (arc5, semicircle6, ellipse10)}


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
    spec: FourbarPathSpec = literature_spec(name).model
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
BEST_KNOWN: dict[str, float] = {
    "arc5_timed": 7.415751306805533e-07, "semicircle6_timed": 1.216212139419232, "ellipse10": 4.0199205542845484e-04,
}
