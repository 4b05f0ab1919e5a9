"""Workshop files of a rotary_planetary result, from result.json's design alone (the pitch curves follow from it in
closed form: nothing is solved again).

pitch_curves.csv  over one carrier turn (0 to 360 deg, both ends: each curve's first and last rows are the same
                  point), for each meshing pair k = 1 (sun -> idler gear 1), 2 (idler gear 2 -> planet): the
                  driver's and the driven gear's pitch point in polar form in the gear's own frame (deg, mm; angles
                  continuous, not wrapped) and the centre distance
pitch_curves.dxf  the four pitch curves in mesh at carrier angle 0 (sun at the origin, machine frame), with a centre
                  mark on each gear's axis and the carrier line
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from synthesis.kinds.rotary_planetary.kinematics import pairs, planet_law, idler_law, train_from_design
from synthesis.report import exports
from synthesis.result import Result

#: rows of pitch_curves.csv: every 0.1 deg of carrier angle, 0 and 360 both written
CSV_SAMPLES = 3601
#: decimals in pitch_curves.csv: fine enough that arc lengths read back agree to 1e-9 relative
CSV_DIGITS = 12


def pitch_curve_columns(design: dict, samples: int = CSV_SAMPLES) -> dict[str, np.ndarray]:
    train = train_from_design(design)
    phi = np.linspace(0.0, 2.0 * math.pi, samples)
    columns: dict[str, np.ndarray] = {"carrier_deg": np.degrees(phi)}
    for k, pair in enumerate(pairs(train, phi), start=1):
        for role, curve in (("driver", pair.driver), ("driven", pair.driven)):
            columns[f"pair{k}_{role}_deg"] = np.degrees(curve.angle[0])
            columns[f"pair{k}_{role}_radius_mm"] = np.asarray(curve.radius[0], dtype=float)
        columns[f"pair{k}_centre_distance_mm"] = np.full(samples, float(pair.centre_distance))
    return columns


def write_pitch_curves_csv(result: Result, path: Path) -> None:
    # as lists, the column type write_csv takes: the same float64 values, written alike
    columns = {name: values.tolist() for name, values in pitch_curve_columns(result.design).items()}
    exports.write_csv(path, columns, digits=CSV_DIGITS)


def _placed(angle_deg, radius, centre, turn: float) -> list[tuple[float, float]]:
    """A pitch curve's points in the machine frame: the gear's frame turned by ``turn`` rad about ``centre``."""
    a = np.radians(angle_deg) + turn
    return list(zip(centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)))


def write_pitch_curves_dxf(result: Result, path: Path) -> None:
    d = result.design
    train = train_from_design(d)
    c = pitch_curve_columns(d, 721)
    a1, a2 = float(d["centre_distance_1"]), float(d["centre_distance_2"])
    sun, idler, planet = (0.0, 0.0), (a1, 0.0), (a1 + a2, 0.0)
    # at carrier angle 0 the idler has turned G(0), the planet F(0) relative to the carrier (NOTES.md)
    g0, f0 = float(idler_law(train, 0.0)), float(planet_law(train, 0.0))
    curves: dict[str, Sequence[Sequence[Sequence[float]]]] = {
        "SUN": [_placed(c["pair1_driver_deg"], c["pair1_driver_radius_mm"], sun, 0.0)],
        "IDLER_1": [_placed(c["pair1_driven_deg"], c["pair1_driven_radius_mm"], idler, g0)],
        "IDLER_2": [_placed(c["pair2_driver_deg"], c["pair2_driver_radius_mm"], idler, g0)],
        "PLANET": [_placed(c["pair2_driven_deg"], c["pair2_driven_radius_mm"], planet, f0)]}
    exports.write_linkage_dxf(
        path, {"O": sun, "A": idler, "B": planet}, ground=("O", "A", "B"), links=(("O", "A"), ("A", "B")),
        curves=curves, closed=tuple(curves),
        note=f"{result.name}: pitch curves in mesh at carrier angle 0; O sun (fixed), A idler, B planet; mm")
