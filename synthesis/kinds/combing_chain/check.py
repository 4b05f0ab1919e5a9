"""``agrisynth check`` for kind combing_chain: the given chain speed(s) against every rule, and the facts the
report draws (corners, the plant lengths that fit, delta over beta, Table 13 as printed against ours).

One rule function (:func:`rules_of`) serves check, the NLP and the fine-grid re-check: it reads a
:class:`Trace`, the plant angles before the cut sampled on a (beta, V_s) grid per gear, built on floats
or CasADi symbols by :func:`trace`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from synthesis.constraints import Rule
from synthesis.kinds.combing_chain.rules import tine_reaches_plant_rule, window_bottom_rule, window_top_rule
from synthesis.kinds.combing_chain import geometry as g
from synthesis.core.kind import figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.combing_chain.spec import CombingChainSpec

#: samples of the check grid per dimension (the re-check of a solve uses FINE x the solver's samples)
CHECK_BETA_SAMPLES = 181
CHECK_SPEED_SAMPLES = 51
#: Table 13 prints delta to the degree and t to 0.01 s from speeds printed to 0.01 m/s: a printed figure
#: is reproduced when ours lies within these (problems/combing_chain/CHAIN.md, "Tolerances")
TOLERANCE = {"delta": 1.5, "time": 0.01}
UNITS = {"delta": "deg", "time": "s"}


@dataclass
class GearTrace:
    """One chain gear on the grid: its speed, the machine speeds it serves and delta[i][j] at (beta_i, V_s_j)."""

    index: int
    chain_speed: Any
    machine_speeds: list
    delta: list                  # rows over beta, columns over the gear's machine speeds
    label_lo: str                # how the rules' `where` calls the ends of its machine-speed range
    label_hi: str


@dataclass
class Trace:
    betas: np.ndarray
    gears: list[GearTrace]


def gear_ranges(spec: CombingChainSpec, design: dict, machine_speed: tuple | None = None) -> list[tuple[Any, Any]]:
    """(lo, hi) machine speeds each gear serves at ``design`` (floats or symbols); ``machine_speed`` replaces the
    spec's range (its ends as symbols: the tolerance analysis's build)."""
    vlo, vhi = spec.operation.machine_speed if machine_speed is None else machine_speed
    if spec.gears == 1 or spec.chain.switch_speed is None:
        return [(vlo, vhi)] * spec.gears
    sw = design["switch_speed"]
    return [(vlo, sw), (sw, vhi)]


def _labels(spec: CombingChainSpec, gear: int) -> tuple[str, str]:
    vlo, vhi = spec.operation.machine_speed
    sw = spec.chain.switch_speed
    if sw is None or spec.gears == 1:
        return f"{vlo:g}", f"{vhi:g}"
    # "switch" whether the switch speed is free or fixed: a rule keeps its name from the solve to the check of its
    # solved.toml (where the solved switch speed is a fixed number); the rule's `where` gives the speed
    sw_label = "switch"
    return (f"{vlo:g}", sw_label) if gear == 0 else (sw_label, f"{vhi:g}")


def trace(spec: CombingChainSpec, design: dict, beta_samples: int, speed_samples: int,
          operation: dict | None = None) -> Trace:
    """delta on the (beta, V_s) grid of every gear at ``design`` (chain speeds, switch speed: floats or symbols).

    ``operation`` (the tolerance analysis's build) gives the ends of the machine-speed and plant-angle ranges as
    CasADi symbols, ``{"machine_speed": (lo, hi), "plant_angle": (lo, hi)}``, so the rules have derivatives w.r.t.
    them; the grid is then written as lo + (hi - lo) i / (n - 1), the numbers' linspace to rounding."""
    c = spec.chain
    betas: Any          # an array of floats, or with the operating range's symbols a list of CasADi expressions
    if operation is None:
        betas = np.linspace(*spec.operation.plant_angle, beta_samples)
        ranges = gear_ranges(spec, design)
    else:
        b_lo, b_hi = operation["plant_angle"]
        betas = [b_lo + (b_hi - b_lo) * (i / max(beta_samples - 1, 1)) for i in range(beta_samples)]
        ranges = gear_ranges(spec, design, operation["machine_speed"])
    gears = []
    for k, ((lo, hi), name) in enumerate(zip(ranges, spec.speed_names())):
        vr = design[name]
        speeds = [lo + (hi - lo) * (j / (speed_samples - 1)) for j in range(speed_samples)]
        delta = [[g.delta(vr, vs, c.h, c.theta, c.e, b if operation else float(b)) for vs in speeds] for b in betas]
        gears.append(GearTrace(k, vr, speeds, delta, *_labels(spec, k)))
    return Trace(betas, gears)


def _speed(label: str, value) -> str:
    """A range end in a rule's words: its number when it is one ("switch 0.498"), its label when it is a symbol."""
    if not isinstance(value, (int, float)):
        return label
    return f"switch {value:g}" if label == "switch" else f"{value:g}"


def rule_prefix(spec: CombingChainSpec, gear: int) -> str:
    return "" if spec.gears == 1 else f"gear{gear + 1}_"


def rules_of(spec: CombingChainSpec, tr: Trace) -> list[Rule]:
    """Every rule on a trace of floats or CasADi symbols.  delta falls with the chain travel
    s = V_r (e + h cot beta) / V_s, so over a gear's grid it is largest at the most upright-or-back plant and
    the fastest machine (beta_hi, V_s hi) and smallest at (beta_lo, V_s lo): the window rules name
    those corners in their ``where`` (the re-check confirms where the worst sample lies); their names are the
    requirement's alone (window_top, window_bottom), the same whatever the spec's ranges, so that two designs
    compare row by row."""
    c, window = spec.chain, spec.requirements.window
    b_lo, b_hi = spec.operation.plant_angle
    cos_t = math.cos(math.radians(c.theta))
    rules: list[Rule] = []
    for gt in tr.gears:
        pre = rule_prefix(spec, gt.index)
        lo_text, hi_text = _speed(gt.label_lo, gt.machine_speeds[0]), _speed(gt.label_hi, gt.machine_speeds[-1])
        span = f"V_s {lo_text}-{hi_text} m/s"
        rules.append(tine_reaches_plant_rule(f"{pre}tine_reaches_plant", [gt.chain_speed - vs * cos_t
                                                                          for vs in gt.machine_speeds],
                                             f"V_r - V_s cos(theta) at every {span}"))
        if window is None:
            continue
        flat = [d for row in gt.delta for d in row]
        where = f"every beta {b_lo:g}-{b_hi:g} deg at every {span}"
        rules.append(window_top_rule(f"{pre}window_top", flat, window[1],
                                     f"{where}; largest at beta {b_hi:g} deg, V_s {hi_text} m/s"))
        rules.append(window_bottom_rule(f"{pre}window_bottom", flat, window[0],
                                        f"{where}; smallest at beta {b_lo:g} deg, V_s {lo_text} m/s"))
    return rules


def evaluate(spec: CombingChainSpec, design: dict, beta_samples: int = CHECK_BETA_SAMPLES,
             speed_samples: int = CHECK_SPEED_SAMPLES) -> tuple[list[Rule], Trace]:
    tr = trace(spec, design, beta_samples, speed_samples)
    return rules_of(spec, tr), tr


# ---- facts ------------------------------------------------------------------------------------------------

def point(spec: CombingChainSpec, beta: float, machine_speed: float, chain_speed: float) -> dict:
    """Everything eq 12-13 say about one plant at one operating point."""
    c = spec.chain
    s = float(g.chain_travel(chain_speed, machine_speed, c.h, c.e, beta))
    x, y = g.tine_at_cut(s, c.h, c.theta, c.e)
    return {"beta_deg": beta, "machine_speed": machine_speed, "chain_speed": chain_speed,
            "K": chain_speed / machine_speed, "root_lead_mm": float(g.root_lead(c.h, c.e, beta)),
            "time_s": float(g.time_to_cut(c.h, c.e, beta, machine_speed)), "chain_travel_mm": s,
            "tine_at_cut_mm": [float(x), float(y)], "delta_deg": float(g.delta_of_travel(s, c.h, c.theta, c.e)),
            "plant_length_mm": float(g.plant_length(s, c.h, c.theta, c.e))}


def gear_facts(spec: CombingChainSpec, design: dict, tr: Trace) -> list[dict]:
    c = spec.chain
    out = []
    for gt, (lo, hi) in zip(tr.gears, gear_ranges(spec, design)):
        lo, hi, vr = float(lo), float(hi), float(gt.chain_speed)
        d = np.asarray(gt.delta, dtype=float)
        s = np.array([[float(g.chain_travel(vr, vs, c.h, c.e, float(b))) for vs in gt.machine_speeds]
                      for b in tr.betas])
        length = g.plant_length(s, c.h, c.theta, c.e)
        i_max, i_min = np.unravel_index(np.argmax(d), d.shape), np.unravel_index(np.argmin(d), d.shape)
        b_lo, b_hi = spec.operation.plant_angle
        out.append({
            "gear": gt.index + 1, "chain_speed": vr, "machine_speed": [lo, hi], "K": [vr / hi, vr / lo],
            "delta_deg": {"min": float(d.min()), "max": float(d.max()),
                          "min_at": {"beta_deg": float(tr.betas[i_min[0]]), "machine_speed": float(gt.machine_speeds[i_min[1]])},
                          "max_at": {"beta_deg": float(tr.betas[i_max[0]]), "machine_speed": float(gt.machine_speeds[i_max[1]])}},
            "plant_length_mm": {"min": float(length.min()), "max": float(length.max())},
            "corners": [point(spec, b, vs, vr) for b in (b_lo, b_hi) for vs in (lo, hi)],
        })
    return out


def closed_form(spec: CombingChainSpec, design: dict) -> dict | None:
    """The design question answered by the printed inverse of eq 12 (K from delta), no optimiser: a gear
    serving V_s in [a, b] keeps every plant in the window iff its chain speed lies in
    [b K(beta_hi, delta_hi), a K(beta_lo, delta_lo)]."""
    if spec.requirements.window is None:
        return None
    c = spec.chain
    (b_lo, b_hi), (d_lo, d_hi) = spec.operation.plant_angle, spec.requirements.window
    inf, sup = g.delta_limits(c.h, c.theta, c.e)
    # a window edge beyond what any chain speed reaches does not bound K (None: unbounded, never inf in JSON)
    k_top = g.K_for_delta(d_hi, c.h, c.theta, c.e, b_hi) if d_hi < sup else 0.0
    k_bot = g.K_for_delta(d_lo, c.h, c.theta, c.e, b_lo) if d_lo > inf else None

    def interval(lo: float, hi: float) -> tuple[list, bool]:
        top = None if k_bot is None else lo * k_bot
        return [hi * k_top, top], top is None or hi * k_top <= top

    vlo, vhi = spec.operation.machine_speed
    gears = []
    for (lo, hi), name in zip(gear_ranges(spec, design), spec.speed_names()):
        span, ok = interval(float(lo), float(hi))
        gears.append({"gear": name, "machine_speed": [float(lo), float(hi)], "chain_speed_interval": span,
                      "feasible": ok})
    one, one_ok = interval(vlo, vhi)
    return {"K_min_for_window_top": k_top, "K_max_for_window_bottom": k_bot,
            "one_gear_chain_speed_interval": one, "one_gear_feasible": one_ok,
            "widest_machine_speed_ratio_per_gear": None if k_bot is None or k_top <= 0 else k_bot / k_top,
            "gears": gears}


def curves(spec: CombingChainSpec, design: dict, samples: int = 121) -> dict:
    """delta and L (eq 13) over beta at the ends and middle of each gear's machine speeds (Fig. 23 as curves)."""
    c = spec.chain
    betas = np.linspace(*spec.operation.plant_angle, samples)
    series = []
    for k, ((lo, hi), name) in enumerate(zip(gear_ranges(spec, design), spec.speed_names())):
        vr = float(design[name])
        for vs in sorted({float(lo), 0.5 * (float(lo) + float(hi)), float(hi)}):
            s = g.chain_travel(vr, vs, c.h, c.e, betas)
            series.append({"gear": k + 1, "chain_speed": vr, "machine_speed": vs,
                           "delta_deg": g.delta_of_travel(s, c.h, c.theta, c.e).tolist(),
                           "plant_length_mm": g.plant_length(s, c.h, c.theta, c.e).tolist()})
    return {"beta_deg": betas.tolist(), "series": series}


def _ours(spec: CombingChainSpec, quantity: str, beta: float, machine_speed: float, chain_speed: float | None) -> float:
    c = spec.chain
    if quantity == "time":
        return float(g.time_to_cut(c.h, c.e, beta, machine_speed))
    return float(g.delta(chain_speed, machine_speed, c.h, c.theta, c.e, beta))


def published_facts(spec: CombingChainSpec, design: dict) -> list[dict]:
    """Each printed figure of the spec: ours at the operating point it is read at, the difference, and
    what the machine can attain at that beta at all (every machine speed of its range, every gear),
    with ours at every pairing of the printed machine speeds and chain speeds."""
    vlo, vhi = spec.operation.machine_speed
    chain_speeds = sorted({float(design[n]) for n in spec.speed_names()})
    rows = []
    for p in spec.published:
        ours = _ours(spec, p.quantity, p.beta, p.machine_speed, p.chain_speed)
        tol = TOLERANCE[p.quantity]
        pairs = [(vs, vr) for vs in (vlo, vhi) for vr in (chain_speeds if p.quantity == "delta" else [None])]
        at_pairs: list[dict[str, Any]] = [
            {"machine_speed": vs, "chain_speed": vr, "ours": _ours(spec, p.quantity, p.beta, vs, vr)}
            for vs, vr in pairs]
        values = [a["ours"] for a in at_pairs]       # extremes over the operating set: at its corners (monotone)
        lo, hi = min(values), max(values)
        reproduced = abs(ours - p.value) <= tol
        if reproduced:
            note = "reproduced"
        elif not lo - tol <= p.value <= hi + tol:
            note = (f"not reproduced: {p.value:g} {UNITS[p.quantity]} lies outside what this machine attains at "
                    f"beta = {p.beta:g} deg over its whole operating range ({lo:.4g}-{hi:.4g} {UNITS[p.quantity]})")
        else:
            hits = [a for a in at_pairs if abs(a["ours"] - p.value) <= tol]
            elsewhere = ("; it is met at " + ", ".join(f"V_s {a['machine_speed']:g} m/s with V_r {a['chain_speed']:g} "
                                                       f"m/s ({a['ours']:.4g})" for a in hits)
                         + ", a pairing we do not read it at") if hits else \
                "; no pairing of the printed speeds gives it, only speeds between them"
            note = (f"not reproduced at the operating point read (ours {ours:.4g}){elsewhere} (attainable "
                    f"{lo:.4g}-{hi:.4g} {UNITS[p.quantity]})")
        rows.append({"label": p.label, "quantity": p.quantity, "unit": UNITS[p.quantity], "beta_deg": p.beta,
                     "machine_speed": p.machine_speed, "chain_speed": p.chain_speed, "published": p.value,
                     "ours": ours, "difference": ours - p.value, "tolerance": tol, "reproduced": reproduced,
                     "attainable": [lo, hi], "at_printed_speeds": at_pairs, "note": note})
    return rows


def facts(spec: CombingChainSpec, design: dict, tr: Trace) -> dict:
    c = spec.chain
    inf, sup = g.delta_limits(c.h, c.theta, c.e)
    gears = gear_facts(spec, design, tr)
    return {
        "source": spec.source,
        "frame": "x forward (travel), y up, root at the origin; beta and delta measured from the backward direction",
        "chain": {"h_mm": c.h, "theta_deg": c.theta, "e_mm": c.e},
        "operation": {"machine_speed": list(spec.operation.machine_speed),
                      "plant_angle_deg": list(spec.operation.plant_angle)},
        "window_deg": None if spec.requirements.window is None else list(spec.requirements.window),
        "delta_limits_deg": {"inf (V_r -> infinity)": inf, "sup (V_r -> 0)": sup},
        "beta_limit_deg": g.beta_limit(c.h, c.e),
        "grid": {"beta_samples": len(tr.betas), "speed_samples": len(tr.gears[0].machine_speeds)},
        "gears": gears,
        "plants_that_fit": {
            "eq13_length_mm": [min(x["plant_length_mm"]["min"] for x in gears),
                               max(x["plant_length_mm"]["max"] for x in gears)],
            "meaning": "eq 13: the length of a plant whose tip is at the tine at the cut; a plant at least the "
                       "largest of these is still held by the tine when it is cut, at every beta and V_s"},
        "closed_form": closed_form(spec, design),
        "curves": curves(spec, design),
        "published": published_facts(spec, design),
    }


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(CombingChainSpec, loaded.model)     # load_spec validated it with this kind's model
    design = spec.design_values()
    rules, tr = evaluate(spec, design)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=design,
                  rules=[r.record().to_json() for r in rules], extra=facts(spec, design, tr))


def headline(result: Result) -> list[str]:
    """Per gear: the tine's angle at the cut over the machine speeds and plant angles, and the plant lengths that
    fit; the worst tine-reaches-plant margin, from result.json facts and rules."""
    facts = result.extra or {}
    lines = []
    for gear in facts.get("gears") or []:
        if not isinstance(gear, dict):
            continue
        delta, length = gear.get("delta_deg") or {}, gear.get("plant_length_mm") or {}
        lines.append(f"gear {gear.get('gear')} (chain {figure_text(gear.get('chain_speed'), 'm/s')}): tine at the cut "
                     f"{figure_text(delta.get('min'), '')}-{figure_text(delta.get('max'), 'deg')}, plants "
                     f"{figure_text(length.get('min'), '', 4)}-{figure_text(length.get('max'), 'mm', 4)} long")
    reach = [r for r in result.rules if r["name"].endswith("tine_reaches_plant")]
    if reach:
        worst = min(reach, key=lambda r: r["margin"] if r.get("margin") is not None else -math.inf)
        lines.append(f"tine overtakes the plant by at least {figure_text(worst.get('value'), worst.get('unit', ''))}")
    return lines
