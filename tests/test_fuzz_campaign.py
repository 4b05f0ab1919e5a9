"""The fuzz campaign (marked ``fuzz``: ``pytest -m fuzz``): hostile input to every reader agrisynth has, each
run deterministic (``derandomize=True``: the same examples every run, so a CI failure reproduces).

* spec documents generated from each kind's own spec model (its JSON schema, the library example as the prior for
  the values), valid and made invalid: wrong types, numbers out of range, NaN and infinities, huge, deep and
  empty lists, unknown keys, unicode -- loaded and checked in-process;
* result.json files of real runs, mutated, given to ``agrisynth compare`` and ``agrisynth tolerance``;
* studio request bodies sent to the studio's own ASGI app in-process (``/api/evaluate`` and the other routes).

The invariant everywhere: exit 0, 1, 2 or 3 (the studio: HTTP 200 or 4xx), never a traceback, no NaN or
infinity in any JSON written or answered, every example within a time bound.  Each test prints what its examples
reached (``pytest -m fuzz -s`` shows it).
"""

from __future__ import annotations

import asyncio
import json
import math
import re
import shutil
import time
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import LIBRARY
from solving import agrisynth, strict_json
from test_fuzz import REACHED, check_in_process, library_kinds, paths, toml_document, values

pytestmark = pytest.mark.fuzz

#: one example (a spec loaded and checked, a comparison drawn, a studio request answered) may take this long; the
#: slowest legitimate one seen takes a few seconds, a quadratic or hanging reader takes minutes
EXAMPLE_SECONDS = 30.0


def fuzz_settings(examples: int):
    return settings(max_examples=examples, deadline=None, database=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.filter_too_much])


# --- spec documents from a kind's spec model ----------------------------------------------------------------

HOSTILE_NUMBERS = [math.nan, math.inf, -math.inf, 0.0, -0.0, -1.0, 1e308, -1e308, 5e-324, 2**63, -(2**63), 10**30]
UNICODE = st.sampled_from(["", "é", "名前", "\u202eevil", "a\u0000b", "\ud7ff", "🙂" * 50, "Ω" * 1000, "\n\r\t",
                           "../../etc/passwd", "${HOME}", "nan"])


def _resolve(schema: dict, defs: dict) -> dict:
    while "$ref" in schema:
        schema = defs[schema["$ref"].rsplit("/", 1)[1]]
    return schema


def _kind_of(value) -> str:
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, (int, float)):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    if isinstance(value, dict):
        return "object"
    return "null"


def _fits(schema: dict, defs: dict, hint) -> bool:
    """Whether ``hint`` (the library example's value) has the type an option of an anyOf asks for."""
    schema = _resolve(schema, defs)
    wanted = schema.get("type")
    if wanted is None:
        return "anyOf" in schema
    return _kind_of(hint) == {"integer": "number"}.get(wanted, wanted)


@st.composite
def from_schema(draw, schema: dict, defs: dict, hint=None, depth: int = 0):
    """A value the schema allows (mostly: a pattern or a cross-field rule may still refuse it), near ``hint``."""
    schema = _resolve(schema, defs)
    if "anyOf" in schema or "oneOf" in schema:
        options = schema.get("anyOf") or schema.get("oneOf")
        fitting = [o for o in options if hint is not None and _fits(o, defs, hint)]
        option = draw(st.sampled_from(fitting)) if fitting and draw(st.integers(0, 3)) else draw(st.sampled_from(options))
        return draw(from_schema(option, defs, hint if option in fitting else None, depth + 1))
    if "const" in schema:
        return schema["const"]
    if "enum" in schema:
        return draw(st.sampled_from(schema["enum"]))
    kind = schema.get("type")
    if kind in ("number", "integer"):
        lo = schema.get("minimum", schema.get("exclusiveMinimum"))
        hi = schema.get("maximum", schema.get("exclusiveMaximum"))
        numeric_hint = isinstance(hint, (int, float)) and not isinstance(hint, bool)
        if numeric_hint and draw(st.integers(0, 19)):      # most fields as the example has them: a document
            return hint                                   # with a field or two changed reaches the model code
        if "exclusiveMinimum" in schema:
            lo += 1e-3 * max(1.0, abs(lo))
        if "exclusiveMaximum" in schema:
            hi -= 1e-3 * max(1.0, abs(hi))
        choices = []
        if numeric_hint:
            choices += [st.floats(0.8, 1.25).map(lambda f, h=hint: h * f)] * 4
        if lo is not None and hi is not None:
            choices += [st.floats(lo, hi), st.sampled_from([lo, hi])]
        elif lo is not None:
            choices += [st.floats(lo, lo + 1e3), st.just(lo)]
        elif hi is not None:
            choices += [st.floats(hi - 1e3, hi), st.just(hi)]
        elif str(schema.get("range", "")).startswith(">"):        # the spec reference's "> 0"
            choices += [st.floats(0.1, 1e3)]
        else:
            choices += [st.floats(-1e3, 1e3)]
        if "default" in schema and isinstance(schema["default"], (int, float)):
            choices.append(st.just(schema["default"]))
        value = draw(st.one_of(choices))
        if kind == "number" and math.isfinite(value):     # not 1e-300: the loader's tiny-value rule refuses it
            value = round(value, 4)
        if kind == "integer":
            return int(value) if math.isfinite(value) else 0
        return float(value)
    if kind == "string":
        if isinstance(hint, str) and draw(st.integers(0, 3)):
            return hint
        if "pattern" in schema:
            return draw(st.from_regex(schema["pattern"], fullmatch=True).filter(lambda s: len(s) <= 60))
        return draw(st.text(max_size=20))
    if kind == "boolean":
        return draw(st.booleans())
    if kind == "null":
        return None
    if kind == "array":
        if "prefixItems" in schema:
            hints = hint if isinstance(hint, list) else []
            return [draw(from_schema(item, defs, hints[k] if k < len(hints) else None, depth + 1))
                    for k, item in enumerate(schema["prefixItems"])]
        item = schema.get("items", {})
        low = schema.get("minItems", 0)
        high = min(schema.get("maxItems", low + 6), low + 6) if depth < 6 else low
        if isinstance(hint, list) and hint and draw(st.integers(0, 2)):
            picks = draw(st.lists(st.sampled_from(range(len(hint))), min_size=max(low, min(len(hint), 1)),
                                  max_size=max(low, min(len(hint) + 2, high if high >= low else low))))
            return [draw(from_schema(item, defs, hint[k], depth + 1)) for k in picks]
        n = draw(st.integers(low, max(low, high)))
        return [draw(from_schema(item, defs, None, depth + 1)) for _ in range(n)]
    if kind == "object" or "properties" in schema:
        hints = hint if isinstance(hint, dict) else {}
        required = set(schema.get("required", []))
        out = {}
        for name, sub in schema.get("properties", {}).items():
            keep = name in required or (name in hints and draw(st.integers(0, 9))) or draw(st.integers(0, 7)) == 0
            if keep and depth < 8:
                value = draw(from_schema(sub, defs, hints.get(name), depth + 1))
                if value is not None:
                    out[name] = value
        extra = schema.get("additionalProperties")
        if isinstance(extra, dict):
            for key, value in hints.items():
                if key not in out and draw(st.integers(0, 3)):
                    made = draw(from_schema(extra, defs, value, depth + 1))
                    if made is not None:
                        out[key] = made
        return out
    return hint if hint is not None else draw(st.integers(-5, 5))


def _set(data, where: tuple, value) -> None:
    parent = data
    for part in where[:-1]:
        parent = parent[part]
    parent[where[-1]] = value


def _at(data, where: tuple):
    for part in where:
        data = data[part]
    return data


OPS = ["wrong_type", "out_of_range", "non_finite", "huge_list", "deep_list", "empty", "unknown_key", "unicode"]


@st.composite
def made_hostile(draw, data: dict):
    """``data`` with 1-3 of the campaign's hostile changes at random places; returns (data, the changes)."""
    done = []
    for _ in range(draw(st.integers(1, 3))):
        where = draw(st.sampled_from(paths(data) or [("kind",)]))
        op = draw(st.sampled_from(OPS))
        old = _at(data, where) if where and where[0] in data else None
        if op == "wrong_type":
            new = draw(st.sampled_from(["75", True, [1.0, 2.0], {"init": "x"}, "", [], {}]))
        elif op == "out_of_range":
            scale = abs(old) if isinstance(old, (int, float)) and not isinstance(old, bool) else 1.0
            new = draw(st.sampled_from([-scale - 1, scale * 1e6 + 1, -1e12, 1e12, 0, -1]))
        elif op == "non_finite":
            new = draw(st.sampled_from(HOSTILE_NUMBERS[:3] + HOSTILE_NUMBERS[6:]))
        elif op == "huge_list":
            unit = old[0] if isinstance(old, list) and old and not isinstance(old[0], (list, dict)) else 1.0
            new = [unit] * draw(st.sampled_from([1000, 5000, 20000]))
        elif op == "deep_list":
            new = 1.0
            for _ in range(draw(st.sampled_from([30, 100, 400]))):
                new = [new]
        elif op == "empty":
            new = draw(st.sampled_from([[], {}, ""]))
        elif op == "unknown_key":
            parent = _at(data, where[:-1]) if len(where) > 1 else data
            target = parent if isinstance(parent, dict) else data
            target[draw(st.sampled_from(["extra", "Init", "bounds ", "l1\u200b", "__class__", "x" * 200]))] = \
                draw(values)
            done.append((op, where[:-1]))
            continue
        else:
            new = draw(UNICODE)
        _set(data, where, new)
        done.append((op, where))
    return data, done


def _without_none(data):
    if isinstance(data, dict):
        return {k: _without_none(v) for k, v in data.items() if v is not None}
    if isinstance(data, list):
        return [_without_none(v) for v in data if v is not None]
    return data


SPEC_DOCUMENTS = 200


@pytest.mark.parametrize("kind", library_kinds())
def test_spec_documents_from_the_kinds_own_model_never_crash_check(kind, tmp_path):
    """Valid documents drawn from the kind's spec model (half of them then made hostile): each is refused with
    exit 2 or 3 and a message, or checks to a result whose JSON is finite -- never another exception."""
    from synthesis import kinds

    found = kinds.get(kind)
    example = LIBRARY / found.example
    base = tomllib.loads(example.read_text())
    for sibling in example.parent.glob("*.toml"):     # specs a spec refers to (the picker's two linkages)
        (tmp_path / sibling.name).write_bytes(sibling.read_bytes())
    schema = found.spec_model().model_json_schema()
    defs = schema.get("$defs", {})
    tally = {"documents": 0, "hostile": 0, "evaluated": 0, "slowest_s": 0.0}

    @fuzz_settings(SPEC_DOCUMENTS)
    @given(st.data())
    def run(data):
        document = _without_none(data.draw(from_schema(schema, defs, base)))
        if data.draw(st.booleans()):
            document, _ = data.draw(made_hostile(document))
            tally["hostile"] += 1
        before = REACHED["check"]
        began = time.perf_counter()
        check_in_process(toml_document(document).encode("utf-8"), tmp_path)
        took = time.perf_counter() - began
        assert took < EXAMPLE_SECONDS, f"{took:.1f} s for one document"
        tally["documents"] += 1
        tally["evaluated"] += REACHED["check"] - before
        tally["slowest_s"] = max(tally["slowest_s"], took)

    run()
    print(f"\n{kind}: {tally}")
    # how many reach the model code (not only the loader's refusals) is printed: it is low for the kinds with many
    # coupled fields (guide_way's 48 control points within their bounds), where the mutated library fuzz reaches more
    assert tally["documents"] == SPEC_DOCUMENTS


# --- result.json files for compare and tolerance ------------------------------------------------------------

RESULT_SPEC = LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml"
RESULT_NAME = "cai2020_crank_rocker_synthesis"


@pytest.fixture(scope="module")
def real_runs(tmp_path_factory):
    """A solve's run folder and a check's (crank_rocker: the quickest solve of the library)."""
    out = tmp_path_factory.mktemp("runs")
    solved = agrisynth("solve", RESULT_SPEC, "--out", out, "--starts", 2, "--workers", 1)
    assert solved.returncode == 0, solved.stderr
    checked = agrisynth("check", RESULT_SPEC, "--out", out)
    assert checked.returncode in (0, 1), checked.stderr
    return out / RESULT_NAME, out / f"{RESULT_NAME}-check"


@st.composite
def mutated_json(draw, base: dict):
    """A mutated copy of a real result.json as bytes: values replaced, deleted, added, made non-finite or
    huge; now and then not JSON at all."""
    pick = draw(st.integers(0, 19))
    if pick == 0:
        return draw(st.binary(max_size=300))
    if pick == 1:
        return b"[" * 5000 + b"]" * 5000
    data = json.loads(json.dumps(base))
    for _ in range(draw(st.integers(1, 4))):
        where = draw(st.sampled_from(paths(data) or [("status",)]))
        parent = _at(data, where[:-1]) if len(where) > 1 else data
        op = draw(st.sampled_from(["replace", "replace", "number", "delete", "extra", "unicode", "huge"]))
        if op == "replace":
            parent[where[-1]] = draw(values)
        elif op == "number":
            parent[where[-1]] = draw(st.sampled_from(HOSTILE_NUMBERS))
        elif op == "delete":
            if isinstance(parent, dict):
                del parent[where[-1]]
            elif parent:
                parent.pop(where[-1])
        elif op == "extra":
            (parent if isinstance(parent, dict) else data)[draw(st.text(min_size=1, max_size=8))] = draw(values)
        elif op == "unicode":
            parent[where[-1]] = draw(UNICODE)
        else:
            parent[where[-1]] = [parent[where[-1]]] * 2000
    return json.dumps(data, allow_nan=True, ensure_ascii=draw(st.booleans())).encode("utf-8")


def no_traceback(proc) -> None:
    assert proc.returncode in (0, 1, 2, 3), (proc.returncode, proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr + proc.stdout, proc.stderr[-2000:]
    if proc.returncode in (2, 3):
        assert proc.stderr.strip(), "a refusal says why"


def every_json_is_finite(folder: Path) -> int:
    count = 0
    for path in folder.rglob("*.json"):
        strict_json(path)
        count += 1
    return count


RESULT_FILES = 60


def test_mutated_result_files_never_crash_compare(real_runs, tmp_path):
    solved, checked = real_runs
    base = json.loads((solved / "result.json").read_text())
    tally = {"files": 0, "exit": {}, "slowest_s": 0.0}

    @fuzz_settings(RESULT_FILES)
    @given(mutated_json(base), st.booleans())
    def run(raw, as_file):
        folder = tmp_path / "mutated"
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(solved, folder)
        (folder / "result.json").write_bytes(raw)
        began = time.perf_counter()
        proc = agrisynth("compare", checked, folder / "result.json" if as_file else folder, "--out",
                         tmp_path / "page", "--force", timeout=EXAMPLE_SECONDS)
        took = time.perf_counter() - began
        no_traceback(proc)
        if proc.returncode in (0, 1):
            assert (tmp_path / "page" / "compare.html").is_file()
            every_json_is_finite(tmp_path / "page")
        tally["files"] += 1
        tally["exit"][proc.returncode] = tally["exit"].get(proc.returncode, 0) + 1
        tally["slowest_s"] = max(tally["slowest_s"], took)

    run()
    print(f"\ncompare: {tally}")
    assert tally["files"] == RESULT_FILES and tally["exit"].get(2, 0) > 0


def test_mutated_result_files_never_crash_tolerance(real_runs, tmp_path):
    """``tolerance DIR`` reads DIR's result.json when DIR has no solved.toml (to say why there is no design); with
    one, the solved design is the spec: both read through the guarded readers."""
    solved, _ = real_runs
    base = json.loads((solved / "result.json").read_text())
    solved_toml = (solved / "solved.toml").read_bytes()
    tally = {"files": 0, "exit": {}, "slowest_s": 0.0}

    @fuzz_settings(RESULT_FILES)
    @given(mutated_json(base), st.booleans())
    def run(raw, keep_solved):
        folder = tmp_path / "mutated"
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir()
        (folder / "result.json").write_bytes(raw)
        if keep_solved:
            (folder / "solved.toml").write_bytes(solved_toml)
        began = time.perf_counter()
        proc = agrisynth("tolerance", folder, "--out", tmp_path / "tol", "--length", 0.1, "--samples", 20, "--force",
                         timeout=EXAMPLE_SECONDS)
        took = time.perf_counter() - began
        no_traceback(proc)
        if keep_solved:
            assert proc.returncode in (0, 1), proc.stderr      # the result.json beside a solved design is not read
        else:
            assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        every_json_is_finite(tmp_path / "tol") if (tmp_path / "tol").exists() else None
        tally["files"] += 1
        tally["exit"][proc.returncode] = tally["exit"].get(proc.returncode, 0) + 1
        tally["slowest_s"] = max(tally["slowest_s"], took)

    run()
    print(f"\ntolerance: {tally}")
    assert tally["files"] == RESULT_FILES


# --- studio request bodies, through the studio's own ASGI app in this process -------------------------------

class _NoSolve:
    """Stands in for the studio's solve job: a body the route accepts would start a solver process, which is the
    solve tests' subject, not the request handling's; this records that it was asked for."""
    started = 0

    def __init__(self, name, path, out, starts):
        self.run_name, self.starts = name, starts
        self.running = False

    def start(self):
        _NoSolve.started += 1

    def status(self):
        return {"state": "done", "run": self.run_name, "starts": self.starts}

    def cancel(self, grace):
        pass


def asgi_request(studio, method: str, path: str, body: bytes, content_type: str = "application/json",
                 declared: int | None = None) -> tuple[int, bytes]:
    """(status, body) of one request handed to the studio's ASGI app, as uvicorn would hand it."""
    headers = [(b"host", f"127.0.0.1:{studio.port}".encode()), (b"x-studio-token", studio.token.encode()),
               (b"content-type", content_type.encode("latin-1")),
               (b"content-length", str(len(body) if declared is None else declared).encode())]
    scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1", "method": method, "scheme": "http",
             "path": path, "raw_path": path.encode(), "query_string": b"", "root_path": "", "headers": headers,
             "client": ("127.0.0.1", 50000), "server": ("127.0.0.1", studio.port)}
    sent: list[dict] = []

    async def main():
        pending = [{"type": "http.request", "body": body[k:k + 4096], "more_body": k + 4096 < len(body)}
                   for k in range(0, max(len(body), 1), 4096)]

        async def receive():
            if pending:
                return pending.pop(0)
            await asyncio.Event().wait()          # the client stays connected

        async def send(message):
            sent.append(message)

        await asyncio.wait_for(studio.app(scope, receive, send), EXAMPLE_SECONDS)

    asyncio.run(main())
    start = next(m for m in sent if m["type"] == "http.response.start")
    return start["status"], b"".join(m.get("body", b"") for m in sent if m["type"] == "http.response.body")


ROUTES = [("POST", "/api/evaluate"), ("POST", "/api/save"), ("POST", "/api/solve"), ("POST", "/api/solve/cancel"),
          ("GET", "/api/session"), ("GET", "/api/solve")]


@st.composite
def request_bodies(draw, free: list[str]):
    """A body for a studio route: mostly a JSON object near what the page sends, hostile in its values."""
    pick = draw(st.integers(0, 11))
    if pick == 0:
        return draw(st.binary(max_size=200)), "application/json"
    if pick == 1:
        return draw(st.sampled_from([b"[" * 30000 + b"]" * 30000, b'{"values":' * 100 + b"1" + b"}" * 100,
                                     b"x" * (64 * 1024 + 1), b"", b"null", b"[]", b'{"values": NaN}',
                                     b'{"values": {"a": Infinity}}', b'\xff\xfe{"values": {}}'])), "application/json"
    number = st.one_of(st.floats(allow_nan=False, allow_infinity=False), st.sampled_from(HOSTILE_NUMBERS[3:]),
                       st.integers(-10**40, 10**40), st.floats(-500, 500))
    names = st.sampled_from(free) if free else st.text(max_size=8)
    body = {}
    if draw(st.integers(0, 4)):
        body["values"] = draw(st.one_of(st.dictionaries(st.one_of(names, names, st.text(max_size=8)),
                                                        st.one_of(number, number, number, values), max_size=6),
                                        values))
    if draw(st.booleans()):
        body["grid"] = draw(st.one_of(st.sampled_from(["fine", "coarse"]), UNICODE, values))
    if draw(st.booleans()):
        body["starts"] = draw(st.one_of(st.integers(-3, 300), st.sampled_from([True, 1.5, "2", None, 10**20])))
    if draw(st.integers(0, 5)) == 0:
        body[draw(st.text(max_size=6))] = draw(values)
    try:
        raw = json.dumps(body, allow_nan=draw(st.booleans())).encode()
    except ValueError:              # NaN in a body that was to be strict JSON: sent as NaN, as a client may
        raw = json.dumps(body).encode()
    content_type = draw(st.sampled_from(["application/json"] * 6 + ["text/plain", "application/json; charset=utf-8",
                                                                       ""]))
    return raw, content_type


def _studio_specs() -> list[str]:
    from studio_fixtures import STUDIO_SPECS

    return sorted(STUDIO_SPECS)


STUDIO_BODIES = 100


@pytest.mark.parametrize("kind", _studio_specs())
def test_studio_request_bodies_get_200_or_a_4xx_and_finite_json(kind, tmp_path, monkeypatch):
    pytest.importorskip("starlette")
    from studio_fixtures import STUDIO_SPECS
    from synthesis.studio import server

    monkeypatch.setattr(server, "SolveJob", _NoSolve)
    studio = server.Studio(STUDIO_SPECS[kind], tmp_path / "studio")
    studio.body_seconds = 2.0
    free = [v.name for v in studio.session.free]
    tally = {"requests": 0, "status": {}, "slowest_s": 0.0}
    try:
        @fuzz_settings(STUDIO_BODIES)
        @given(st.sampled_from(ROUTES), request_bodies(free))
        def run(route, body):
            method, path = route
            raw, content_type = body
            began = time.perf_counter()
            status, answer = asgi_request(studio, method, path, raw if method == "POST" else b"", content_type)
            took = time.perf_counter() - began
            assert status == 200 or 400 <= status < 500, (status, answer[:300])
            data = json.loads(answer, parse_constant=lambda c: pytest.fail(f"{c} in a studio answer"))
            if status != 200:
                assert isinstance(data.get("error"), str) and "\n" not in data["error"].strip(), data
                assert "Traceback" not in data["error"]
            studio.job = None                  # the next solve request is not refused as a second solve
            tally["requests"] += 1
            tally["status"][status] = tally["status"].get(status, 0) + 1
            tally["slowest_s"] = max(tally["slowest_s"], took)
            assert took < EXAMPLE_SECONDS

        run()
    finally:
        studio.socket.close()
    print(f"\nstudio {kind}: {tally}, solves asked for: {_NoSolve.started}")
    assert tally["requests"] == STUDIO_BODIES and tally["status"].get(200, 0) > 0
    assert sum(n for s, n in tally["status"].items() if s >= 400) > 0
