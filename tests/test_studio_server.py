"""agrisynth studio without a browser: the guard (token, Host, Origin), what it writes, and that its rule
table is `agrisynth check`'s at the same values, for every kind it serves."""

from __future__ import annotations

import json
import math
import os

import pytest

from studio_fixtures import STUDIO_SPECS, api, moved_values, request, running_studio

pytest.importorskip("starlette")


@pytest.fixture(scope="module")
def planting_studio(tmp_path_factory):
    with running_studio(STUDIO_SPECS["planting_fourbar"], tmp_path_factory.mktemp("studio")) as studio:
        yield studio


def test_the_page_needs_the_token(planting_studio):
    s = planting_studio
    for token in (None, "", "x" * len(s.token), s.token[:-1]):
        status, _, body = request(s, "GET", "/api/session", token=token)
        assert status == 403 and b"token" in body, (token, status, body)
    conn_status, headers, body = request(s, "GET", f"/?token={s.token}", token=None)
    assert conn_status == 200 and b"studio.js?token=" + s.token.encode() in body
    assert "default-src 'none'" in headers["content-security-policy"]
    assert "connect-src 'self'" in headers["content-security-policy"]
    assert request(s, "GET", "/studio.js", token=None)[0] == 403
    assert request(s, "GET", f"/studio.js?token={s.token}", token=None)[0] == 200
    assert api(s, "/api/session")["kind"] == "planting_fourbar"


def test_other_hosts_and_origins_are_refused(planting_studio):
    s = planting_studio
    for host in ("evil.example", f"evil.example:{s.port}", f"127.0.0.1:{s.port + 1}", f"127.0.0.2:{s.port}", ""):
        status, _, body = request(s, "GET", "/api/session", host=host)
        assert status == 403 and b"Host" in body, (host, status)
    assert request(s, "GET", "/api/session", host=f"localhost:{s.port}")[0] == 200
    values = {v.name: v.value for v in s.session.free}
    files = sorted(s.out.iterdir())
    for origin in ("http://evil.example", f"http://evil.example:{s.port}", "null", f"https://127.0.0.1:{s.port}"):
        status, _, body = request(s, "POST", "/api/save", {"values": values}, origin=origin)
        assert status == 403 and b"Origin" in body, (origin, status)
    assert sorted(s.out.iterdir()) == files         # nothing refused wrote a file
    status, _, _ = request(s, "POST", "/api/evaluate", {"values": values}, origin=f"http://127.0.0.1:{s.port}")
    assert status == 200
    # the page and its assets are guarded alike (the token in the address does not let another Host or Origin in)
    for path in ("/", "/studio.js", "/studio.css"):
        status, _, body = request(s, "GET", f"{path}?token={s.token}", token=None, host=f"evil.example:{s.port}")
        assert status == 403 and b"Host" in body, (path, status)
        status, _, body = request(s, "GET", f"{path}?token={s.token}", token=None, origin="http://evil.example")
        assert status == 403 and b"Origin" in body, (path, status)
        assert request(s, "GET", f"{path}?token={s.token}", token=None)[0] == 200


def test_on_port_80_a_host_without_the_port_is_this_studio(tmp_path):
    """A browser leaves out the default port: on port 80 Host is `127.0.0.1` or `localhost`, Origin likewise."""
    from synthesis.studio.server import Refused, Studio

    studio = Studio(STUDIO_SPECS["crank_rocker"], tmp_path / "studio")
    try:
        def check(host, origin=None):
            headers = [(b"host", host.encode())] + ([(b"origin", origin.encode())] if origin else [])
            studio._check({"headers": headers, "query_string": f"token={studio.token}".encode()})
        studio.port = 80
        for host in ("127.0.0.1", "localhost", "127.0.0.1:80", "localhost:80"):
            check(host, f"http://{host}")
        studio.port = 8765
        for host in ("127.0.0.1", "localhost", "127.0.0.1:80"):
            with pytest.raises(Refused, match="Host"):
                check(host)
        with pytest.raises(Refused, match="Origin"):
            check("127.0.0.1:8765", "http://127.0.0.1")
    finally:
        studio.socket.close()


def test_bad_values_get_one_line_naming_the_field(planting_studio):
    s = planting_studio
    cases = [({"values": {"l2": 999.0}}, "values.l2: 999 lies outside its bounds [28, 42]"),
             ({"values": {"l2": 42.000000001}}, "values.l2: 42.000000001 lies outside its bounds [28, 42]"),
             ({"values": {"l1": 70.0}}, "values.l1: not a free design variable"),
             ({"values": {"l2": "35"}}, "values.l2: expected a finite number, got '35'"),
             ({"values": [1, 2]}, "values: expected an object of design values, got list"),
             ({"values": {}, "grid": "medium"}, "grid: expected one of coarse, fine, got 'medium'")]
    for body, message in cases:
        status, _, raw = request(s, "POST", "/api/evaluate", body)
        answer = json.loads(raw)
        assert status == 400 and answer["error"].startswith(message) and "\n" not in answer["error"], (body, answer)
    status, _, raw = request(s, "POST", "/api/evaluate", b'{"values": {"l2": NaN}}')
    assert status == 400 and json.loads(raw)["error"].startswith("request: not JSON")
    status, _, raw = request(s, "POST", "/api/evaluate", b"values=1", content_type="application/x-www-form-urlencoded")
    assert status == 400 and "Content-Type" in json.loads(raw)["error"]
    for path, body, message in (
            ("/api/evaluate", {"values": {}, "grids": "fine"}, "request: unknown key 'grids' (expected: grid, values)"),
            ("/api/save", {"values": {}, "file": "../x.toml"}, "request: unknown key 'file' (expected: values)"),
            ("/api/solve", {"start": 3}, "request: unknown key 'start' (expected: starts, values)"),
            ("/api/solve/cancel", {"now": True}, "request: unknown key 'now' (expected: none)")):
        status, _, raw = request(s, "POST", path, body)
        assert status == 400 and json.loads(raw)["error"] == message, (path, raw)
    assert s.job is None                 # the refused solve did not start



def test_a_name_another_studio_takes_between_the_look_and_the_write_is_left_to_it(planting_studio, monkeypatch):
    """Two studios with one --out (the default results/studio): each looked for a free name, then wrote over
    whatever was there -- of 100 concurrent saves 41 files held the other studio's values, and two solves shared a
    run folder.  A name is now claimed by the write itself (a hard link, never over a file): here another process
    writes saved_1 between this studio's look and its write, and this one takes saved_2."""
    from synthesis.studio import server as server_module

    s = planting_studio
    values = moved_values(s.session)
    real = server_module.create_new_text
    taken: list = []

    def other_studio_first(path, text):
        if not taken:
            taken.append(path)
            real(path, "# the other studio's spec\n")       # it wins the race for this name
        return real(path, text)

    monkeypatch.setattr(server_module, "create_new_text", other_studio_first)
    saved = api(s, "/api/save", {"values": values})
    assert taken and taken[0].name == "redesign_from_example1_saved_1.toml"
    assert saved["file"] == "redesign_from_example1_saved_2.toml"
    assert (s.out / taken[0].name).read_text() == "# the other studio's spec\n"          # not written over
    for name in (taken[0].name, saved["file"]):         # the studio is shared with the tests after this one
        (s.out / name).unlink()



def test_a_dangling_link_holds_its_name(planting_studio):
    """A broken link named like the next saved spec: the name looked free (exists() follows the link) and the write
    found it taken, again and again -- the save, and every later one behind its lock, hung."""
    s = planting_studio
    link = s.out / "redesign_from_example1_saved_1.toml"
    assert not os.path.lexists(link)
    link.symlink_to(s.out / "nowhere.toml")
    try:
        saved = api(s, "/api/save", {"values": moved_values(s.session)})
        assert saved["file"] == "redesign_from_example1_saved_2.toml" and link.is_symlink()
    finally:
        link.unlink()
        (s.out / "redesign_from_example1_saved_2.toml").unlink(missing_ok=True)


def test_a_new_file_where_hard_links_are_refused(tmp_path, monkeypatch):
    """A file system answering a hard link with EOPNOTSUPP (not EPERM): the save ended in HTTP 500."""
    import errno

    from synthesis import result as result_module

    def refused(src, dst):
        raise OSError(errno.EOPNOTSUPP, "Operation not supported")

    monkeypatch.setattr(result_module.os, "link", refused)
    result_module.create_new_text(tmp_path / "a.toml", "first\n")
    assert (tmp_path / "a.toml").read_text() == "first\n"
    with pytest.raises(FileExistsError):
        result_module.create_new_text(tmp_path / "a.toml", "second\n")
    assert (tmp_path / "a.toml").read_text() == "first\n" and [p.name for p in tmp_path.iterdir()] == ["a.toml"]
    # the text could not be put in place (EIO): no empty claim is left holding the name
    real_replace = result_module.os.replace

    def failing(src, dst):
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(result_module.os, "replace", failing)
    with pytest.raises(OSError):
        result_module.create_new_text(tmp_path / "b.toml", "x\n")
    monkeypatch.setattr(result_module.os, "replace", real_replace)
    assert [p.name for p in tmp_path.iterdir()] == ["a.toml"]
    result_module.create_new_text(tmp_path / "b.toml", "x\n")          # the name is free again
    assert (tmp_path / "b.toml").read_text() == "x\n"

def test_a_new_file_is_never_written_over(tmp_path):
    from synthesis.result import create_new_text

    create_new_text(tmp_path / "a.toml", "first\n")
    with pytest.raises(FileExistsError):
        create_new_text(tmp_path / "a.toml", "second\n")
    assert (tmp_path / "a.toml").read_text() == "first\n"
    assert [p.name for p in tmp_path.iterdir()] == ["a.toml"]           # no temporary file left behind

def test_saves_only_into_its_folder_with_names_it_picks(planting_studio, tmp_path):
    s = planting_studio
    values = moved_values(s.session)
    before = {p.name for p in s.out.iterdir()}
    status, _, _ = request(s, "POST", "/api/save", {"values": values, "file": "../../escape.toml", "name": "/etc/passwd"})
    assert status == 400                 # the page never names a file: such a request is refused outright
    first = api(s, "/api/save", {"values": values})
    second = api(s, "/api/save", {"values": values})
    assert (first["file"], second["file"]) == ("redesign_from_example1_saved_1.toml",
                                               "redesign_from_example1_saved_2.toml")
    assert {p.name for p in s.out.iterdir()} - before == {first["file"], second["file"]}
    assert not (s.out.parent / "escape.toml").exists()
    # the saved spec holds the page's values as start values, bounds kept, under its own name
    from synthesis.spec import load_spec

    loaded = load_spec(s.out / first["file"])
    assert loaded.name == "redesign_from_example1_saved_1"
    assert loaded.model.arm.l2.init == values["l2"] and tuple(loaded.model.arm.l2.bounds) == (28.0, 42.0)
    assert loaded.model.arm.l1 == 75.0


def _rows(rules: list[dict]) -> list[tuple]:
    return [(r["name"], r["value"], r["satisfied"]) for r in rules]


#: kinds whose page draws nothing (the rule table and the sliders only)
UNDRAWN = {"guide_tube"}


@pytest.mark.parametrize("kind", sorted(STUDIO_SPECS))
def test_fine_table_is_agrisynth_checks_at_those_values(kind, tmp_path):
    """The page's fine-grid table equals the check of the spec "save spec" writes, value for value;
    the coarse table has the same rules; the drawing has something to draw."""
    with running_studio(STUDIO_SPECS[kind], tmp_path / "studio") as s:
        values = moved_values(s.session)
        fine = api(s, "/api/evaluate", {"values": values, "grid": "fine"})
        coarse = api(s, "/api/evaluate", {"values": values, "grid": "coarse"})
        saved = api(s, "/api/save", {"values": values})
    assert fine["error"] is None and coarse["error"] is None
    # what `agrisynth check SAVED` evaluates (the CLI path is run in tests/test_studio_browser.py)
    from synthesis import kinds
    from synthesis.spec import load_spec

    checked = kinds.checker(kind)(load_spec(tmp_path / "studio" / saved["file"]))
    assert _rows(fine["rules"]) == _rows(checked.rules)
    for name, value in values.items():
        assert checked.design[name] == value
    assert [r["name"] for r in coarse["rules"]] == [r["name"] for r in fine["rules"]]
    drawing = fine["drawing"]
    lines, frames, charts = drawing["main"]["lines"], drawing["mechanism"]["frames"], drawing["charts"]
    # guide_tube's check holds no geometry to draw (its figures are drop-time charts): sliders and the table only
    assert (len(lines) + len(frames) + len(charts) > 0) == (kind not in UNDRAWN), drawing
    for l in lines:
        assert len(l["x"]) == len(l["y"]) >= 2, l["name"]
        finite_xy = [(x, y) for x, y in zip(l["x"], l["y"]) if x is not None and y is not None]
        assert len(finite_xy) >= 2 and all(math.isfinite(x) and math.isfinite(y) for x, y in finite_xy), l["name"]
    for c in charts:
        assert c["series"] and len(c["x"]) >= 2, c["name"]
        assert all(len(series["y"]) == len(c["x"]) for series in c["series"]), c["name"]
    shapes = drawing["mechanism"]["shapes"]
    for f in frames:
        joints = {k: v for k, v in f.items() if not isinstance(v, dict)}
        placed = {k: v for k, v in f.items() if isinstance(v, dict)}      # a rigid outline: named, moved, turned
        assert joints and all(len(xy) == 2 and all(math.isfinite(v) for v in xy) for xy in joints.values())
        for p in placed.values():
            assert p["shape"] in shapes and len(shapes[p["shape"]]) >= 3 and math.isfinite(p["turn_deg"])
            assert len(p["at"]) == 2 and all(math.isfinite(v) for v in p["at"])


def test_planting_draws_the_arm_and_both_frames(planting_studio):
    s = planting_studio
    given = {v.name: v.value for v in s.session.free}
    answer = api(s, "/api/evaluate", {"values": given, "grid": "fine"})
    drawing = answer["drawing"]
    assert drawing["ground"] is not None
    assert {p["name"] for p in drawing["ground"]["points"]} == {"P1", "P2", "P3", "P4", "P5", "P6"}
    frames = drawing["mechanism"]["frames"]
    assert 36 <= len(frames) <= 72 and set(frames[0]) == {"O", "O'", "A", "B", "C"}
    # the pose's joints keep the link lengths of the design (l2 = |OA|, l3 = |AB|, l4 = |O'B|, l5 = |AC|)
    for f in frames:
        for (a, b), length in ((("O", "A"), given["l2"]), (("A", "B"), given["l3"]), (("O'", "B"), given["l4"]),
                               (("A", "C"), given["l5"])):
            assert math.dist(f[a], f[b]) == pytest.approx(length, abs=2e-3)
    # the claw tip C of the poses lies on the drawn machine-frame path
    path = drawing["main"]["lines"][0]
    assert path["name"] == "path (machine frame)"
    for f in frames[::9]:
        assert min(math.dist(f["C"], xy) for xy in zip(path["x"], path["y"])) < 3.0


def test_coarse_grid_is_coarser_and_says_so(planting_studio):
    s = planting_studio
    info = api(s, "/api/session")
    assert info["grids"] == {"coarse": "40 samples per phase, 360 per crank turn",
                             "fine": "400 samples per phase, 3600 per crank turn"}
    given = {v.name: v.value for v in s.session.free}
    coarse = api(s, "/api/evaluate", {"values": given, "grid": "coarse"})
    fine = api(s, "/api/evaluate", {"values": given, "grid": "fine"})
    # the transmission angle is sampled over a turn: on 360 samples its extreme is at most 1 deg of crank off
    by_name = {r["name"]: r for r in fine["rules"]}
    for r in coarse["rules"]:
        assert r["value"] == pytest.approx(by_name[r["name"]]["value"], rel=0.02, abs=0.05), r["name"]


def test_the_coarse_grid_note_states_the_samples_evaluated():
    """Each note gives the counts the check runs on, not the [solver] value it is derived from; a check that
    reads no (effective) sample count is said to have one grid, and its coarse table is its fine one."""
    from synthesis.core.coarse import coarser
    from synthesis.spec import load_spec
    from synthesis.studio import grids
    from synthesis.studio.session import Session

    spec = load_spec(STUDIO_SPECS["fourbar_path"]).model
    assert spec.solver.samples == 36 and coarser(spec).solver.samples == 4      # not below ge=4
    assert spec.rules.grashof_class == "crank_rocker"         # path_rules reads the samples only for grashof "any"
    assert grids.note("fourbar_path", "coarse", spec).startswith("the check's one grid (grashof = \"crank_rocker\"")
    anything = spec.model_copy(update={"rules": spec.rules.model_copy(update={"grashof_class": "any"})})
    assert grids.note("fourbar_path", "coarse", anything) == ("the check on 40 samples per gap between targets "
                                                              "(fine: 360)")
    steering = load_spec(STUDIO_SPECS["steering_linkage"]).model
    assert grids.note("steering_linkage", "coarse", steering) == ("the check on 41 inside locks (fine: 401), "
                                                                  "without its Table 12 explanation")
    guide_way = load_spec(STUDIO_SPECS["guide_way"]).model
    assert grids.note("guide_way", "coarse", guide_way) == "the check on 50 samples per segment (fine: 400)"
    comb = load_spec(STUDIO_SPECS["comb_finger"]).model
    assert grids.note("comb_finger", "coarse", comb) == ("the check's one grid (3600 finger turn angles: it does not "
                                                         "go below that for [solver] turn_samples 72)")
    for kind in ("fourbar_path", "comb_finger"):
        session = Session.open(STUDIO_SPECS[kind])
        values = moved_values(session, 0.1)
        assert session.evaluate(values, "coarse")["rules"] == session.evaluate(values, "fine")["rules"], kind


@pytest.mark.parametrize("kind", sorted(["planting_fourbar", "steering_linkage", "tillage_linkage", "clamp_cam", "guide_way",
                                         "crank_rocker", "combing_chain", "fourbar_path"]))
def test_coarse_rules_are_the_checks_on_fewer_samples(kind):
    """Same rules, values close to the fine grid's (sampled extremes move a little), a different grid note."""
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS[kind])
    values = moved_values(session, 0.1)
    coarse, fine = session.evaluate(values, "coarse"), session.evaluate(values, "fine")
    assert coarse["grid_note"] != fine["grid_note"]
    by_name = {r["name"]: r for r in fine["rules"]}
    assert [r["name"] for r in coarse["rules"]] == list(by_name)
    for r in coarse["rules"]:
        assert r["value"] == pytest.approx(by_name[r["name"]]["value"], rel=0.03, abs=0.1), r["name"]


def settled(studio, deadline_s: float = 120.0) -> dict:
    """/api/solve once the solve has ended (polled; the deadline only bounds a hung worker)."""
    import time

    end = time.monotonic() + deadline_s
    while True:
        answer = api(studio, "/api/solve")
        if answer["state"] not in ("running", "cancelling"):
            return answer
        assert time.monotonic() < end, answer
        time.sleep(0.1)


def test_one_solve_at_a_time_and_cancel_stops_it(planting_studio):
    s = planting_studio
    values = moved_values(s.session, 0.1)
    first = api(s, "/api/solve", {"values": values, "starts": 256})
    assert first["state"] == "running" and first["total"] == 256
    status, _, raw = request(s, "POST", "/api/solve", {"values": values, "starts": 1})
    assert status == 409 and json.loads(raw)["error"].startswith("a solve is running (redesign_from_example1_solve_1)")
    cancelling = api(s, "/api/solve/cancel", {})
    assert cancelling["state"] in ("cancelling", "cancelled"), cancelling
    cancelled = settled(s)
    assert cancelled["state"] == "cancelled" and cancelled["exit_code"] in (143, -15), cancelled
    assert cancelled["exit"] in ("exit 143: cancelled (the finished starts are kept)",
                                 "cancelled before any start finished (nothing kept)"), cancelled
    assert cancelled["done"] < 256
    assert s.job.process.poll() is not None         # the worker process is gone
    status, _, raw = request(s, "POST", "/api/solve", {"values": values, "starts": 0})
    assert status == 400 and json.loads(raw)["error"] == ("starts: expected a whole number 1..256 or auto (the page's "
                                                          "cap; `agrisynth solve` takes more), got '0'")


@pytest.mark.parametrize("kind", sorted(STUDIO_SPECS))
def test_the_corners_of_the_box_evaluate_to_finite_json(kind):
    """Every slider at a bound (alternately low and high): a table or a one-line reason, never NaN or infinity."""
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS[kind])
    for corner in (0, 1):
        values = {v.name: v.bounds[(corner + i) % 2] for i, v in enumerate(session.free)}
        for grid in ("coarse", "fine"):
            out = session.evaluate(values, grid)
            json.dumps(out, allow_nan=False)
            assert (out["error"] is None) == bool(out["rules"]), out["error"]
            assert out["error"] is None or "\n" not in out["error"]


def test_steering_coarse_grid_samples_fewer_locks_and_skips_the_table12_fits():
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS["steering_linkage"])
    values = moved_values(session, 0.2)
    coarse, fine = session.evaluate(values, "coarse"), session.evaluate(values, "fine")
    by_name = {r["name"]: r for r in fine["rules"]}
    for r in coarse["rules"]:
        # the transmission angle's extreme over 41 locks instead of 401: within a tenth of a degree here
        assert r["value"] == pytest.approx(by_name[r["name"]]["value"], abs=0.1), r["name"]
    assert len(coarse["drawing"]["charts"][0]["x"]) == 41 and len(fine["drawing"]["charts"][0]["x"]) > 41
    assert coarse["grid_note"] == "the check on 41 inside locks (fine: 401), without its Table 12 explanation"


def test_answers_are_not_held_back_by_nagles_algorithm(planting_studio):
    """The listening socket says it is TCP, so asyncio turns Nagle's algorithm off on every connection (with
    it on, each keep-alive answer waited for the browser's delayed ACK, ~40 ms: measured by the benchmark)."""
    import socket

    s = planting_studio
    assert s.socket.proto == socket.IPPROTO_TCP
    assert s.socket.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY) != 0


def test_fourbar_path_draws_its_linkage_from_the_kinds_own_construction():
    """Poses from the textbook construction the kind's figures use: the links keep their lengths and the
    coupler point P runs on the path the check traced."""
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS["fourbar_path"])
    values = moved_values(session, 0.25)
    drawing = session.evaluate(values, "fine")["drawing"]
    frames = drawing["mechanism"]["frames"]
    assert len(frames) >= 24 and set(frames[0]) == {"O", "A", "B", "O'", "P"}
    path = drawing["main"]["lines"][0]
    for f in frames:
        for (a, b), length in ((("O", "A"), values["r2"]), (("A", "B"), values["r3"]), (("O'", "B"), values["r4"]),
                               (("O", "O'"), values["r1"])):
            assert math.dist(f[a], f[b]) == pytest.approx(length, abs=2e-3)
        assert min(math.dist(f["P"], xy) for xy in zip(path["x"], path["y"])) < 2.0


def test_a_huge_integer_is_a_400_naming_the_field(planting_studio):
    """A JSON integer beyond a float's range (330 digits) is bad input, not an internal error."""
    s = planting_studio
    huge = b'{"values": {"l2": 1' + b"0" * 330 + b'}}'
    for path in ("/api/evaluate", "/api/save", "/api/solve"):
        status, _, raw = request(s, "POST", path, huge)
        answer = json.loads(raw)
        assert status == 400 and answer["error"].startswith("values.l2: expected a finite number, got '1000"), answer


@pytest.mark.slow
def test_only_one_of_simultaneous_solves_starts(tmp_path):
    """Two solve requests at once, each held where it writes its spec until the other arrives there too (or,
    when the other cannot, as it must not, for 2 s): exactly one starts, the other is told a solve is running."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    with running_studio(STUDIO_SPECS["crank_rocker"], tmp_path / "studio") as s:
        both_there = threading.Barrier(2)
        write_spec = s._write_spec

        def held(*args):
            try:
                both_there.wait(timeout=2)
            except threading.BrokenBarrierError:
                pass
            return write_spec(*args)
        s._write_spec = held
        values = moved_values(s.session, 0.1)
        with ThreadPoolExecutor(2) as pool:
            answers = list(pool.map(lambda _: request(s, "POST", "/api/solve", {"values": values, "starts": 64}),
                                    range(2)))
        assert sorted(status for status, _, _ in answers) == [200, 409], [a[0] for a in answers]
        assert len(list(s.out.glob("*_solve_*.toml"))) == 1


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_cancel_answers_at_once_and_kills_a_worker_that_does_not_stop(tmp_path):
    """A worker that cannot answer SIGTERM (stopped here with SIGSTOP): cancel answers "cancelling" without
    waiting for it, and after the grace period the worker's process group is killed."""
    import os
    import signal
    import time

    with running_studio(STUDIO_SPECS["crank_rocker"], tmp_path / "studio") as s:
        s.grace = 0.5
        api(s, "/api/solve", {"values": moved_values(s.session, 0.1), "starts": 256})
        # stopped once it answers SIGTERM itself (a start has finished): a stopped process with SIGTERM's default
        # action would still be ended by it
        while api(s, "/api/solve")["done"] < 1:
            assert s.job.running, s.job.status()
            time.sleep(0.05)
        os.killpg(s.job.process.pid, signal.SIGSTOP)
        answer = api(s, "/api/solve/cancel", {})
        assert answer["state"] == "cancelling" and answer["exit_code"] is None, answer
        assert api(s, "/api/solve")["state"] == "cancelling"
        ended = settled(s)
        assert ended["state"] == "cancelled" and ended["exit_code"] == -signal.SIGKILL, ended
        assert ended["exit"] == "killed after 0.5 s of not stopping (nothing kept)"


@pytest.mark.slow
def test_a_solve_runs_the_studios_own_package_whatever_its_folder(tmp_path, monkeypatch):
    """Started with a relative PYTHONPATH (`PYTHONPATH=. agrisynth studio ...`): the worker, which runs in the
    studio's folder, still imports this synthesis package and its run is written."""
    from pathlib import Path

    import synthesis

    monkeypatch.chdir(Path(synthesis.__file__).parent.parent)
    monkeypatch.setenv("PYTHONPATH", ".")
    with running_studio(STUDIO_SPECS["crank_rocker"], tmp_path / "studio") as s:
        api(s, "/api/solve", {"values": moved_values(s.session, 0.1), "starts": 1})
        ended = settled(s)
    assert ended["state"] == "finished" and ended["exit_code"] in (0, 1), ended
    words = {0: "exit 0: every rule satisfied", 1: "exit 1: solved, some rule violated"}
    assert ended["exit"] == words[ended["exit_code"]]
    assert (tmp_path / "studio" / ended["run"] / "result.json").is_file() and ended["status"] == "optimal"


def test_a_solve_that_fails_says_so_with_its_last_line(tmp_path):
    """No result.json: the exit code is not read as `solve`'s verdict; the page gets the worker's last line."""
    from synthesis.studio.solver import SolveJob

    job = SolveJob("gone", tmp_path / "gone.toml", tmp_path, 1)
    job.start()
    job.wait(120)
    status = job.status()
    assert status["state"] == "failed" and status["exit_code"] == 2, status
    assert status["exit"].startswith("failed (exit 2): ") and "gone.toml" in status["exit"], status


def test_guide_way_key_points_turn_red_exactly_when_check_says_so(tmp_path):
    """Control point 0 weighs 1/6 at E (u = 0 of a uniform cubic B-spline): moved up dy, the path misses E by dy / 6.
    key_points (<= 0.01 mm) holds at dy = 0.05 (0.0083 mm) and fails at 0.07 (0.0117 mm) and 20 (3.33 mm), on both
    grids and in the check of the spec "save spec" writes; the key point E is drawn at its target, and where the path
    passes beside it once it misses."""
    from synthesis import kinds
    from synthesis.spec import load_spec

    with running_studio(STUDIO_SPECS["guide_way"], tmp_path / "studio") as s:
        given = {v.name: v.value for v in s.session.free}
        seen = {}
        for dy in (0.0, 0.05, 0.07, 20.0):
            values = dict(given, P0_y=given["P0_y"] + dy)
            answers = [api(s, "/api/evaluate", {"values": values, "grid": grid}) for grid in ("coarse", "fine")]
            saved = api(s, "/api/save", {"values": values})
            result = kinds.checker("guide_way")(load_spec(tmp_path / "studio" / saved["file"]))
            checked = {r["name"]: r for r in result.rules}
            for answer in answers:
                row = next(r for r in answer["rules"] if r["name"] == "key_points")
                want = checked["key_points"]
                assert (row["value"], row["satisfied"]) == (want["value"], want["satisfied"])
            seen[dy] = checked["key_points"]["value"], checked["key_points"]["satisfied"]
            points = {p["name"]: (p["x"], p["y"]) for p in answers[1]["drawing"]["main"]["points"]}
            assert points["E"] == (-50.087, -221.2)                      # the target, rounded to 1e-3 mm
            if checked["key_points"]["satisfied"]:
                assert "path_at_E" not in points
            else:
                assert points["path_at_E"] == (-50.087, pytest.approx(-221.2 + dy / 6, abs=1.5e-3))
    assert [ok for _, ok in seen.values()] == [True, True, False, False]
    for dy, (value, _) in seen.items():
        assert value == pytest.approx(dy / 6, abs=1e-9)


def test_planting_poses_send_none_for_a_joint_that_is_not_finite(monkeypatch):
    """An open loop gives NaN joints; the page gets null there (JSON has no NaN), as the studio's own rounding did."""
    import numpy as np

    import synthesis.kinds.planting.kinematics as arm
    from synthesis.kinds.planting.poses import frames

    class Checked:
        trajectory = {"crank_deg": [0.0, 10.0, 20.0]}
        design = {"l1": 1.0, "l2": 1.0, "l3": 1.0, "l4": 1.0, "l5": 1.0, "zeta": 0.0, "phi": 0.0, "branch": 1}

    monkeypatch.setattr(arm, "joint_positions",
                        lambda design, theta: {"A": np.array([[np.nan, 1.23456, np.inf], [0.5, 0.5, 0.5]])})
    got = frames(Checked(), 72)
    assert got == [{"A": [None, 0.5]}, {"A": [1.235, 0.5]}, {"A": [None, 0.5]}]
    json.dumps(got, allow_nan=False)


def _segment_distance(p, a, b) -> float:
    """Distance from point p to the segment a-b (plane)."""
    ax, ay, bx, by = a[0], a[1], b[0], b[1]
    dx, dy = bx - ax, by - ay
    t = max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / (dx * dx + dy * dy or 1.0)))
    return math.dist(p, (ax + t * dx, ay + t * dy))


def _placed(mechanism: dict, value: dict) -> list:
    """A placed shape's outline in the drawing's frame (as the page draws it)."""
    a = math.radians(value["turn_deg"])
    c, s = math.cos(a), math.sin(a)
    return [(value["at"][0] + c * x - s * y, value["at"][1] + s * x + c * y) for x, y in mechanism["shapes"][value["shape"]]]


#: the library cam (counter-clockwise, translating, no offset), a clockwise one with an offset, and a clockwise
#: oscillating follower: (replacements of the library spec's lines)
CAMS = {
    "counter_clockwise": [],
    "clockwise_offset": [("roller_radius = 3.5", 'roller_radius = 3.5\nrotation = "clockwise"'),
                         ("offset = { init = 0.0", "offset = { init = 8.0")],
    "clockwise_oscillating": [("roller_radius = 3.5", 'roller_radius = 3.5\nrotation = "clockwise"'),
                              ('type = "translating"', 'type = "oscillating"\npivot_distance = 80.0\n'
                                                      'arm_length = 60.0\nside = -1'),
                              ("offset = { init = 0.0, bounds = [-20.0, 20.0] }\n", ""),
                              ("stroke = 10.0", "stroke = 12.0")],
}


@pytest.mark.parametrize("cam", sorted(CAMS))
def test_the_cam_turns_with_its_follower(cam, tmp_path):
    """clamp_cam's poses: the working profile as the check exports it (mirrored for a clockwise cam), placed at
    each pose's cam angle, touches the roller -- the roller centre lies one roller radius from the drawn profile,
    never nearer than the chords' 0.01 mm -- the pose at cam angle 0 is the exported profile itself, and a whole
    turn of poses in the cam's own turning sense, each pose once."""
    from solving import spec_with
    from synthesis.studio.session import Session

    spec = spec_with(tmp_path, STUDIO_SPECS["clamp_cam"], CAMS[cam])
    session = Session.open(spec)
    answer = session.evaluate({}, "fine")
    assert answer["error"] is None, answer["error"]
    mechanism = answer["drawing"]["mechanism"]
    frames = mechanism["frames"]
    assert len(frames) >= 36 and {"O", "C", "cam", "roller"} <= set(frames[0])
    rr = session.given()["roller_radius"]
    for f in frames:
        cam_xy = _placed(mechanism, f["cam"])
        gap = min(_segment_distance(f["C"], a, b) for a, b in zip(cam_xy, cam_xy[1:]))
        assert rr - 0.01 <= gap <= rr + 0.02, (f["cam"]["turn_deg"], gap)
    # unturned, the outline is the working profile the check exports (and the page draws as profile.working)
    working = next(line for line in answer["drawing"]["main"]["lines"] if line["name"] == "profile.working")
    shape = mechanism["shapes"]["cam"]
    assert max(min(math.dist(xy, w) for w in zip(working["x"], working["y"])) for xy in shape[::20]) < 0.5
    turns = [f["cam"]["turn_deg"] for f in frames]
    sense = -1 if cam.startswith("clockwise") else 1
    assert all(sense * t >= 0 for t in turns) and len(set(turns)) == len(turns)
    # frame to frame the cam turns on by at most 6 deg in its own sense (wrapping once round at the rise start)
    steps = [(sense * (b - a)) % 360.0 for a, b in zip(turns, turns[1:])]
    assert all(0 < step <= 6 for step in steps) and 354 <= sum(steps) < 360


def test_the_crank_rocker_turns_a_whole_turn_keeping_its_links():
    """crank_rocker's poses: a whole turn (not only the two extremes the check reports), links kept."""
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS["crank_rocker"])
    values = moved_values(session, 0.5)
    frames = session.evaluate(values, "fine")["drawing"]["mechanism"]["frames"]
    assert len(frames) >= 36 and set(frames[0]) == {"G", "F", "E", "A"}
    for f in frames:
        for (a, b), name in ((("G", "F"), "l7"), (("F", "E"), "l8"), (("E", "A"), "l9"), (("G", "A"), "l10")):
            assert math.dist(f[a], f[b]) == pytest.approx(values.get(name, session.given()[name]), abs=2e-3)
    crank = sorted(math.degrees(math.atan2(f["F"][1], f["F"][0])) % 360 for f in frames)
    assert max(b - a for a, b in zip(crank, crank[1:])) < 12 and crank[-1] - crank[0] > 340


def test_the_comb_finger_turns_about_its_hub():
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS["comb_finger"])
    values = moved_values(session, 0.5)
    given = session.given() | values
    frames = session.evaluate(values, "fine")["drawing"]["mechanism"]["frames"]
    assert len(frames) >= 36
    for f in frames:
        assert math.dist(f["T"], f["R"]) == pytest.approx(given["r"], abs=2e-3)
    drawing = session.evaluate(values, "fine")["drawing"]
    mechanism = drawing["mechanism"]
    circle = next(line for line in drawing["main"]["lines"] if line["name"] == "curves.tip_circle")
    for f in mechanism["frames"]:
        assert all(math.dist(xy, f["S"]) == pytest.approx(given["rho"], abs=2e-3) for xy in _placed(mechanism, f["drum"]))
        # the tip runs on the tip circle the check draws from its own geometry (181 points: chords sag < 0.05 mm)
        ring = list(zip(circle["x"], circle["y"]))
        assert min(_segment_distance(f["T"], a, b) for a, b in zip(ring, ring[1:])) < 0.05


def test_the_combined_picker_shows_its_design_greyed():
    """The combined picker (check only) has no variables of its own: the page shows the design it evaluates --
    its drive's and linkage's lengths from the spec files it names, and its installation angles -- fixed, with units."""
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS["picker"])
    shown = {v.name: v for v in session.variables}
    assert shown["crank_rocker.l7"].value == 54.0 and shown["crank_rocker.l7"].unit == "mm"
    assert shown["double_crank.phi3"].unit == "deg" and shown["theta2"].unit == "deg"
    assert shown["double_crank.branch"].value == 1 and shown["double_crank.branch"].unit == "-"
    assert len(shown) == 16 and not session.free
    assert session.describe()["variables"][0] == {
        "name": "crank_rocker.l7", "value": 54.0, "unit": "mm", "free": False, "bounds": None, "group": None,
        "note": "from the part's spec file (check only)"}


def test_an_operating_range_s_verdict_says_it_is_the_nominal_point_s(tmp_path):
    """A trial: on an envelope spec (forward speed 0.5-0.75 m/s) the page said "every rule satisfied" for the plain
    redesign's design, which enters the soil at 77.4 deg (< 80) at 0.75 m/s; check says it evaluates the nominal
    value only, the page said nothing.  Its answer carries that scope (the verdict line appends it); a spec without a
    range has none."""
    from conftest import LIBRARY

    with running_studio(LIBRARY / "planting_arm/envelope_redesign_from_example1.toml", tmp_path / "a") as s:
        ranged = api(s, "/api/evaluate", {"values": moved_values(s.session), "grid": "fine"})
    assert ranged["error"] is None
    assert ranged["scope"] == ("at the nominal operating point (forward_speed given as a range: this page evaluates "
                               "the nominal value only; solve re-checks every rule over the range)")
    with running_studio(STUDIO_SPECS["planting_fourbar"], tmp_path / "b") as s:
        plain = api(s, "/api/evaluate", {"values": moved_values(s.session), "grid": "fine"})
    assert plain["scope"] == ""     # the page's verdict line: tests/test_studio_browser.py


def test_the_address_is_told_once_the_socket_listens(tmp_path):
    """The studio printed its address a moment before its socket listened (a browser given it at once was refused):
    the command prints it from ``on_listening``, which the server calls once it accepts connections."""
    import socket
    import threading

    from synthesis.studio.server import Studio

    studio = Studio(STUDIO_SPECS["crank_rocker"], tmp_path / "studio")
    with pytest.raises(ConnectionRefusedError):            # bound, not yet listening
        socket.create_connection(("127.0.0.1", studio.port), timeout=5).close()
    answered = []
    told = threading.Event()

    def listening() -> None:
        with socket.create_connection(("127.0.0.1", studio.port), timeout=5):
            answered.append(studio.port)
        told.set()

    server = studio.server(listening)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [studio.socket]}, daemon=True)
    thread.start()
    try:
        assert told.wait(60) and answered == [studio.port]
    finally:
        server.should_exit = True
        thread.join(60)


def test_the_missing_extra_message_names_the_install_at_hand(tmp_path):
    """A source checkout (pyproject.toml beside the package: editable, or on PYTHONPATH) is told to install the extra
    editable from its own folder; an installed copy (site-packages) from the package index, never `pip install -e`."""
    from synthesis.studio import install_command, missing_extra_text

    checkout, site = tmp_path / "checkout", tmp_path / "site-packages"
    for root in (checkout, site):
        (root / "synthesis").mkdir(parents=True)
    (checkout / "pyproject.toml").write_text("[project]\nname = 'agrisynth'\n")
    assert install_command(checkout / "synthesis") == f"pip install -e '{checkout}[studio]'"
    assert install_command(site / "synthesis") == "pip install 'agrisynth[studio]'"
    assert missing_extra_text("uvicorn", site / "synthesis") == (
        "agrisynth studio needs the studio extra (uvicorn is missing): pip install 'agrisynth[studio]'")


def test_the_drive_torque_follows_the_sliders():
    """A spec with a [dynamics] table: the page gets the input torque and shaking moment (N m) and the shaking force
    (N) over the crank angle, equal to check's facts.dynamics at those values (thinned to the page's points); moving
    the crank length changes the torque curve."""
    from synthesis import kinds
    from synthesis.spec import load_spec
    from synthesis.studio.session import Session
    from conftest import LIBRARY

    path = LIBRARY / "picker" / "crank_rocker_torque_limited.toml"
    session = Session.open(path)
    given = session.evaluate({}, "fine")["drawing"]["charts"]
    assert [(c["name"], c["unit"]) for c in given[:2]] == [("drive", "N m"), ("frame", "N")]
    facts = kinds.get("crank_rocker").check(load_spec(path)).extra["dynamics"]
    torque = dict(zip(given[0]["x"], given[0]["series"][0]["y"]))
    for crank, value in list(zip(facts["crank_deg"], facts["input_torque_Nm"]))[::45]:
        assert torque[round(crank, 3)] == pytest.approx(value, abs=1e-3)
    moved = session.evaluate({"l7": session.given()["l7"] * 1.1}, "fine")["drawing"]["charts"]
    peak = lambda chart: max(abs(v) for v in chart["series"][0]["y"])  # noqa: E731
    assert abs(peak(moved[0]) - peak(given[0])) > 0.01 * peak(given[0])


def test_an_evaluation_error_is_said_of_the_page_s_values_not_of_the_spec_file():
    """A guide-way control point moved where the arm cannot reach: the reason begins "at the page's values", not
    with the (untouched) spec file's path."""
    from synthesis.studio.session import Session

    session = Session.open(STUDIO_SPECS["guide_way"])
    values = {v.name: v.value for v in session.free}
    p6 = next(v for v in session.free if v.name == "P6_x")
    values["P6_x"] = p6.bounds[1]
    out = session.evaluate(values, "fine")
    assert out["error"].startswith("at the page's values: [spline] control: segment ED: the arm cannot reach"), \
        out["error"]
    assert str(STUDIO_SPECS["guide_way"]) not in out["error"]


def test_a_spec_the_studio_saves_reads_back_whatever_its_file_name_holds(tmp_path):
    """A spec file named with a newline: the saved spec's "# from <name>" comment ended at it and the rest of the name
    became TOML, which load_spec refused."""
    from conftest import LIBRARY
    from synthesis.spec import load_spec
    from synthesis.studio.session import Session

    spec = tmp_path / "ev\nil.toml"
    spec.write_text((LIBRARY / "planting_arm" / "redesign_from_example1.toml").read_text())
    session = Session.open(spec)
    text = session.spec_text(session.given(), "saved", "saved\nby the test", tmp_path)
    assert "# from ev?il.toml" in text and "# saved?by the test" in text
    out = tmp_path / "saved.toml"
    out.write_text(text)
    assert load_spec(out).name == "saved"


@pytest.mark.slow         # seconds: a --starts auto solve of the crank-rocker
def test_a_spec_asking_starts_auto_is_solved_so_from_the_page(tmp_path):
    """A spec's `starts = "auto"` showed in the page's number box as nothing and the page solved 8 fixed starts;
    the box now holds "auto" and the solve is --starts auto's (its batches said as they begin)."""
    text = STUDIO_SPECS["crank_rocker"].read_text()
    assert "starts = " in text
    import re

    spec = tmp_path / "auto.toml"
    spec.write_text(re.sub(r"(?m)^starts = \d+", 'starts = "auto"', text))
    with running_studio(spec, tmp_path / "out") as s:
        assert api(s, "/api/session")["starts"] == "auto"
        started = api(s, "/api/solve", {"values": moved_values(s.session, 0.0), "starts": "AUTO"})
        assert started["state"] == "running"
        done = settled(s)
        assert done["state"] == "finished", done
        result = json.loads((s.out / done["run"] / "result.json").read_text())
        assert result["solver"]["auto"]["stopped_by"] in ("rule", "max_starts") and done["total"] >= 16
