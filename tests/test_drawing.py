"""A run's figures drawn side by side (synthesis/report/drawing.py): the same files and outcomes as drawn in turn."""

from __future__ import annotations

import os
import warnings

import pytest

from synthesis.report.drawing import draw_all, groups


def test_the_animation_gets_a_core_of_its_own():
    assert groups(["a.png", "b.svg", "c.gif", "d.csv"], 2) == [["c.gif"], ["a.png", "b.svg", "d.csv"]]
    assert groups(["a.png", "c.gif", "e.gif"], 2) == [["c.gif", "e.gif"], ["a.png"]]
    assert groups(["a.png", "b.png", "c.png"], 4) == [["a.png"], ["b.png"], ["c.png"]]
    assert groups(["a.png", "c.gif"], 1) == [["a.png", "c.gif"]]
    assert groups([], 2) == []


def _writers():
    def text(value):
        def write(path):
            path.write_text(value)
        return write

    def fails(path):
        path.write_text("half")
        raise RuntimeError("out of ink")

    def warns(path):
        warnings.warn("a library said this", UserWarning)
        path.write_text("warned")

    def dies(path):
        os._exit(3)          # a drawing process that ends without reporting (a crash in native code)

    return {"a.png": text("A"), "b.gif": text("B"), "c.csv": fails, "d.svg": warns, "e.dxf": dies}


@pytest.mark.parametrize("cores", [2, 3])
def test_side_by_side_gives_what_drawing_in_turn_gives(tmp_path, cores):
    """Each file written or named with its reason, in the writers' order, with what the libraries said; a failed
    file is removed; a drawing process that dies names its files.  In turn (one core) the dying writer would end
    this test's process, so it is left out of that run and its outcome checked on its own."""
    serial_writers = {k: v for k, v in _writers().items() if k != "e.dxf"}
    (tmp_path / "serial").mkdir()
    (tmp_path / "parallel").mkdir()
    serial = draw_all(serial_writers, tmp_path / "serial", cores=1)
    parallel = draw_all(serial_writers, tmp_path / "parallel", cores=cores)
    assert [(d.name, d.error) for d in parallel] == [(d.name, d.error) for d in serial]
    assert [d.name for d in serial] == ["a.png", "b.gif", "c.csv", "d.svg"]
    assert serial[2].error == "RuntimeError: out of ink" and not (tmp_path / "parallel" / "c.csv").exists()
    assert "a library said this" in serial[3].said and "a library said this" in parallel[3].said
    for name in ("a.png", "b.gif", "d.svg"):
        assert (tmp_path / "serial" / name).read_text() == (tmp_path / "parallel" / name).read_text()
    (tmp_path / "dying").mkdir()
    # the dying writer named as an animation: a group of its own, drawn in a forked process (this process draws the
    # last group itself, and would end with it)
    dying = {"e.gif": _writers()["e.dxf"], "a.png": _writers()["a.png"]}
    assert groups(list(dying), 2) == [["e.gif"], ["a.png"]]
    out = {d.name: d for d in draw_all(dying, tmp_path / "dying", cores=2)}
    assert out["a.png"].error is None
    assert out["e.gif"].error.startswith("RuntimeError: the drawing process ended (exit code 3)")


def test_a_group_whose_process_cannot_start_is_drawn_here(tmp_path, monkeypatch):
    """No process or pipe left (fork fails): every file is still drawn, in turn, and nothing is lost."""
    def no_fork():
        raise BlockingIOError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(os, "fork", no_fork)
    writers = {k: v for k, v in _writers().items() if k not in ("c.csv", "e.dxf")}
    out = draw_all(writers, tmp_path, cores=2)
    assert [(d.name, d.error) for d in out] == [("a.png", None), ("b.gif", None), ("d.svg", None)]
    assert (tmp_path / "b.gif").read_text() == "B"


def test_a_drawing_process_that_dies_mid_group_keeps_what_it_finished(tmp_path):
    """Files are reported one by one: those written before the process died count; the one it died on is named
    with why and nothing of it is left, not even an atomic write's temporary file."""
    def dies_after_a_temporary(path):
        (path.parent / f".{path.name}.tmp123{path.suffix}").write_text("partial")
        os._exit(5)

    writers = {"x.gif": _writers()["b.gif"], "y.gif": dies_after_a_temporary, "a.png": _writers()["a.png"]}
    # cores=2: the two animations share the forked group, the png is drawn here
    assert groups(list(writers), 2) == [["x.gif", "y.gif"], ["a.png"]]
    out = {d.name: d for d in draw_all(writers, tmp_path, cores=2)}
    assert out["x.gif"].error is None and (tmp_path / "x.gif").read_text() == "B"
    assert out["y.gif"].error.startswith("RuntimeError: the drawing process ended (exit code 5)")
    assert not list(tmp_path.glob("*y.gif*")) and out["a.png"].error is None
