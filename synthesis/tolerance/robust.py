"""``solve`` of a spec with a ``[tolerance]`` table: every rule held at its linearised worst case in the
tolerance box (the core transcription's robust form, :mod:`synthesis.core.transcribe`), for every kind.

:func:`robust_kind` wraps a kind's :class:`~synthesis.core.kind.Solving`: its NLP is built with the box in its
setting (``Setting.tolerance``: :func:`synthesis.core.declared.compile_problem` holds the kind's own Problem in it,
the kind knowing nothing of it, and starts the robust extra variables at each start), and the result gets the
Monte-Carlo check of the answer under ``facts.tolerance``.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from synthesis.core import interrupt
from synthesis.core.kind import Finished, Kind, Setting
from synthesis.core.problem import Problem, Tolerance
from synthesis.core.sensitivity import PinningError
from synthesis.spec.design_info import describe, describe_lists
from synthesis.errors import AgrisynthError, SpecError
from synthesis.tolerance.analysis import corner_margins, linearise, monte_carlo, stack_up
from synthesis.tolerance.design import (DesignMap, box_of, followers_of, refuse_crossing_zero, spec_keys,
                                        whole_problem)


def _box_text(spec, scale: float | None = None, units: set | None = None) -> str:
    """The spec's tolerance box in words ("±0.2 mm, ±0.3 deg, l3 ±0.1"); with ``scale``, every half-width times it,
    named ("lengths ±0.0616 mm") and only the per-unit widths of ``units`` (those the box gives a variable)."""
    tol = spec.tolerance
    parts = []
    for width, unit, word in ((tol.length, "mm", "lengths"), (tol.angle, "deg", "angles")):
        if width and scale is None:
            parts.append(f"±{width:g} {unit}")
        elif width and (units is None or unit in units):
            parts.append(f"{word} ±{scale * width:.3g} {unit}")
    parts += [f"{k} ±{v:g}" if scale is None else f"{k} ±{scale * v:.3g}" for k, v in tol.variables.items()]
    return ", ".join(parts) or ("none" if scale is None else "")


class _Resolver:
    """Problem -> its Tolerance, from the spec (names in the NLP's order are the spec's variables)."""

    def __init__(self, kind: Kind, spec):
        self.kind, self.kind_name, self.spec = kind, kind.name, spec

    def __call__(self, problem: Problem) -> Tolerance | None:
        info = describe(self.spec)
        names = list(info)
        n = len(names)
        unsupported = SpecError(f"{self.kind_name}: a [tolerance] table in `solve` is not supported for this kind "
                                f"yet (its NLP does not work in the spec's design variables {names}); "
                                f"`agrisynth tolerance RESULT` analyses a solved design")
        if problem.x.numel() < n:       # e.g. a fixed wall angle that enters the NLP as a number
            raise SpecError(f"{self.kind_name}: a [tolerance] table in `solve` needs every design variable of the "
                            f"spec ({', '.join(names)}) in the NLP, and this kind's NLP takes a fixed one as a number "
                            f"({problem.x.numel()} decision entries); `agrisynth tolerance RESULT` analyses a solved "
                            f"design with the fixed ones toleranced too")
        try:
            d0, J = self.kind.design_affine(self.spec, n)
        except AttributeError:        # a map the kind cannot give from the spec alone
            raise unsupported from None
        dmap = DesignMap(names, names, [info[k]["unit"] or self.kind.design_unit for k in names], d0, J,
                         followers_of(self.kind.follows, names))
        tol = self.spec.tolerance
        box = box_of(dmap, tol.length, tol.angle, dict(tol.variables))
        # a design entry nothing in the NLP reads (an NLP may keep a fixed variable's entry but compute with its
        # number) would take its tolerance silently nowhere: refused, naming it.  (An entry the objective reads but no
        # rule does is held trivially: no rule's worst case moves with it.)
        objective = [ca.vec(ca.SX(problem.objective.f))] if isinstance(getattr(problem.objective, "f", None),
                                                                        (ca.SX, ca.MX)) else []
        objective += [ca.vec(ca.SX(e)) for e, _, _ in getattr(problem.objective, "rows", ())]   # an epigraph's rows
        rows = ca.vertcat(*(ca.vec(ca.SX(e)) for rule in problem.rules for e, _, _ in rule.rows()),
                          *(ca.vec(ca.SX(e)) for e, _, _ in problem.structural), *objective)
        # design variable k is read when a coordinate the NLP reads moves with it: (J^-1)[j, k] != 0 for such a j
        # (Grashof coordinates mix the lengths)
        read = [bool(ca.depends_on(rows, problem.x[j])) for j in range(n)]
        inverse = np.linalg.pinv(np.asarray(J, float))
        ignored = [names[k] for k in range(n)
                   if box[k] > 0 and not any(read[j] and abs(inverse[j, k]) > 1e-12 for j in range(n))]
        if ignored:
            raise SpecError(f"{self.kind_name}: a [tolerance] table in `solve` cannot hold the tolerance of "
                            f"{', '.join(ignored)}: this kind's NLP takes a fixed variable as a number; give it as "
                            f"{{init = v, bounds = [v, v]}} to tolerance it (`agrisynth tolerance RESULT` analyses "
                            f"fixed dimensions as they are)")
        return Tolerance(n, box, J, dmap.moves if dmap.followers else None)


@dataclasses.dataclass(frozen=True)
class RobustBuild:
    """The kind's build with its problems held in the spec's tolerance box (``Setting.tolerance``)."""

    base: object
    kind: Kind

    def __call__(self, setting: Setting, elastic: bool = False):
        expected = list(describe(setting.spec))
        try:
            nlp = self.base(dataclasses.replace(setting, tolerance=_Resolver(self.kind, setting.spec)), elastic)
            # the kind's whole problem, as built here in the box (a reduced form it solves first dropped)
            whole_problem(nlp)
        except PinningError as exc:     # structural rows that do not pin the NLP's other variables
            raise SpecError(f"{self.kind.name}: a [tolerance] table in `solve` is not supported for this kind "
                            f"yet ({exc}); `agrisynth tolerance RESULT` analyses a solved design") from None
        if spec_keys(list(nlp.names), describe(setting.spec)) != expected:
            # the box is sized and ordered by the spec's design variables: a kind whose NLP works in other
            # variables (a subset, nominal units) cannot take it yet
            raise SpecError(f"{self.kind.name}: a [tolerance] table in `solve` is not supported for this kind yet "
                            f"(its NLP variables {list(nlp.names)} are not the spec's {expected}); "
                            f"`agrisynth tolerance RESULT` analyses a solved design")
        return nlp


def _follows(dmap: DesignMap, box) -> dict:
    """result.json ``facts.tolerance.follows`` where the box moves a variable only with others (its ``box`` entry is
    how far they move it): variable -> {other: d variable / d other}; nothing where the box moves no such variable."""
    follows = dmap.moved_followers(box)
    return {"follows": follows} if follows else {}


def _box_outside(spec, dmap: DesignMap, design: dict, box) -> str | None:
    """Why the answer's box reaches beyond a limit the spec holds a variable to (> 0, >= 0, an acute angle's (0, 90)),
    in :func:`~synthesis.tolerance.design.refuse_crossing_zero`'s words; None when it stays inside."""
    try:
        refuse_crossing_zero(spec, dmap, design, box)
    except SpecError as exc:
        return str(exc).removeprefix("tolerance: ")
    return None


@dataclasses.dataclass(frozen=True)
class RobustFinish:
    base: object
    kind: Kind

    def __call__(self, setting: Setting, best) -> Finished:
        # a signal inside the kind's finish or the linearisation below is obeyed once it is done: raised inside a
        # CasADi call it came out as a NotImplementedError traceback ("wrong number or type of arguments")
        with interrupt.deferred():
            finished = self.base(setting, best)
        spec, tol = setting.spec, setting.spec.tolerance
        facts = dict(finished.facts)
        if best.satisfied:
            info = describe(spec)
            names = list(info)
            n = len(names)
            dmap = DesignMap(names, names, [info[k]["unit"] or self.kind.design_unit for k in names],
                             np.zeros(n), np.eye(n), followers_of(self.kind.follows, names))
            box = box_of(dmap, tol.length, tol.angle, dict(tol.variables))
            design = {k: float(best.outcome.design[k]) for k in names}
            # a signal noted since the starts finished (swallowed inside a CasADi call) stops the run here, before
            # the check of its answer, as one arriving in the check does (monte_carlo obeys it between samples)
            interrupt.check()
            if interrupt.pending() is not None:
                # the interrupted run's result (written under a deferral): it keeps its starts now, within seconds of
                # the signal, without the Monte-Carlo or the worst-case rows (a linearisation); the resumed run
                # checks its answer in full
                mc = {"samples": 0, "seed": tol.seed, "distribution": "not run: the solve was interrupted; "
                      "`agrisynth solve SPEC --resume RUN_DIR` finishes the run, this check with it", "pass_rate": None, "rules": {}}
                facts["tolerance"] = {"box": {k: float(b) for k, b in zip(names, dmap.spread(box))}, **_follows(dmap, box),
                                      "monte_carlo": mc, "held_at": "not checked: the solve was interrupted"}
                return dataclasses.replace(finished, facts=facts)
            outside = _box_outside(spec, dmap, design, box)
            # samples beyond a limit the spec holds a variable to are no designs of it: counted, they could pass
            mc = ({"samples": 0, "seed": tol.seed, "distribution": f"not run: {outside}", "pass_rate": None,
                   "rules": {}} if outside is not None
                  else monte_carlo(self.kind, spec, design, dmap, box, tol.samples, tol.seed))
            # the linearisation reads the rules at the answer: its design and whatever else it holds that the NLP's
            # auxiliaries are (the crank angles of its targets, say: KindNLP.answer_start)
            design = {**best.outcome.details, **best.outcome.design, **design}
            facts["tolerance"] = {"box": {k: float(b) for k, b in zip(names, dmap.spread(box))}, **_follows(dmap, box),
                                  "monte_carlo": mc, "held_at": "linearised worst case of every rule row in the box"}
            # the promise of a robust solve, checked on the answer: every rule at its linearised worst case
            # in the box (exact derivatives, the analysis grid); a miss makes the run "failed" (core)
            with interrupt.deferred():
                worst = _worst_case_records(self.kind, spec, design, box, {r.name: r.unit for r in best.records})
            # the sampled misses are news only when the linearised worst case holds: where it does not, the run has
            # failed and its note says so
            note = _sampled_misses(mc, worst) if all(w["satisfied"] for w in worst) else None
            return dataclasses.replace(finished, facts=facts, rules=[r.to_json() for r in best.records] + worst,
                                       note=note)
        return dataclasses.replace(finished, facts=facts)


def _sampled_misses(mc: dict, worst: list[dict] = ()) -> str | None:
    """The note of a robust answer whose Monte-Carlo check found designs that miss a rule although every rule holds at
    its linearised worst case (the model is not linear); None when every sample passed or none was drawn.  A rule's
    pass rate counts the samples the re-check could not evaluate at all (``unevaluable``) as misses of every rule, so
    the rules named are those missed in evaluated samples, and the unevaluable samples are said apart."""
    corners = [w["name"].removesuffix("@tolerance") for w in worst if "the rule curves beyond it" in (w["note"] or "")]
    at_corner = (f" Re-checked at its linear worst corner of the box, {', '.join(corners)} "
                 f"{'misses' if len(corners) == 1 else 'miss'} (the rows say by how much): the linear worst case is "
                 f"what the solve holds, and the rule curves beyond it." if corners else "")
    samples = int(mc.get("samples") or 0)
    rate = mc.get("pass_rate")
    if rate is None or not samples:
        return at_corner.strip() or None
    failing = samples - round(rate * samples)
    if failing <= 0:
        return at_corner.strip() or None
    unevaluable = int(mc.get("unevaluable") or 0)
    missed = [name for name, r in (mc.get("rules") or {}).items()
              if samples - round((r.get("pass_rate") or 0.0) * samples) - unevaluable > 0]
    what = [f"{failing} of {samples} Monte-Carlo samples in the tolerance box miss a rule"]
    if "envelope" in mc:
        what.append(" at the nominal operating point or at a point of the operating range's re-check grid")
    if missed:
        what.append(f" ({', '.join(missed)})")
    if unevaluable:
        what.append(f"{';' if missed else ':'} {unevaluable} of them could not be evaluated at all")
    held = "at the operating points the NLP samples, " if "envelope" in mc else ""
    return ("".join(what) + f". The solve holds every rule at its linearised worst case in the box, {held}which does "
            f"not cover every sampled design (`agrisynth tolerance RESULT` analyses this answer)." + at_corner)


def _worst_case_records(kind: Kind, spec, design: dict, box: np.ndarray, units: dict[str, str]) -> list[dict]:
    """One rule row per rule: its linearised worst-case margin in the tolerance box (>= 0 holds).  ``units``: the
    re-check's unit of each rule; a rule the NLP writes in other terms (a curvature for a radius: unit "1" for mm)
    is linearised in the NLP's, and its row says so: same sign, not the same number."""
    # a rule whose NLP rows are the rule itself (an exact minimum over a turn, each branch of a max()) is read on
    # them, as the NLP held it (stack_up, Linearised.held): its sampled values linearise otherwise
    # (a finger's clearance from the other unit's: -9.5e-6 mm at its samples, +1e-6 on its exact row, +1.2e-5 at the
    # box's worst corner)
    lin = linearise(kind, spec, design)
    if list(lin.dmap.keys) != list(describe(spec)):     # the box is in the spec's order (RobustBuild checks the NLP)
        raise SpecError(f"{kind.name}: the analysis variables {lin.dmap.keys} are not the spec's {list(describe(spec))}")
    rows = []
    stacked = stack_up(lin, np.asarray(box, float))
    # each rule re-checked at its linear worst corner, a design in the box: where it misses there although its
    # linear worst case holds, the row says so (the promise is the linear one; the rule curves over the box)
    corner_margins(kind, spec, lin.design, lin.dmap, stacked)
    for row in stacked:
        margin = row["linear_worst_margin"]
        finite = bool(np.isfinite(margin))
        rows.append({"name": f"{row['name']}@tolerance", "value": margin if finite else None, "limit": [0.0, None],
                     "unit": row["unit"], "satisfied": finite and margin >= -1e-9 * row["scale"],
                     "margin": margin if finite else None,
                     "normalised_margin": margin / row["scale"] if finite else None,
                     "where": "linearised worst case in the tolerance box",
                     "note": _row_note(row, units.get(row["name"], row["unit"]), finite and margin >= 0)})
    return rows


def _row_note(row: dict, recheck_unit: str, holds: bool) -> str | None:
    """A worst-case row's caveats: linearised in the solver's terms; missed at its own linear worst corner."""
    notes = []
    if recheck_unit != row["unit"]:
        notes.append(f"linearised in the solver's form of the rule (unit {row['unit']!r}), not in the re-check's "
                     f"{recheck_unit}: its sign is the verdict, its size is not in {recheck_unit}")
    corner = row.get("corner_margin")
    if holds and corner is not None and corner < 0:
        notes.append(f"re-checked at that corner of the box the rule misses by {-corner:.4g} {recheck_unit}: the "
                     f"linear worst case holds, the rule curves beyond it")
    return "; ".join(notes) or None


def _equalities_only(rule) -> bool:
    rows = list(rule.box_rows or rule.rows())      # in the box, the rows the robust transcription holds
    return bool(rows) and all(lb is not None and ub is not None and np.all(np.asarray(lb) == np.asarray(ub))
                              for _, lb, ub in rows)


def breaking_rules(kind: Kind, spec, design: dict, *, first: tuple = ()) -> list[dict]:
    """The rules the spec's tolerance box breaks at ``design``, from the linearised stack-up (exact derivatives, the
    analysis grid): every rule whose linear worst-case margin in the box is below 0, those named in ``first`` (e.g.
    the elastic re-solve's relaxed rules) first, then by normalised worst margin.  Each with its nominal margin,
    its loss to the tolerances (sum_i |dg/dx_i| tol_i), every variable's share, the shares of all lengths / all
    angles, and the linear estimate of the largest uniform scale of the box that holds it at this design
    (nominal margin / loss; 0 when the rule misses even at the nominal design)."""
    tol = spec.tolerance
    lin = linearise(kind, spec, design)
    box = box_of(lin.dmap, tol.length, tol.angle, dict(tol.variables))
    units = dict(zip(lin.dmap.keys, lin.dmap.units))
    widths = dict(zip(lin.dmap.keys, box))
    # a rule whose NLP rows are all equalities (a crank-rocker's time ratio and rocker swing) is held at the nominal
    # design only: the robust transcription cannot hold an equality at a worst case, so it breaks nothing there
    nominal_only = {r.name for r in lin.rules if _equalities_only(r)}
    out = []
    for row in stack_up(lin, box):
        worst = row["linear_worst_margin"]
        if row["name"] in nominal_only or not np.isfinite(worst) or worst >= -1e-9 * (row["scale"] or 1.0):
            continue
        shares = sorted(((k, abs(c)) for k, c in row["contributions"].items() if c), key=lambda kc: -kc[1])
        loss = float(sum(c for _, c in shares))
        nominal = worst + loss
        by_unit = {u: float(sum(c for k, c in shares if units[k] == u)) for u in ("mm", "deg")}
        out.append({"rule": row["name"], "unit": row["unit"], "scale": row["scale"], "linear_worst_margin": worst,
                    "nominal_margin": nominal, "loss": loss,
                    "contributions": [{"variable": k, "half_width": float(widths[k]), "unit": units[k],
                                       "contribution": c} for k, c in shares],
                    "by_unit": by_unit,
                    "linear_scale": (nominal / loss if nominal > 0 and loss > 0 else 0.0)})
    out.sort(key=lambda r: (r["rule"] not in first, r["linear_worst_margin"] / (r["scale"] or 1.0)))
    return out


def breaking_text(rows: list[dict], where: str, spec, shown: int = 3) -> str | None:
    """The exit-3 words of :func:`breaking_rules`: the rule, by how much its worst case misses, the tolerances that
    contribute most, and the linear estimate of the largest uniform scale of the box that can be met."""
    if not rows:
        return None
    parts = []
    for r in rows[:shown]:
        u = "" if r["unit"] in ("", "-") else " " + r["unit"]
        if r["nominal_margin"] < 0:
            parts.append(f"{r['rule']}@tolerance: misses its limit by {-r['nominal_margin']:.3g}{u} at the nominal "
                         f"design already (no tolerance box holds it at this design)")
            continue
        top = ", ".join(f"{c['variable']} ±{c['half_width']:g} {c['unit']} ({c['contribution']:.3g}{u})"
                        for c in r["contributions"][:3])
        units = "; ".join(f"all {'lengths' if k == 'mm' else 'angles'} {v:.3g}{u}" for k, v in r["by_unit"].items() if v)
        parts.append(f"{r['rule']}@tolerance: its worst case misses by {-r['linear_worst_margin']:.3g}{u} (nominal "
                     f"margin {r['nominal_margin']:.3g}{u}, lost to the tolerances {r['loss']:.3g}{u}); largest "
                     f"contributions: {top}" + (f"; by unit: {units}" if units else ""))
    text = f"The tolerances that break them (linearised stack-up at {where}): " + "; ".join(parts) + "."
    held = [r for r in rows if r["nominal_margin"] >= 0]
    if held and len(held) == len(rows):
        k = min(r["linear_scale"] for r in held)
        present = {c["unit"] for r in rows for c in r["contributions"]}    # the units the box gives a width to
        box = _box_text(spec, k, present)
        text += (f" Linear estimate (at this design, not a solve): the box scaled by {k:.2g} ({box}) is the largest "
                 f"uniform scale these rules can be held at.")
    return text


@dataclasses.dataclass(frozen=True)
class ExplainBreak:
    """``Solving.explain_failure`` of a robust solve: which tolerance breaks which rule (:func:`breaking_rules`), at
    the elastic re-solve's design when it converged, else at the best start's."""

    kind: Kind
    spec: object

    def __call__(self, result) -> str | None:
        elastic = result.elastic or {}
        names = list(describe(self.spec))
        use_elastic = bool(elastic.get("converged")) and isinstance(elastic.get("design"), dict)
        # the answer's auxiliaries too, as KindNLP.answer_start reads them (the crank angles of its targets, say)
        source = {**self.kind.answer_details(result), **dict(result.design or {})}
        if use_elastic:         # the elastic design's own dimensions; the best start's list values are not its
            for name in describe_lists(self.spec):
                source.pop(name, None)
            source.update({k: v for k, v in elastic["design"].items() if v is not None})
        try:
            design = {**source, **{k: float(source[k]) for k in names}}
            rows = breaking_rules(self.kind, self.spec, design, first=tuple(elastic.get("relaxed") or ()))
        except (KeyError, TypeError, AgrisynthError, ValueError, ArithmeticError, RuntimeError) as exc:
            return f"(Which tolerance breaks which rule could not be worked out: {type(exc).__name__}: {exc}.)"
        where = "the elastic re-solve's design" if use_elastic else "the best start's design"
        return breaking_text(rows, where, self.spec)


def robust_kind(kind: Kind, spec) -> Kind:
    """The kind, solving with the spec's ``[tolerance]`` box (the kind itself when the spec has none)."""
    if getattr(spec, "tolerance", None) is None:
        return kind
    if kind.robust_refusal is not None:
        raise SpecError(f"tolerance: a [tolerance] table in `solve` is not supported for kind {kind.name} "
                        f"({kind.robust_refusal}); leave it out to solve, and analyse the solved design with "
                        f"`agrisynth tolerance RESULT`")
    base = kind.solving()
    hint = (f"The rules are held at their linearised worst case in the tolerance box ({_box_text(spec)}): "
            f"loosen the tolerances of the [tolerance] table, or those rules. ")
    solving = dataclasses.replace(base, build=RobustBuild(base.build, kind), finish=RobustFinish(base.finish, kind),
                                  relax_hint=hint + base.relax_hint, explain_failure=ExplainBreak(kind, spec))

    return kind.solving_with(solving)
