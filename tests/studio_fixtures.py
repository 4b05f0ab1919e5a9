"""Test helpers for the studio: a server on a free loopback port, raw HTTP requests to it."""

from __future__ import annotations

import contextlib
import http.client
import json
from pathlib import Path

import pytest

from conftest import LIBRARY

#: kind -> the library spec its studio tests and benchmarks open (the kinds with a moving mechanism or a profile)
STUDIO_SPECS = {
    "planting_fourbar": LIBRARY / "planting_arm/redesign_from_example1.toml",
    "fourbar_path": LIBRARY / "fourbar_path/picking_arc.toml",
    "crank_rocker": LIBRARY / "picker/cai2020_crank_rocker_synthesis.toml",
    "picker_double_crank": LIBRARY / "picker/picker_double_crank_redesign.toml",
    "clamp_cam": LIBRARY / "clamp_cam/opening_cam_redesign_modified_sine.toml",
    "guide_way": LIBRARY / "guide_way/smooth_redesign.toml",
    "tillage_linkage": LIBRARY / "tillage/tillage_redesign.toml",
    "steering_linkage": LIBRARY / "steering/steering_redesign_40.toml",
    "comb_finger": LIBRARY / "comb_finger/redesign_max_combing.toml",
    "combing_chain": LIBRARY / "combing_chain/redesign_window_80_100.toml",
    # the wall angles of both tube pairs free (a trial: the page showed them fixed, "nothing free to solve for")
    "guide_tube": LIBRARY / "guide_tube/uniform_spacing_mu_envelope.toml",
    "picker": LIBRARY / "picker/cai2020_picker.toml",
}


@contextlib.contextmanager
def running_studio(spec: Path, out: Path):
    pytest.importorskip("starlette")
    pytest.importorskip("uvicorn")
    from synthesis.studio.server import Studio

    studio = Studio(spec, out)
    studio.start_in_thread()
    try:
        yield studio
    finally:
        studio.stop()


def request(studio, method: str, path: str, body=None, *, token: str | None = "good", host: str | None = None,
            origin: str | None = None, content_type: str = "application/json") -> tuple[int, dict, bytes]:
    """(status, headers, body) of one request; ``token="good"`` sends the studio's token in the header."""
    conn = http.client.HTTPConnection("127.0.0.1", studio.port, timeout=60)
    headers = {"Host": f"127.0.0.1:{studio.port}" if host is None else host}
    if token is not None:
        headers["X-Studio-Token"] = studio.token if token == "good" else token
    if origin is not None:
        headers["Origin"] = origin
    data = None
    if body is not None:
        data = body if isinstance(body, bytes) else json.dumps(body).encode()
        headers["Content-Type"] = content_type
    conn.request(method, path, body=data, headers=headers)
    response = conn.getresponse()
    out = response.status, {k.lower(): v for k, v in response.getheaders()}, response.read()
    conn.close()
    return out


def api(studio, path: str, body=None) -> dict:
    status, _, raw = request(studio, "POST" if body is not None else "GET", path, body)
    assert status == 200, raw
    return json.loads(raw, parse_constant=lambda c: pytest.fail(f"{c} in a studio answer"))


#: kind -> the free variables ``moved_values`` moves (default: all).  guide_way's 48 are control points of the claw
#: path: all moved up at once shift the loop 12 mm, into the circle R - d the claw cannot reach; control point 4
#: lies on stretch E-D away from the fold (moved up, its curve bends less tight: the undercut margin changes sign)
MOVED = {"guide_way": ("P4_x", "P4_y")}


def moved_values(session, fraction: float = 0.3) -> dict[str, float]:
    """Each free variable of ``MOVED`` (default: every one) moved ``fraction`` of the way from its given value to
    its upper bound."""
    only = MOVED.get(session.kind)
    return {v.name: v.value + fraction * (v.bounds[1] - v.value) for v in session.free
            if only is None or v.name in only}
