"""Scale (the extreme-case matrix): every library problem with free variables solved with its lengths in
metres (every length x 1e-3) and x 1e3 instead of mm, against the same problem in mm.

The unit change is applied to the problem's NLP in the core (``ipopt.SolveMethod.length_factor``, synthesis.core.units):
every variable, row, bound and the objective of declared length power p is multiplied by factor**p (mm, m/s,
mm/s^2: p = 1, mm^2: 2, deg, rad, ratios: 0) -- the same feasible set and minimiser, the numbers a user in
metres would hand IPOPT.  Kinds carry mm constants and specs are in mm by contract, so the change is made on the
NLP, not on the spec; the kind and the multistart see mm as always (starts, re-check, result), IPOPT sees the
variables, the rows and the objective at their nominal scale (the kind's units): what is tested is that every
unit is declared right and that the rounding of the round trip does not move a solve.

The measure of "the same design": max over the design's entries of |d - d_mm| / max(1, |d_mm|) (mm or deg: a
relative difference, absolute below 1 unit).  Iterations: IPOPT's, summed over the starts compared.
"""

from __future__ import annotations

import functools
import statistics
from pathlib import Path

import numpy as np
import pytest

from solving import run_solve
from synthesis import kinds
from synthesis.core import ipopt, units
from synthesis.core.kind import Setting
from synthesis.core.solve import run_multistart, run_solve as run_core_solve
from synthesis.core.transcribe import transcribe
from synthesis.spec.design_info import describe
from synthesis.errors import SpecError
from synthesis.spec import load_spec

ROOT = Path(__file__).resolve().parents[2]
LIBRARY = ROOT / "problems"
FACTORS = (1e-3, 1e3)

#: one problem per kind whose start 0 (the spec's own design) is cheap and converges in mm: the default suite
#: solves it in mm, in metres and x 1e3 (about 10 s in all); every library problem and all its starts are the
#: benchmark study below.  Left to the study: guide_way (a 20 s build of its IPOPT solver), fourbar_path (start 0
#: of picking_arc stops at max_iter in mm too, so there is nothing to compare) and tillage_linkage (start 0 of
#: tillage_redesign takes 631 iterations in mm and is sensitive at the last digit (tillage_linkage/nlp.py): a start
#: that far from the optimum tests the multistart, which the study compares).
FAST = ("picker/cai2020_crank_rocker_synthesis.toml", "picker/picker_double_crank_redesign.toml",
        "clamp_cam/opening_cam_redesign.toml", "comb_finger/redesign_max_combing.toml",
        "combing_chain/redesign_window_80_100.toml", "guide_tube/uniform_spacing.toml",
        "steering/steering_redesign_27.toml", "planting_arm/redesign_from_example3.toml")

#: start 0 in mm, metres and x 1e3 reaches the same design within this (relative, 1 unit floor).  IPOPT sees the
#: kind's own numbers in every unit up to the rounding of the unit's round trip (variables, rows and objective are
#: scaled back by their declared units), so a design moves by rounding only -- unless the solve amplifies it (a
#: degenerate optimum); the bound was set when the rows were left in the new unit (measured then on the library's
#: best designs: at most 5.4e-7, most below 1e-9)
DESIGN_TOLERANCE = 1e-6
#: where a design differs by more, the mm design's own accuracy decides: solved again at tol 1e-11 (TIGHT) it
#: moves by e; two solves each stopping within e of the optimum differ by up to 2 e, so "the same" is within
#: 3 e.  guide_way smooth_redesign: its flat spline-energy optimum moves 1.1e-5 in mm itself from IPOPT's
#: tol 1e-8 to 1e-11 (objective 0.98726475630 -> 0.98726475310, measured before the fit was solved in units of
#: the path length: its objective is relative to the fit's energy), and at tol 1e-11 the three units agree
#: within 2.1e-9
TIGHT = {"ipopt.tol": 1e-11, "ipopt.acceptable_tol": 1e-11}
OWN_ERRORS = 3.0
#: "a comparable number of iterations": IPOPT's iterations in the other unit (start 0's in the default test, the
#: total over the starts in the library rows) at most this many times the mm count.  Not 1 by design: it was
#: set when IPOPT saw rows 1e-3 .. 1e-6 (or 1e3 .. 1e6) times as large, which changed its constraint scaling and
#: barrier path (start 0 of the default problems: 0.5 .. 2.0); with the rows scaled back, rounding alone remains.  Over several starts a start IPOPT
#: finds locally infeasible ends when its restoration phase gives up, which depends on the rows' absolute
#: size: planting envelope_redesign_from_example2 in metres runs 4 of its 32 starts to max_iter (500) where mm
#: stops them as infeasible after 74-184 iterations (total 2.22 x), while its 7 starts converging in both units
#: take 0.85 x the mm iterations; the ratio over starts converging in both units is in the figures too
ITERATION_RATIO = 3.0
#: problems whose optimum is not a point: two designs with the same objective and every rule satisfied exist,
#: so the design is compared through the objective (the proof is test_comb_finger_optimum_is_not_a_point)
NOT_A_POINT = {"comb_finger"}


def _guide_way_spline_free(model) -> bool:
    """A guide way spec solves for its spline's control points: all of them free within `move` of the convex fit
    when `control` is not given, else the coordinates given as {init, bounds} (smooth_redesign_dynamics gives every
    one as a number: a check)."""
    spline = getattr(model, "spline", None)
    if spline is None:
        return False
    if spline.control is None:
        return True
    return any(not isinstance(v, (int, float)) for point in spline.control for v in point)


@functools.cache
def library_problems() -> tuple[str, ...]:
    """Every library spec (relative to problems/) whose kind solves and that has a free design variable."""
    out = []
    for path in sorted(LIBRARY.rglob("*.toml")):
        loaded = load_spec(path)
        try:
            kinds.solving_kind_for(loaded)
        except SpecError:
            continue
        free = any(v["free"] for v in describe(loaded.model).values())
        if loaded.kind == "guide_way":          # its free variables are the spline's control points
            free = _guide_way_spline_free(loaded.model)
        if free:
            out.append(str(path.relative_to(LIBRARY)))
    return tuple(out)


def solve_in(loaded, factor: float, starts: int):
    """The kind's multistart (one worker, the spec's seed) with every length factor x its mm number."""
    kind = kinds.solving_kind_for(loaded)
    solving = kind.solving()
    spec = loaded.model
    # prepare (fits to published tables, laws) is data for the problem, in mm: not the NLP a unit change is about
    setting = Setting(spec, spec.solver.seed, solving.prepare(spec))
    return run_multistart(ipopt.solved_with_method(kind, length_factor=factor), setting, starts=starts, workers=1)


def design_difference(design: dict, reference: dict) -> float:
    return max((abs(design[k] - v) / max(1.0, abs(v)) for k, v in reference.items()
                if isinstance(v, (int, float)) and not isinstance(v, bool)), default=0.0)


def compare(relative: str, starts: int) -> dict:
    """mm, x 1e-3 and x 1e3 of one library problem from its first ``starts`` starts: per factor the best
    design's difference, the objective's relative difference, the iteration ratio, the satisfied starts and
    each start's (iterations, return status); for a problem no start of which satisfies every rule in mm
    (infeasible), the rules its elastic diagnosis names as conflicting, in each unit."""
    loaded = load_spec(LIBRARY / relative)
    try:
        mm = solve_in(loaded, 1.0, starts)
    # refused (before any start: a rule no design variable moves, judged on the kind's own problem, so the message
    # cannot differ by unit): the row says only that the build in each unit refuses alike and does not fail otherwise
    except SpecError as exc:
        return {"kind": loaded.kind, "refused": str(exc), **{f: {"refused": _refusal(loaded, f, starts)}
                                                              for f in FACTORS}}
    runs = {1.0: mm, **{f: solve_in(loaded, f, starts) for f in FACTORS}}
    mm_iterations = sum(r.outcome.iterations for r in mm.reports)
    out = {"kind": loaded.kind, "mm_iterations": mm_iterations, "mm_satisfied": mm.best.satisfied,
           "mm_starts": [(r.outcome.iterations, r.outcome.objective, r.outcome.return_status) for r in mm.reports]}
    conflicting = {f: conflicting_rules(loaded, f, starts) for f in (1.0, *FACTORS)} if not mm.best.satisfied else {}
    out["mm_own_accuracy"] = None
    for f in FACTORS:
        run = runs[f]
        iterations = sum(r.outcome.iterations for r in run.reports)
        a, b = run.best.outcome.objective, mm.best.outcome.objective
        both = [(m.outcome.iterations, r.outcome.iterations) for m, r in zip(mm.reports, run.reports)
                if m.outcome.success and r.outcome.success]
        out[f] = {"design": design_difference(run.best.outcome.design, mm.best.outcome.design),
                  "objective": abs(a - b) / max(1e-12, abs(b)), "iterations": iterations,
                  "ratio": iterations / max(1, mm_iterations), "satisfied": run.best.satisfied,
                  "starts": [(r.outcome.iterations, r.outcome.return_status) for r in run.reports],
                  "converged": len(both), "mm_converged": sum(m.outcome.success for m in mm.reports),
                  "converged_ratio": sum(r for _, r in both) / max(1, sum(m for m, _ in both))}
        if conflicting:
            out[f]["conflicting"] = conflicting[f]
            out[f]["same_conflict"] = conflicting[f] == conflicting[1.0]
    if (mm.best.satisfied and loaded.kind not in NOT_A_POINT
            and any(out[f]["design"] >= DESIGN_TOLERANCE for f in FACTORS)):
        out["mm_own_accuracy"] = own_accuracy(loaded, mm.best.outcome, starts)
    return out


def _refusal(loaded, factor: float, starts: int) -> str | None:
    """The message the solve in that unit is refused with before any start (None: it is not refused)."""
    try:
        solve_in(loaded, factor, starts)
    except SpecError as exc:
        return str(exc)
    return None


def own_accuracy(loaded, best, starts: int) -> float | None:
    """How far the mm design itself is from the optimum IPOPT's tolerance leaves it: the move of the best start's
    design when IPOPT, with tol 1e-11, is started in mm at the best start's whole decision vector (its auxiliaries
    included: a warm restart, not a new start from the design).  None -- no allowance -- for a kind that does not
    declare its problem to the core, when the tight solve does not converge, or when it ends at another objective
    (beyond 1e-6 relative): then it left for another optimum, a move that says nothing of the tolerance."""
    import dataclasses

    from synthesis.core.declared import DeclaredNLP

    solving = kinds.solving_kind_for(loaded).solving()
    setting = Setting(loaded.model, loaded.model.solver.seed, solving.prepare(loaded.model))
    # built without an IPOPT instance: only its declared problem is read, and IPOPT is built once, below, tight
    declared = getattr(solving.build(dataclasses.replace(setting, solver=False), False), "declared", None)
    if declared is None or best.raw is None:
        return None
    problem = declared.problem
    tight = dataclasses.replace(declared, problem=dataclasses.replace(
        problem, ipopt_options={**problem.ipopt_options, **TIGHT}))
    compiled = DeclaredNLP(tight, setting).compiled
    w, n_x = np.asarray(best.raw.x, float), problem.x.numel()
    out = compiled.solve(best.start, w[:n_x], extra0=w[n_x:])
    design = tight.design(out.x)
    objective = tight.objective(out, design, False)
    if not out.success or abs(objective - best.objective) > DESIGN_TOLERANCE * max(1.0, abs(best.objective)):
        return None
    return design_difference(design, best.design)


def conflicting_rules(loaded, factor: float, starts: int) -> list[str]:
    """The conflicting rules of the whole solve (multistart, then the elastic diagnosis) in that unit."""
    kind = ipopt.solved_with_method(kinds.solving_kind_for(loaded), length_factor=factor)
    result, _, _ = run_core_solve(kind, loaded, starts=starts, workers=1)
    return sorted((result.elastic or {}).get("conflicting", []))


def same(row: dict, f: float) -> bool:
    """The unit's solve is the mm one: the same design (the objective where the optimum is not a point; the
    same conflicting rules where no design satisfies them all) and the same verdict."""
    r = row[f]
    if "refused" in row:
        return r["refused"] == row["refused"]
    if r["satisfied"] != row["mm_satisfied"]:
        return False
    if not row["mm_satisfied"]:
        return r["same_conflict"]
    if row["kind"] in NOT_A_POINT:
        return r["objective"] < DESIGN_TOLERANCE
    own = row.get("mm_own_accuracy")
    return r["design"] < max(DESIGN_TOLERANCE, OWN_ERRORS * own if own is not None else 0.0)


def comparable_iterations(row: dict, f: float) -> bool:
    """"Solves ... in a comparable number of iterations" (the performance goal): IPOPT's iterations over the starts that
    converge in both units at most ITERATION_RATIO x the mm ones.  A start that does not solve in one unit is not
    a solve to compare: a start IPOPT gives up on as locally infeasible ends when its restoration phase gives up,
    which judges absolute row violations (1e-3 x smaller in metres), so the same infeasible start takes 76
    iterations in mm and 476 in metres (planting redesign_from_example2, start 0) -- measured, not a unit defect.
    Where no start converges in both units, the total over all starts is compared (the figure gives both)."""
    r = row[f]
    if "refused" in row:           # no start solved in any unit
        return True
    return (r["converged_ratio"] if r["converged"] else r["ratio"]) <= ITERATION_RATIO


def figure(row: dict) -> str:
    if "refused" in row:
        return "; ".join(f"x{f:g}: refused before any start, {'as' if same(row, f) else 'NOT as'} in mm "
                         f"({row['refused']})" for f in FACTORS)
    verdict = "" if row["mm_satisfied"] else "no design satisfies every rule (as in mm); "
    own = row.get("mm_own_accuracy")
    own_text = "" if own is None else f" (the mm design itself moves {own:.1e} at tol 1e-11)"
    return "; ".join(f"x{f:g}: {verdict}" + (f"conflicting rules {'the same' if row[f]['same_conflict'] else 'OTHER'} "
                                             f"({', '.join(row[f]['conflicting'])}), " if not row["mm_satisfied"] else "")
                     + f"design within {row[f]['design']:.1e}{own_text}, objective {row[f]['objective']:.1e}, "
                     f"iterations {row[f]['iterations']} / {row['mm_iterations']} mm = {row[f]['ratio']:.2f}, "
                     f"over the {row[f]['converged']} starts converging in both units "
                     f"{row[f]['converged_ratio']:.2f} ({row[f]['converged']} of {len(row[f]['starts'])} converge, "
                     f"mm {row[f]['mm_converged']})"
                     for f in FACTORS)


# ------------------------------------------------------------------------------------------ the units themselves

def test_length_power_table_and_an_unknown_unit():
    """The table's powers (mm 1, mm^2 2, m/s 1, mm/s^2 1, 1/mm -1, deg 0, ratios 0) and a unit not in it
    refused with the quantity named, not guessed."""
    assert [units.length_power(u) for u in ("mm", "mm^2", "m/s", "mm/s^2", "1/mm", "deg", "rad", "", "-")] == \
        [1, 2, 1, 1, -1, 0, 0, 0, 0]
    with pytest.raises(ValueError, match="rule spacing.*'furlong'"):
        units.length_power("furlong", "rule spacing")
    with pytest.raises(ValueError):
        ipopt.SolveMethod(length_factor=0.0)


@pytest.mark.parametrize("relative", library_problems())
def test_every_library_problem_declares_units_the_table_knows(relative):
    """Every quantity of every library problem the kinds build (variables, structural rows, rules, objective and its
    extras) has a unit in the length-power table, so the problem can be handed to IPOPT in metres: the benchmark
    above solves them, this builds them (no IPOPT instance: at most about half a second each).  A counterweight's
    kg and the rotary planetary kind's mm^2/rad were missing until 2026-11-29, found only by that benchmark.  Each
    problem is checked as solved and in its elastic form; the polisher a path synthesis builds on first use is its
    configuration form's problem with other IPOPT options, so the same units."""
    loaded = load_spec(LIBRARY / relative)
    if getattr(loaded.model, "tolerance", None) is not None:
        pytest.skip("a tolerance box is refused in another unit (its sensitivity variables mix units)")
    solving = kinds.solving_kind_for(loaded).solving()
    nlp = solving.build(Setting(loaded.model, 0, solving.prepare(loaded.model), solver=False), False)
    compiled = ipopt.compiled_in(nlp)
    assert compiled
    for c in compiled:
        # the problem as solved, and its elastic form (an infeasible run's diagnosis, solved in the same unit)
        for elastic, t in ((c.elastic, c.t), (True, transcribe(c.problem, elastic=True))):
            n_w = t.w.numel()
            assert units.variable_factors(c.problem, 1e-3, n_w, elastic).shape == (n_w,)
            assert units.row_factors(c.problem, 1e-3, t.owner, elastic).shape == (t.g.numel(),)
            assert units.objective_factor(c.problem, 1e-3, elastic) > 0


def _crank_rocker_spec(tmp_path, k: float):
    """The crank-rocker synthesis with every length of the spec x k (a physically k-times larger mechanism:
    its rules are angles and a time ratio, so it is the mm problem in another length unit)."""
    import re

    text = (LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").read_text()
    text, n = re.subn(r"(l\d+ = \{ init = )([\d.]+), bounds = \[([\d.]+), ([\d.]+)\]",
                      lambda m: f"{m.group(1)}{float(m.group(2)) * k!r}, bounds = [{float(m.group(3)) * k!r}, "
                                f"{float(m.group(4)) * k!r}]", text)
    assert n == 3 and "l10 = 140.0" in text
    path = tmp_path / f"scaled_{k:g}.toml"
    path.write_text(text.replace("l10 = 140.0", f"l10 = {140.0 * k!r}"))
    return load_spec(path)


@pytest.mark.parametrize("k", FACTORS)
def test_declared_units_match_the_physics(tmp_path, k):
    """Independent re-check of the declared units: the crank-rocker's spec with every length x k builds (by the
    kind's own code) the NLP a length unit change must give, so at any point its rows and objective equal the
    mm NLP's rows x factor**p of their declared units -- at 5 random points, to 1e-9 relative."""
    from synthesis.core.kind import Setting
    from synthesis.kinds.crank_rocker.solve import SOLVING

    mm = SOLVING.build(Setting(load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").model))
    scaled = SOLVING.build(Setting(_crank_rocker_spec(tmp_path, k).model))
    declared = ipopt.CompiledNLP(mm.problem, length_factor=k)
    n_w = mm.compiled.t.w.numel()
    u, c = declared._unit, declared._row_unit
    assert u.tolist() == [k] * 4 + [1.0] * 2 and n_w == 6          # lengths and slacks x k, the angles not
    rng = np.random.default_rng(1)
    for _ in range(5):
        w = np.concatenate([rng.uniform(20.0, 150.0, 4), rng.uniform(0.0, 6.0, 2)])
        g_mm = np.asarray(mm.compiled.g_function(w, []), float).ravel()
        g_k = np.asarray(scaled.compiled.g_function(w * u, []), float).ravel()
        np.testing.assert_allclose(g_k, c * g_mm, rtol=1e-9, atol=1e-12 * np.max(np.abs(g_mm)))
        f_mm, f_k = float(mm.compiled.f_function(w, [])), float(scaled.compiled.f_function(w * u, []))
        assert f_k == pytest.approx(declared._objective_unit * f_mm, rel=1e-12)


def test_a_robust_problem_is_refused_not_solved_wrongly():
    """A tolerance-box problem's sensitivity variables mix units: the change is refused with the reason."""
    loaded = load_spec(LIBRARY / "clamp_cam" / "opening_cam_robust_redesign.toml")
    with pytest.raises(ValueError, match="tolerance box"):
        solve_in(loaded, 1e-3, 1)


def test_comb_finger_optimum_is_not_a_point():
    """redesign_max_combing: two starts end at the same combing angle (objective) with every rule satisfied
    but at designs 1.3 mm apart in the drum height b (no rule binds b there) -- its optimum is a set, so its scale
    rows compare the objective."""
    loaded = load_spec(LIBRARY / "comb_finger" / "redesign_max_combing.toml")
    first, second = solve_in(loaded, 1.0, 3).reports[:2]
    assert first.satisfied and second.satisfied
    assert second.outcome.objective == pytest.approx(first.outcome.objective, rel=1e-8)
    assert design_difference(second.outcome.design, first.outcome.design) > 1e-4


# ------------------------------------------------------------------------------------- the scale case, start 0

@pytest.mark.parametrize("relative", [pytest.param(r, marks=pytest.mark.slow) if r.startswith("planting_arm/") else r
                                      for r in FAST])
def test_start_0_in_metres_and_x1e3_reaches_the_mm_design(relative, record_property):
    """Start 0 (the spec's design) of the problem in mm, metres (x 1e-3) and x 1e3: the same design within
    1e-6 (relative, 1 mm / 1 deg floor; the objective within 1e-6 where the optimum is not a point) and at most
    3 x the mm iterations."""
    row = compare(relative, 1)
    record_property("figure", f"{relative}: " + figure(row))
    assert row["mm_satisfied"]
    for f in FACTORS:
        assert row[f]["satisfied"] and same(row, f)
        assert row[f]["ratio"] <= ITERATION_RATIO


# ------------------------------------------------------------------- every library problem (benchmark)

#: the bench's start count (synthesis.bench.generic.FULL.starts): one row per library problem in bench.md's
#: extreme matrix compares the best of a problem's first 4 starts (its own seed) in each unit; the full study
#: below takes every start
BENCH_STARTS = 4


#: rows known to fail, with the measured cause (strict xfail of an AssertionError: the row fails the day it passes or
#: fails otherwise, so this is re-read).
#: tillage's two torque redesigns, measured 2026-11-29 (first 4 starts, spec's seed).  tillage_min_peak_torque: its
#: starts moved by +-1e-15 relative end elsewhere in mm itself (start 1 at 74.06 / 89.62 / 73.87; start 3, 60.229,
#: the best of the 4 in mm, once Infeasible_Problem_Detected after 902 iterations; start 0 only when moved by 1e-14;
#: start 2 not at all), while started at the mm best design the metres NLP stays there (moves 6e-9 in 97
#: iterations, objective within 5e-10).  tillage_torque_limited: its best of the 4 in mm (start 3, 403.18) is
#: Solved_To_Acceptable_Level, not a converged optimum -- started at its design IPOPT moves 0.21 to 390.49 in mm and
#: ends Infeasible_Problem_Detected in metres and x 1e3 -- and that start moved by +-1e-15 ends at 602.80 / 395.38.
#: Why the metres runs fare worse than mm's (no start of min_peak_torque's first 4 converges in metres, 2 in mm) is
#: not investigated further.
KNOWN_FAILING: dict[str, str] = {
    "tillage/tillage_min_peak_torque.toml": "its starts moved by 1e-15 relative end elsewhere in mm itself; the "
                                            "metres NLP started at the mm best stays there (moves 6e-9)",
    "tillage/tillage_torque_limited.toml": "its best start in mm is Solved_To_Acceptable_Level (IPOPT started there "
                                           "moves 0.21 to 390.49 in mm) and moved by 1e-15 ends elsewhere"}
#: the every-start study's (shown there, not asserted; not strict)
KNOWN_FAILING_EVERY_START: dict[str, str] = dict(KNOWN_FAILING)
#: (tillage_redesign was one until 2026-11-24: its start 0 was chaotic at the last digit -- moved by 1e-15 relative
#: in mm it ended at 393.27 mm instead of 373.06, and so did its metres round trip -- on a degenerate optimum;
#: the kind now relaxes bounds by 1e-10 (synthesis/kinds/tillage_linkage/nlp.py) and every such start ends at 373.06)


def _library_params():
    return [pytest.param(p, id=p, marks=[pytest.mark.xfail(reason=KNOWN_FAILING[p], strict=True,
                                                            raises=AssertionError)]
                         if p in KNOWN_FAILING else []) for p in library_problems()]


@pytest.mark.benchmark
@pytest.mark.parametrize("relative", _library_params())
def test_library_problem_in_metres_and_x1e3(relative, record_property):
    """One library problem, its first 4 starts in mm, metres (x 1e-3) and x 1e3: the best design within
    1e-6 (relative, 1 unit floor; the objective where the optimum is not a point; the conflicting rules where
    none is feasible), and the iterations of the starts converging in both units at most 3 x their mm iterations
    (the total over all starts where none does; both ratios are in the figure).  A problem with a tolerance box is refused (its sensitivity variables mix units)."""
    loaded = load_spec(LIBRARY / relative)
    if getattr(loaded.model, "tolerance", None) is not None:
        with pytest.raises(ValueError, match="tolerance box"):
            solve_in(loaded, 1e-3, 1)
        record_property("figure", f"{relative}: refused (a tolerance box: its sensitivity variables mix units)")
        return
    row = compare(relative, min(BENCH_STARTS, loaded.model.solver.starts))
    record_property("figure", f"{relative}, first {min(BENCH_STARTS, loaded.model.solver.starts)} starts: "
                    + figure(row))
    for f in FACTORS:
        assert same(row, f)
        assert comparable_iterations(row, f)


@pytest.mark.benchmark
def test_every_library_problem_every_start(record_property):
    """Every library problem with free variables, all its starts (its own count and seed), mm against x 1e-3
    and x 1e3: the best design and objective and the iterations, with the median and worst ratio, under the
    bench row's tolerances (not part of bench.md: minutes of solves)."""
    rows, refused = {}, []
    for relative in library_problems():
        loaded = load_spec(LIBRARY / relative)
        if getattr(loaded.model, "tolerance", None) is not None:
            refused.append(relative)
            continue
        rows[relative] = compare(relative, loaded.model.solver.starts)
    lines = [f"{p}: " + figure(r) for p, r in rows.items()]
    for key, what in (("ratio", "total"), ("converged_ratio", "over starts converging in both units")):
        ratios = [r[f][key] for r in rows.values() if "refused" not in r for f in FACTORS]
        lines.append(f"iteration ratio ({what}) over {len(ratios) // len(FACTORS)} problems x 2 units: median "
                     f"{statistics.median(ratios):.2f}, worst {max(ratios):.2f}, best {min(ratios):.2f}")
    lines.append(f"refused (tolerance box): {', '.join(refused)}")
    # the rows known to fail (KNOWN_FAILING_EVERY_START, with their cause) are shown, not held to the tolerances
    lines.append(f"known to fail (not asserted): "
                 f"{', '.join(p for p in rows if p in KNOWN_FAILING_EVERY_START) or 'none'}")
    record_property("figure", "\n".join(lines))
    print("\n".join(lines))
    bad = [(p, f) for p, r in rows.items() if p not in KNOWN_FAILING_EVERY_START for f in FACTORS
           if not (same(r, f) and comparable_iterations(r, f))]
    assert not bad, bad


@pytest.mark.parametrize("factor, scaling", [(1.0, "nominal"), (1e-3, "nominal"), (1e3, "nominal"), (1e-3, "none")])
def test_a_watched_solve_sees_the_objective_in_the_problem_s_units(factor, scaling):
    """The iteration watch (fourbar_path's early cut) is handed f in the kind's units whatever unit IPOPT works
    in: at iteration 0 it is f(x0) exactly, and at the end the optimum 7 mm^2 (a merge once handed it c_f f)."""
    import casadi as ca
    from synthesis.core.ipopt import CompiledNLP
    from synthesis.core.problem import ObjectiveParts, Problem

    x = ca.SX.sym("x", 2)
    problem = Problem("watched", x, [0.0, 0.0], [100.0, 100.0], [], [],
                      ObjectiveParts(f=(x[0] - 30) ** 2 + (x[1] - 40) ** 2 + 7.0), x_units=["mm", "mm"],
                      objective_unit="mm^2")
    nlp = CompiledNLP(problem, watched=True, method=ipopt.SolveMethod(scaling=scaling, length_factor=factor))
    seen = []
    out = nlp.solve(0, np.array([1.0, 2.0]), watch=lambda k, f: seen.append(f) or False)
    assert seen[0] == pytest.approx(29.0 ** 2 + 38.0 ** 2 + 7.0, rel=1e-12)
    assert seen[-1] == pytest.approx(7.0, rel=1e-6)
    assert out.objective == pytest.approx(7.0, rel=1e-6)


@pytest.mark.parametrize("k", FACTORS)
def test_tillage_declared_units_match_its_kinematics(k):
    """tillage_linkage's structural rows (the lowest/highest point and soil entry/exit conditions, in mm / 100)
    and its objective c / 100 are lengths: with a, b, c and height_c x k (angles kept) the tip's path is k times
    the mm one, so each structural row and the objective is factor**p of its mm value for its declared p --
    checked at 3 random designs to 1e-9 relative (they were declared plain numbers, which left them at mm size
    in another length unit: the x 1e3 row then ended start 0 at c = 393.3 instead of 373.1 mm)."""
    from synthesis.core.kind import Setting
    from synthesis.kinds.tillage_linkage.nlp import angles_guess
    from synthesis.kinds.tillage_linkage.solve import SOLVING

    spec = load_spec(LIBRARY / "tillage" / "tillage_redesign.toml").model
    nlp = SOLVING.build(Setting(spec))
    declared = ipopt.CompiledNLP(nlp.problem, length_factor=k)
    u, c = declared._unit, declared._row_unit
    structural = np.array([o is None for o in nlp.compiled.t.owner])
    assert structural.sum() > 6 and declared._objective_unit == k
    rng = np.random.default_rng(3)
    for _ in range(3):
        design = np.array([rng.uniform(60, 140), rng.uniform(200, 380), rng.uniform(300, 800), rng.uniform(5, 60),
                           rng.uniform(100, 300)])
        w = np.concatenate([design, angles_guess(spec, dict(zip(nlp.names, design)))])
        g = np.asarray(nlp.compiled.g_function(w, []), float).ravel()
        g_k = np.asarray(nlp.compiled.g_function(w * u, []), float).ravel()     # the k-times mechanism in mm
        np.testing.assert_allclose(g_k[structural], (c * g)[structural], rtol=1e-9,
                                   atol=1e-12 * np.max(np.abs(g[structural])))
        assert float(nlp.compiled.f_function(w * u, [])) == pytest.approx(k * float(nlp.compiled.f_function(w, [])),
                                                                          rel=1e-12)
