"""Bad input says what was expected in one line, in the user's terms."""

from __future__ import annotations


import pytest

from conftest import LIBRARY, PLANTING
from synthesis.errors import SpecError
from synthesis.spec import load_spec
from solving import agrisynth, spec_with

REDESIGN = (PLANTING / "redesign_from_example1.toml").read_text()
L2 = "l2 = { init = 35, bounds = [28, 42] }"


def message(tmp_path, old: str, new: str, lines: int = 1) -> str:
    assert old in REDESIGN, old
    path = tmp_path / "bad.toml"
    path.write_text(REDESIGN.replace(old, new, 1))
    with pytest.raises(SpecError) as exc:
        load_spec(path)
    text = str(exc.value)
    assert len(text.splitlines()) == lines, text     # one line per bad field
    assert text.startswith(f"{path}: planting_fourbar.")
    return text.removeprefix(f"{path}: planting_fourbar.")


@pytest.mark.parametrize("old, new, expected", [
    ("forward_speed = 0.6", 'forward_speed = "0.8 m/s"',
     "operation.forward_speed: expected a number in m/s, written without a unit, got '0.8 m/s'"),
    ("crank_speed = 250", 'crank_speed = "300 rpm"',
     "operation.crank_speed: expected a number in r/min, written without a unit, got '300 rpm'"),
    (L2, "l2 = { init = 35, bounds = [25] }", "arm.l2.bounds: expected [lo, hi] (two numbers), got [25]"),
    (L2, "l2 = { init = 35, bounds = [25, 30, 40] }",
     "arm.l2.bounds: expected [lo, hi] (two numbers), got [25, 30, 40]"),
    (L2, "l2 = [25, 45]",
     "arm.l2: expected a number, or a table to free it: l2 = {init = 35, bounds = [25, 45]}, got [25, 45]"),
    (L2, "l2 = { bounds = [28, 42] }", "arm.l2.init: missing required field"),
])
def test_value_messages(tmp_path, old, new, expected):
    text = message(tmp_path, old, new)
    assert text == expected
    assert "FreeVariable" not in text and "dictionary" not in text


def test_unknown_top_level_key_suggests_nothing_unrelated(tmp_path):
    text = message(tmp_path, "source = ", 'description = "my arm"\nsource = ')
    assert text.startswith("description: unknown field; allowed: name, source, ")
    assert "did you mean" not in text
    assert text.endswith("(a note about the spec goes in source = \"...\" or a # comment)")
    for section in ("kind", "arm", "seedbed", "operation", "soil", "rules", "objective", "solver"):
        assert section in text


@pytest.mark.parametrize("old, typo, meant", [("[seedbed]", "[seedbd]", "seedbd: unknown field; did you mean 'seedbed'?"),
                                            ("[operation]", "[operations]",
                                             "operations: unknown field; did you mean 'operation'?"),
                                            ("crank_speed = 250", "crank_sped = 250",
                                             "operation.crank_sped: unknown field; did you mean 'crank_speed'?")])
def test_unknown_key_close_to_a_field_suggests_it(tmp_path, old, typo, meant):
    """One line: the field it meant is missing too, which the suggestion says (the missing field's line came first,
    being earlier in the file, and read as a second fault)."""
    assert message(tmp_path, old, typo, lines=1) == meant


def test_rule_key_named_as_in_the_output_suggests_the_spec_key(tmp_path):
    text = message(tmp_path, "[objective]", "[rules]\np1p3_distance = [100, 110]\n\n[objective]")
    assert text == "rules.p1p3_distance: unknown field; did you mean 'p1p3'?"


def test_linkage_that_cannot_assemble_names_the_file(tmp_path):
    path = tmp_path / "far.toml"
    path.write_text(REDESIGN.replace("l1 = 75", "l1 = 400", 1))
    proc = agrisynth("check", str(path), "--out", str(tmp_path / "out"), timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.startswith(f"error: {path}: planting_fourbar: linkage cannot assemble at any crank angle")
    assert len(proc.stderr.strip().splitlines()) == 1


def test_planting_limits_follow_the_seedling_height_and_the_mat_thickness(tmp_path):
    """P1P3 and P2P3 not written in the spec follow the inputs they stand for (the paper's
    [105, 115] mm for a 110 mm seedling, about 22 mm for a 22 mm mat); written ones are kept as written."""
    from conftest import PLANTING
    from synthesis.spec import load_spec

    text = (PLANTING / "taiwan_example1.toml").read_text()
    assert "p1p3" not in text and "seedling_height = " in text and "thickness = " in text
    spec = load_spec(PLANTING / "taiwan_example1.toml").model
    assert spec.rules.p1p3 == pytest.approx((105.0, 115.0)) and spec.rules.p2p3 == pytest.approx((21.0, 23.0))
    path = tmp_path / "taller.toml"
    path.write_text(text.replace("seedling_height = 110", "seedling_height = 120").replace("thickness = 22", "thickness = 20"))
    taller = load_spec(path).model
    assert taller.rules.p1p3 == pytest.approx((120 * 105 / 110, 120 * 115 / 110))
    assert taller.rules.p2p3 == pytest.approx((20 * 21 / 22, 20 * 23 / 22))
    assert set(taller.derived_limits()) == {"p1p3", "p2p3"} and "seedling height 120 mm" in taller.derived_limits()["p1p3"]
    path.write_text(text.replace("[rules]", "[rules]\np1p3 = [100, 120]") if "[rules]" in text
                    else text + "\n[rules]\np1p3 = [100, 120]\n")
    given = load_spec(path).model
    assert given.rules.p1p3 == (100.0, 120.0) and set(given.derived_limits()) == {"p2p3"}


def test_a_precision_point_not_searched_says_which_point_was_missing_and_why():
    """On taiwan_example2 the claw never crosses the 22 mm mat line, so P2 is not found and P1
    (searched above it) never looked for; the P1 rules used to say only "P1 not found"."""
    from conftest import PLANTING
    from synthesis import kinds
    from synthesis.spec import load_spec

    result = kinds.checker("planting_fourbar")(load_spec(PLANTING / "taiwan_example2.toml"))
    notes = {r["name"]: r.get("note") for r in result.rules}
    p2 = ("P2 not found: the claw does not cross the line 22 mm above the seedbed bottom on its way down between "
          "soil exit and entry (that line is [seedbed] thickness = 22 mm: lower it, or give the arm a taller loop)")
    assert notes["p2_speed"] == p2
    for name in ("p1p3_distance", "p2p3_distance", "p1p2p3_collinearity"):     # each needs P1 (P1P2P3 frame)
        assert notes[name] == f"P1 not searched: {p2}"


def test_a_name_that_cannot_name_a_folder_is_said_in_words(tmp_path):
    """pydantic's "string should match pattern '^[A-Za-z0-9][A-Za-z0-9_.-]*$'" asked a user to read a regex."""
    text = message(tmp_path, 'name = "redesign_from_example1"', 'name = "Ab c"')
    assert text == ("name: letters, digits, '_', '.' and '-' only, starting with a letter or digit (it names the "
                    "result folder), got 'Ab c'")


def test_fourbar_path_needs_three_distinct_targets(tmp_path):
    """Four copies of one point are one target: bad input, not a synthesis that "satisfies every rule".  A point
    may repeat (published sets repeat a loop's first point as its last), so three distinct ones are asked for."""
    from conftest import LIBRARY

    text = (LIBRARY / "fourbar_path" / "picking_arc.toml").read_text()
    head, rest = text.split("points = [", 1)
    tail = rest[rest.index("\n]\n") + 2:]
    path = tmp_path / "dup.toml"
    path.write_text(head + "points = [" + "[376.0, 123.7], " * 4 + "[205.0, 258.0]]" + tail)
    with pytest.raises(SpecError) as exc:
        load_spec(path)
    assert str(exc.value) == (f"{path}: fourbar_path.targets: points: expected at least 3 distinct target points, "
                              f"got 2 among the 5 given (points closer than 1e-06 of the set's size, 0.000217 mm "
                              f"here, are one target)")
    path.write_text(head + "points = [" + "[376.0, 123.7], " * 2 + "[300.0, 200.0], [205.0, 258.0]]" + tail)
    assert len(load_spec(path).model.targets.points) == 4


@pytest.mark.parametrize("old, new, field", [
    ("zeta = ", "zeta = 1000 #", "arm.zeta"),
    ("phi = ", "phi = { init = 10, bounds = [-400, 20] } #", "arm.phi"),
])
def test_an_angle_beyond_a_turn_is_refused_not_taken_modulo_360(tmp_path, old, new, field):
    """zeta = 1000 was evaluated as 280 in silence; picker_double_crank's phi3 / phi4, fourbar_path's theta0 and
    clamp_cam's rise_start take the same [-360, 360] deg (common.within_a_turn)."""
    bad = "1000" if "1000" in new else "-400"
    assert message(tmp_path, old, new) == f"{field}: expected an angle within one turn, [-360, 360] deg, got {bad}"


@pytest.mark.parametrize("spec, old, field", [
    ("planting_arm/taiwan_example1.toml", "branch = -1", "planting_fourbar.arm.branch"),
    ("fourbar_path/picking_arc.toml", "branch = 1", "fourbar_path.linkage.branch"),
    ("picker/cai2020_double_crank.toml", "branch = 1", "picker_double_crank."),
    ("guide_way/liang_2z.toml", "branch = 1", "guide_way."),
])
@pytest.mark.parametrize("value", ["true", "false"])
def test_a_boolean_is_no_sign(tmp_path, spec, old, field, value):
    """A branch is -1 or +1: TOML's true was taken for +1 (pydantic's literal check: True == 1) while false was
    refused; both are refused in one line naming the field."""
    from conftest import ROOT

    text = (ROOT / "problems" / spec).read_text()
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, f"branch = {value}", 1))
    with pytest.raises(SpecError) as exc:
        load_spec(path)
    said = str(exc.value)
    assert len(said.splitlines()) == 1 and field in said and said.endswith(
        f"branch: expected -1 or 1, got {value.capitalize()}"), said


def test_a_spec_saved_with_a_byte_order_mark_reads_as_without(tmp_path):
    """Editors that save "UTF-8 with BOM" put U+FEFF first; TOML's parser refused it as an invalid statement at line 1,
    column 1.  The mark is no content: the spec reads as the same file without it; an empty spec is still refused;
    a tilt beyond a turn is refused like zeta's."""
    text = (PLANTING / "taiwan_example1.toml").read_text()
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert load_spec(path).model == load_spec(PLANTING / "taiwan_example1.toml").model
    path.write_bytes(b"\xef\xbb\xbf\n")
    with pytest.raises(SpecError, match="empty file"):
        load_spec(path)
    path.write_text(text.replace("tilt = -34.1", "tilt = 1000", 1))
    with pytest.raises(SpecError, match="seedbed.tilt: expected an angle within one turn"):
        load_spec(path)


def test_a_printed_figure_of_a_paper_is_positive(tmp_path):
    """combing_chain's [[published]] values are an angle before the cut or a time: -1 s was taken as a figure to
    compare with."""
    from conftest import ROOT

    text = (ROOT / "problems" / "combing_chain" / "hinomoto_ub550.toml").read_text()
    path = tmp_path / "negative.toml"
    path.write_text(text.replace("value = 0.85", "value = -1", 1))
    with pytest.raises(SpecError, match=r"published\.0\.value: expected > 0, got -1"):
        load_spec(path)


def test_numbers_that_look_like_the_wrong_unit_get_a_note_and_the_library_none(tmp_path):
    """A practitioner's trial: a crank-rocker in metres (frame 0.2) and a tillage angle's bounds in radians
    ([0.17, 1.05]) solved 'optimal' without a word.  They are valid input, so a note each, never an error."""
    import glob

    from conftest import LIBRARY
    from synthesis.spec.plausibility import unit_notes

    assert all(unit_notes(load_spec(f).model) == [] for f in sorted(glob.glob(str(LIBRARY / "*" / "*.toml"))))
    text = (LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").read_text()
    for old, new in (("{ init = 50.0, bounds = [5.0, 200.0] }", "{ init = 0.05, bounds = [0.005, 0.2] }"),
                     ("{ init = 120.0, bounds = [5.0, 400.0] }", "{ init = 0.12, bounds = [0.005, 0.4] }"),
                     ("l10 = 140.0", "l10 = 0.14")):
        assert old in text
        text = text.replace(old, new)
    metres = tmp_path / "metres.toml"
    metres.write_text(text)
    assert unit_notes(load_spec(metres).model) == [
        "every length is under 1 mm (the largest, links.l8, is 0.4 mm): lengths are in mm; were they given in metres?"]
    # a cam in metres: its rules' defaults in mm (min_working_radius 3 mm), which the user never wrote, do not hide it
    cam = spec_with(tmp_path, LIBRARY / "clamp_cam" / "opening_cam_redesign.toml", [
        ("{ init = 50.0, bounds = [20.0, 150.0] }", "{ init = 0.05, bounds = [0.02, 0.15] }"),
        ("roller_radius = 3.5", "roller_radius = 0.0035"),
        ("{ init = 0.0, bounds = [-20.0, 20.0] }", "{ init = 0.0, bounds = [-0.02, 0.02] }"),
        ("stroke = 10.0", "stroke = 0.01")], "cam.toml")
    assert unit_notes(load_spec(cam).model) == [
        "every length is under 1 mm (the largest, cam.base_radius, is 0.15 mm): lengths are in mm; were they given in "
        "metres?"]
    # one link in metres among lengths in mm: 11 rules violated and no word on units, before
    arm = spec_with(tmp_path, LIBRARY / "planting_arm" / "taiwan_example1.toml", [("l5 = 191 ", "l5 = 0.191 ")],
                    "arm.toml")
    assert unit_notes(load_spec(arm).model) == [
        "arm.l5 = 0.191 mm beside lengths up to 180.6 mm: lengths are in mm; was it given in metres?"]
    # a bound of 0.5 mm is a designer's limit, not a link in metres: the value given (a free variable's init) is read
    wide = spec_with(tmp_path, LIBRARY / "planting_arm" / "redesign_from_example1.toml",
                     [("l2 = { init = 35, bounds = [28, 42] }", "l2 = { init = 35, bounds = [0.5, 42] }")], "wide.toml")
    assert unit_notes(load_spec(wide).model) == []
    text = (LIBRARY / "tillage" / "tillage_redesign.toml").read_text()
    old = next(line for line in text.splitlines() if line.startswith("theta = {"))
    radians = tmp_path / "radians.toml"
    radians.write_text(text.replace(old, "theta = { init = 0.52, bounds = [0.17, 1.05] }"))
    assert unit_notes(load_spec(radians).model) == [
        "linkage.theta bounds [0.17, 1.05] deg span under 2 deg: angles are in degrees ([9.74, 60.16] if those were "
        "radians)"]


@pytest.mark.parametrize("name, said", [
    ("compare", "name: may not be 'compare': agrisynth's compare command writes results/compare/, got 'compare'"),
    ("bench", "name: may not be 'bench': agrisynth's bench command writes results/bench/, got 'bench'"),
    ("studio", "name: may not be 'studio': agrisynth's studio command writes results/studio/, got 'studio'"),
    # a file system that ignores case (macOS, Windows) writes results/bench/ for it too
    ("Bench", "name: may not be 'Bench': agrisynth's bench command writes results/bench/, got 'Bench'"),
    ("x-check", "name: may not end in '-check': agrisynth names another command's run folder <name>-check, got "
                "'x-check'"),
])
def test_a_spec_name_that_is_another_commands_folder_is_refused(tmp_path, name, said):
    """A solve named "compare" wrote results/compare/, which `agrisynth compare --force` then replaced by its page."""
    assert message(tmp_path, 'name = "redesign_from_example1"', f'name = "{name}"') == said


@pytest.mark.parametrize("given, said", [
    ("crank = { mass = 1, com = [0, 0], inertia = -1 }", "planting_fourbar.dynamics.crank.inertia: expected >= 0, got -1"),
    ("crank = { density = 0, area = 100 }", "planting_fourbar.dynamics.crank.density: expected > 0, got 0"),
])
def test_a_link_table_that_fits_no_form_is_told_what_is_wrong_with_the_form_it_was_given_in(tmp_path, given, said):
    """A link is a bar {density, area} or lumped {mass, com, inertia}: a lumped link with a negative inertia was told
    four lines of "BarLink.mass: unknown field" and "... and 2 more", never its inertia."""
    text = (LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml").read_text()
    assert "crank = { density = 7850, area = 100 }" in text
    spec = tmp_path / "spec.toml"
    spec.write_text(text.replace("crank = { density = 7850, area = 100 }", given, 1))
    proc = agrisynth("check", str(spec), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.strip() == f"error: {spec}: {said}", proc.stderr


def test_keys_the_user_names_with_a_capital_are_not_taken_for_a_union_s_forms(tmp_path):
    """Poses named Pick and Drop were taken for a union's branches (class names): one of the two complaints was dropped
    and the pose's name cut from the path."""
    text = (LIBRARY / "picker" / "picker_double_crank_key_pose.toml").read_text()
    text = text.replace("[key_poses.pick]", "[key_poses.Pick]").replace("[key_poses.drop]", "[key_poses.Drop]")
    text = text.replace("attitude_tolerance = 1.0     # deg", "attitude_tolerance = -1", 1).replace('at = "M2"', 'at = "M9"')
    spec = tmp_path / "spec.toml"
    spec.write_text(text)
    proc = agrisynth("check", str(spec), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.strip().splitlines() == [
        f"error: {spec}: picker_double_crank.key_poses.Pick.attitude_tolerance: expected > 0, got -1",
        "picker_double_crank.key_poses.Drop.at: expected 'M1' or 'M2', got 'M9'"], proc.stderr
