"""Workshop exports of every kind with geometry: the CSV of every traced path and the
DXF of the linkage with its traced curves, written by the kinds' figure writers from result data alone.

Each library baseline is checked in-process (well under a second each) and its exports are read back: CSV
columns and row counts against the result, DXF opened with ezdxf: layers, entity counts, joint positions and
the extents of the drawing against the linkage and the paths it must hold.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from conftest import PLANTING
from synthesis import kinds
from synthesis.spec import load_spec

ezdxf = pytest.importorskip("ezdxf")
from ezdxf import bbox  # noqa: E402

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

#: spec -> (CSV columns, DXF: layer -> number of entities of the kind named, joints drawn, ground pivots)
LINKAGES = {
    "planting_arm/taiwan_example1.toml": (
        ["t_s", "crank_deg", "machine_x_mm", "machine_y_mm", "machine_vx_mm_s", "machine_vy_mm_s", "ground_x_mm",
         "ground_y_mm", "ground_vx_mm_s", "ground_vy_mm_s", "ax_mm_s2", "ay_mm_s2"],
        {"LINKS": 6, "COUPLER": 1, "PATH_MACHINE": 1, "PATH_GROUND": 1}, {"O", "O'", "A", "B", "C"}),
    "fourbar_path/picking_arc.toml": (
        ["t_s", "crank_deg", "x_mm", "y_mm", "vx_mm_s", "vy_mm_s", "ax_mm_s2", "ay_mm_s2"],
        {"LINKS": 6, "COUPLER": 1, "PATH": 1, "TARGETS": 20}, {"O", "O'", "A", "B", "P"}),
    "picker/cai2020_crank_rocker.toml": (
        ["crank_deg", "rocker_deg", "transmission_deg", "F_x_mm", "F_y_mm", "E_x_mm", "E_y_mm"],
        {"LINKS": 4, "PATH_F": 1, "PATH_E": 1, "EXTENDED": 1}, {"G", "A", "F", "E"}),
    "picker/cai2020_double_crank.toml": (
        ["crank_deg", "x_mm", "y_mm"],
        {"LINKS": 6, "COUPLER": 1, "PATH_COUPLER": 1, "PATH_DRIVEN": 1}, {"A", "B", "C", "D", "M"}),
    "picker/cai2020_picker.toml": (
        ["t_s", "crank_gf_deg", "crank_ab_deg", "x_mm", "y_mm", "vx_mm_s", "vy_mm_s", "ax_mm_s2", "ay_mm_s2"],
        {"LINKS": 10, "COUPLER": 2, "PATH_M": 1}, {"A", "B", "C", "D", "M", "G", "F", "E"}),
    "tillage/hwang_tillage_baseline.toml": (
        ["t_s", "crank_deg", "machine_x_mm", "machine_y_mm", "ground_x_mm", "ground_y_mm", "ground_vx_mm_s",
         "ground_vy_mm_s", "ax_mm_s2", "ay_mm_s2", "bar_angle_deg"],
        {"LINKS": 2, "PATH_MACHINE": 1, "PATH_GROUND": 1, "GROUND_LINE": 1}, {"A", "B", "C", "D"}),
    "steering/hwang_model3_steering.toml": (
        ["inside_deg", "outside_deg", "ackermann_deg", "error_deg", "T_L_x_mm", "T_L_y_mm", "T_R_x_mm", "T_R_y_mm"],
        {"LINKS": 4, "LOCK": 1, "PATH_T_L": 1, "PATH_T_R": 1}, {"K_L", "T_L", "T_R", "K_R"}),
}


def _checked(spec: str):
    loaded = load_spec(PROBLEMS / spec)
    return kinds.checker(loaded.model.kind)(loaded)


def _write(result, tmp_path: Path) -> dict[str, Path]:
    writers = kinds.figure_writers(result)
    out = {}
    for name in ("paths.csv", "linkage.dxf"):
        assert name in writers, f"{result.kind} lists no {name}"
        writers[name](tmp_path / name)
        out[name] = tmp_path / name
    return out


def _csv(path: Path) -> tuple[list[str], np.ndarray]:
    header = path.read_text().splitlines()[0].split(",")
    return header, np.genfromtxt(path, delimiter=",", skip_header=1)


def _by_layer(msp, types: str) -> dict[str, list]:
    out: dict[str, list] = {}
    for e in msp.query(types):
        out.setdefault(e.dxf.layer, []).append(e)
    return out


@pytest.mark.parametrize("spec", list(LINKAGES))
def test_linkage_exports_hold_the_paths_and_the_linkage(spec, tmp_path):
    columns, layers, joint_names = LINKAGES[spec]
    result = _checked(spec)
    files = _write(result, tmp_path)

    header, rows = _csv(files["paths.csv"])
    assert header == columns
    assert rows.shape[1] == len(columns) and np.all(np.isfinite(rows))
    tr = result.trajectory
    if tr is not None:           # one row per trajectory sample, the same time and crank angle
        assert rows.shape[0] == len(tr["t"])
        assert rows[:, 0] == pytest.approx(tr["t"], abs=1e-6)
        xcol = header.index("ground_x_mm") if "ground_x_mm" in header else header.index("x_mm")
        assert rows[:, xcol] == pytest.approx(tr["x"], abs=1e-6)
    else:
        assert rows.shape[0] >= 361
    assert "crank_deg" in header or "crank_gf_deg" in header or "inside_deg" in header

    doc = ezdxf.readfile(files["linkage.dxf"])
    assert doc.header["$INSUNITS"] == 4
    msp = doc.modelspace()
    drawn = _by_layer(msp, "LINE LWPOLYLINE CIRCLE")
    for layer, count in layers.items():
        assert len(drawn.get(layer, [])) == count, (layer, {k: len(v) for k, v in drawn.items()})
    assert not [l.dxf.name for l in doc.layers if l.dxf.name not in ("0", "Defpoints") and l.dxf.name not in drawn
                and l.dxf.name != "LABELS"], "a layer without entities"
    labels = {t.dxf.text for t in msp.query("TEXT") if " " not in t.dxf.text}
    assert labels == joint_names
    # every joint letter sits beside a joint circle (ground pivots on GROUND, the others on JOINTS)
    centres = np.array([(c.dxf.center.x, c.dxf.center.y) for c in msp.query("CIRCLE")])
    for t in msp.query("TEXT"):
        if " " not in t.dxf.text:
            assert np.min(np.hypot(*(centres - np.array((t.dxf.insert.x, t.dxf.insert.y))).T)) < 0.1 * np.ptp(centres) + 10
    # the link labels carry the link lengths: each LINKS line's length is written on LABELS
    lengths = {round(math.dist((l.dxf.start.x, l.dxf.start.y), (l.dxf.end.x, l.dxf.end.y)), 2) for l in drawn["LINKS"]}
    written = {float(t.dxf.text.split()[-1]) for t in msp.query("TEXT") if "-" in t.dxf.text.split()[0]}
    assert lengths <= {round(v, 2) for v in written}
    # extents of the geometry (text aside): the paths and the linkage, no stray far-away entity
    box = bbox.extents(msp.query("LINE LWPOLYLINE CIRCLE"))
    paths = np.vstack([np.array(p.get_points("xy")) for layer, es in drawn.items() if layer.startswith("PATH")
                       for p in es])
    lo, hi = paths.min(axis=0), paths.max(axis=0)
    assert box.extmin.x <= lo[0] + 1e-6 and box.extmin.y <= lo[1] + 1e-6
    assert box.extmax.x >= hi[0] - 1e-6 and box.extmax.y >= hi[1] - 1e-6
    span = max(box.size.x, box.size.y)
    assert span < 3 * max(np.ptp(np.vstack([paths, centres]), axis=0))


def test_steering_tie_rod_ends_reach_the_lock_position(tmp_path):
    """The exported tie-rod end paths are the straight-ahead arms turned by the wheel angles: at the maximum
    inside lock they end on the result's own position at that lock, to 1e-6 mm."""
    result = _checked("steering/hwang_model3_steering.toml")
    header, rows = _csv(_write(result, tmp_path)["paths.csv"])
    lock = result.extra["positions"][-1]
    last = rows[np.argmin(abs(rows[:, 0] - lock["inside_deg"]))]
    assert last[0] == pytest.approx(lock["inside_deg"])
    assert [last[header.index(c)] for c in ("T_L_x_mm", "T_L_y_mm", "T_R_x_mm", "T_R_y_mm")] == pytest.approx(
        [*lock["T_L"], *lock["T_R"]], abs=1e-6)
    # and the tie rod keeps its length all the way
    tie = np.hypot(rows[:, header.index("T_L_x_mm")] - rows[:, header.index("T_R_x_mm")],
                   rows[:, header.index("T_L_y_mm")] - rows[:, header.index("T_R_y_mm")])
    assert tie == pytest.approx(result.extra["tie_rod_length_mm"], abs=1e-6)


def test_cam_csv_has_angles_radii_motion_and_the_dxf_a_centre_mark(tmp_path):
    result = _checked("clamp_cam/opening_cam.toml")
    writers = kinds.figure_writers(result)
    writers["profile.csv"](tmp_path / "profile.csv")
    writers["profile.dxf"](tmp_path / "profile.dxf")
    header, rows = _csv(tmp_path / "profile.csv")
    assert header == ["cam_angle_deg", "crank_deg", "working_x_mm", "working_y_mm", "pitch_x_mm", "pitch_y_mm",
                      "pitch_r_mm", "working_r_mm", "pitch_radius_of_curvature_mm", "working_radius_of_curvature_mm",
                      "s_mm", "v_mm_s", "a_mm_s2", "pressure_angle_deg"]
    prof = result.extra["profile"]
    assert rows.shape == (3601, 14) and rows[-1, 0] == 360.0 and np.array_equal(rows[0, 1:], rows[-1, 1:])
    assert rows[:-1, 2] == pytest.approx(prof["working"]["x"], abs=1e-6)
    # the smallest convex working radius of the table is the cam's (the facts refine it between samples)
    rho_w = rows[:, 9]
    convex = rho_w[np.isfinite(rho_w) & (rows[:, 8] > 0)]
    assert convex.min() == pytest.approx(result.extra["cam"]["min_working_radius_mm"], abs=0.02)
    # s over the turn: 0 .. the stroke; the pitch radius is base + s (zero offset) where the follower is translating
    assert rows[:, 10].min() == pytest.approx(0.0, abs=1e-9)
    assert rows[:, 10].max() == pytest.approx(result.extra["cam"]["stroke"], abs=1e-6)
    assert rows[:, 6] == pytest.approx(prof["base_radius"] + rows[:, 10], abs=3e-6)
    # pressure angle at the crank angles of the follower table, as in result.json
    fol = result.extra["follower"]
    k = int(np.argmax(np.abs(fol["pressure_angle_deg"])))
    i = int(np.argmin(np.abs(rows[:, 1] - fol["crank_deg"][k])))
    assert abs(rows[i, 13]) == pytest.approx(abs(fol["pressure_angle_deg"][k]), abs=0.5)

    doc = ezdxf.readfile(tmp_path / "profile.dxf")
    layers = {l.dxf.name for l in doc.layers}
    assert "OUTER" not in layers                                   # no groove: no (empty) outer layer
    msp = doc.modelspace()
    centre = [e for e in msp if e.dxf.layer == "CENTRE"]
    assert sorted(e.dxftype() for e in centre) == ["CIRCLE", "LINE", "LINE"]
    assert all(np.allclose((e.dxf.center.x, e.dxf.center.y), 0) for e in centre if e.dxftype() == "CIRCLE")
    box = bbox.extents(msp)
    r = np.hypot(rows[:, 4], rows[:, 5]).max()
    assert box.extmax.x == pytest.approx(np.max(rows[:, 4]), abs=1e-3) or box.extmax.x <= r + 1e-6
    assert max(box.size.x, box.size.y) <= 2 * r + 1e-6


def test_a_planting_result_without_a_trajectory_says_why_it_has_no_exports(tmp_path):
    """A linkage that does not assemble over a whole turn has no trajectory: its paths.csv and linkage.dxf are
    refused with that reason (the report shows it), not a TypeError from reading a missing path."""
    import dataclasses

    from synthesis.kinds.planting.export import write_linkage_dxf, write_paths_csv

    result = kinds.get("planting_fourbar").check(load_spec(PLANTING / "taiwan_example1.toml"))
    broken = dataclasses.replace(result, trajectory=None)
    for writer, name in ((write_paths_csv, "paths.csv"), (write_linkage_dxf, "linkage.dxf")):
        with pytest.raises(ValueError, match="no trajectory: the linkage does not assemble over a whole crank turn"):
            writer(broken, tmp_path / name)
        assert not (tmp_path / name).exists()
