"""Compiled derivatives (`solve --compiled`, synthesis.core.compiled_code): the same answer as CasADi's interpreter to
the bit, a library compiled once per NLP and found again, and a machine without a compiler told so in one line."""

from __future__ import annotations

import json
import math
import os
import shlex

import casadi as ca
import numpy as np
import pytest

from conftest import LIBRARY
from solving import agrisynth
from synthesis.constraints.base import Rule
from synthesis.core.compiled_code import CompilerMissing, compiler, library_name
from synthesis.core.ipopt import CompiledNLP, SolveMethod
from synthesis.core.problem import ObjectiveParts, Problem

def _compiler() -> list[str] | None:
    try:
        return compiler()
    except CompilerMissing:
        return None


pytestmark = pytest.mark.skipif(_compiler() is None, reason="no C compiler")


def _rosenbrock_in_a_disc(radius: float = 1.2) -> Problem:
    """min (1 - x)^2 + 100 (y - x^2)^2 s.t. x^2 + y^2 <= r^2: a curved valley, a Hessian that is not constant."""
    x = ca.SX.sym("x", 2)
    f = (1 - x[0]) ** 2 + 100 * (x[1] - x[0] ** 2) ** 2
    return Problem("rosenbrock", x, [-2.0, -2.0], [2.0, 2.0], [],
                   [Rule("disc", x[0] ** 2 + x[1] ** 2, None, radius ** 2, "mm^2", 1.0)], ObjectiveParts(f=f))


def test_a_compiled_solve_is_the_interpreted_one_to_the_bit_and_its_library_is_found_again(tmp_path):
    folder = tmp_path / "compiled"
    interpreted = CompiledNLP(_rosenbrock_in_a_disc())
    first = CompiledNLP(_rosenbrock_in_a_disc(), method=SolveMethod(compiled=str(folder)))
    again = CompiledNLP(_rosenbrock_in_a_disc(), method=SolveMethod(compiled=str(folder)))
    libraries = sorted(folder.glob("*.so"))
    assert len(libraries) == 1 and first.compile_s > 0.0 and again.compile_s == 0.0
    assert not [p for p in folder.iterdir() if p.name.startswith(".compiling-")]     # no temporary folder left
    for x0 in ([-1.2, 1.0], [0.5, -1.5], [1.9, 1.9]):
        a, b, c = (nlp.solve(0, np.array(x0)) for nlp in (interpreted, first, again))
        assert a.return_status == "Solve_Succeeded" and a.iterations > 5
        for other in (b, c):
            assert other.x.tobytes() == a.x.tobytes() and other.lam_g.tobytes() == a.lam_g.tobytes()
            assert other.iterations == a.iterations and other.objective == a.objective
    # the optimum on the disc's edge: x^2 + y^2 = 1.44 (the unconstrained minimum (1, 1) lies outside)
    assert math.isclose(float(np.sum(a.x ** 2)), 1.44, rel_tol=1e-7)


def test_the_library_is_named_by_the_nlps_expressions_not_its_bounds(tmp_path):
    """A bound (IPOPT's, not the NLP's functions) keeps the library; a constant in an expression makes another."""
    cc = compiler()
    x = ca.SX.sym("x", 2)

    def nlp(c):
        return {"x": x, "f": (x[0] - c) ** 2 + x[1] ** 2, "g": x[0] * x[1]}
    assert library_name("p", nlp(1.0), cc) == library_name("p", nlp(1.0), cc)
    assert library_name("p", nlp(1.0), cc) != library_name("p", nlp(1.0 + 2e-16 * 8), cc)
    # IPOPT's run-time options share a library; one that changes the generated functions (no Hessian) does not
    assert library_name("p", nlp(1.0), cc, {"ipopt.tol": 1e-9, "print_time": False}) == library_name("p", nlp(1.0), cc)
    assert library_name("p", nlp(1.0), cc, {"ipopt.hessian_approximation": "limited-memory"}) != library_name(
        "p", nlp(1.0), cc)
    method = SolveMethod(compiled=str(tmp_path))
    wide = CompiledNLP(_rosenbrock_in_a_disc(1.2), method=method)
    narrow = CompiledNLP(_rosenbrock_in_a_disc(1.1), method=method)        # the rule's limit: IPOPT's bound
    assert wide.compile_s > 0.0 and narrow.compile_s == 0.0 and len(list(tmp_path.glob("*.so"))) == 1


def test_compiled_derivatives_are_exact_derivatives():
    with pytest.raises(ValueError, match="compiled: the compiled functions are the exact derivatives"):
        SolveMethod(derivatives="finite_difference", compiled="somewhere")


@pytest.mark.slow
@pytest.mark.parametrize("spec", ["steering/steering_redesign_27.toml", "picker/cai2020_crank_rocker_synthesis.toml",
                                  "guide_tube/uniform_spacing.toml"])
def test_solve_compiled_writes_the_interpreted_runs_result(spec, tmp_path):
    """`solve --compiled` against `solve`: every start's design and objective and the answer, to the bit."""
    runs = {}
    for how, extra in (("interpreted", ()), ("compiled", ("--compiled",))):
        run = agrisynth("solve", str(LIBRARY / spec), "--starts", "4", "--workers", "1", "--out", str(tmp_path / how),
                        *extra, cwd=tmp_path)
        assert run.returncode in (0, 1), run.stderr
        folder = next(p for p in (tmp_path / how).iterdir() if not p.name.startswith("."))
        runs[how] = json.loads((folder / "result.json").read_text())
    assert "compiled derivatives" in run.stderr + run.stdout
    assert len(list((tmp_path / "compiled" / ".compiled").glob("*.so"))) >= 1
    a, b = runs["interpreted"], runs["compiled"]
    assert json.dumps(a["design"]) == json.dumps(b["design"]) and a["objective"] == b["objective"]
    assert a["status"] == b["status"] and a["solver"]["iterations"] == b["solver"]["iterations"]
    assert [json.dumps(s["design"]) for s in a["starts"]] == [json.dumps(s["design"]) for s in b["starts"]]
    assert [(s["objective"], s["iterations"]) for s in a["starts"]] == [(s["objective"], s["iterations"])
                                                                          for s in b["starts"]]
    assert a["solver"]["compiled"] is None and b["solver"]["compiled"]["compile_s"] >= 0.0


def test_no_compiler_is_said_in_one_line_before_any_folder_is_made(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-here")
    run = agrisynth("solve", str(LIBRARY / "steering" / "steering_redesign_27.toml"), "--compiled", "--out",
                    str(tmp_path / "out"), cwd=tmp_path)
    assert run.returncode == 2
    assert run.stderr.strip() == ("error: compiled derivatives need a C compiler, and 'no-such-compiler-here' was not "
                                  "found ($CC): install gcc (Debian: apt-get install gcc) or set $CC, or solve without "
                                  "--compiled")
    assert not (tmp_path / "out").exists()
    assert issubclass(CompilerMissing, Exception)


def test_compiled_is_for_local_workers(tmp_path):
    run = agrisynth("solve", str(LIBRARY / "steering" / "steering_redesign_27.toml"), "--compiled", "--scheduler",
                    "tcp://127.0.0.1:1", cwd=tmp_path)
    assert run.returncode == 2 and "--compiled" in run.stderr and "local workers only" in run.stderr


def test_a_library_folder_that_cannot_be_written_is_said_in_one_line(tmp_path):
    """OUT/.compiled a file (or a full disk): exit 2 naming the folder, no traceback."""
    spec = tmp_path / "steer.toml"
    spec.write_text((LIBRARY / "steering" / "steering_redesign_27.toml").read_text())
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / ".compiled").write_text("not a folder")
    run = agrisynth("solve", str(spec), "--compiled", "--starts", "1", "--workers", "1", "--out",
                    str(tmp_path / "out"), cwd=tmp_path)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "cannot write the library into" in lines[0]
    assert str(tmp_path / "out" / ".compiled") in lines[0] and "Traceback" not in run.stderr
    # a compiled-code error is no OutputError (whose run folder is kept, to say where): no staging folder is left
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [".compiled"]


@pytest.mark.slow
def test_bench_compiled_times_the_same_runs_compiled_beside_the_interpreted(tmp_path):
    run = agrisynth("bench", "--problems", "steering_redesign_40", "--quick", "--compiled", "--out", str(tmp_path),
                    cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    data = json.loads((tmp_path / "bench" / "bench.json").read_text())
    rows = {r["method"]: r for r in data["rows"]}
    ad, compiled = rows["ipopt_multistart"], rows["ipopt_compiled"]
    assert compiled["objective"] == ad["objective"]                 # the same runs, to the bit
    assert compiled["details"]["median_iterations"] == ad["details"]["median_iterations"]
    line = data["summary"][0]
    assert line["compiled_median_s"] == compiled["median_s"] and line["compiled_ipopt_ratio"].endswith("x")
    assert data["settings"]["study"]["compiled"] == str((tmp_path / ".compiled").resolve())
    assert list((tmp_path / ".compiled").glob("*.so"))
    assert "### Compiled derivatives (`--compiled`)" in (tmp_path / "bench" / "bench.md").read_text()


def test_a_library_that_cannot_be_loaded_is_compiled_again(tmp_path):
    """A file under the library's name that is no library (cut short by a power loss in an earlier run) is replaced,
    not trusted.  (The name is found by a first build in another folder: a library this process has loaded must not
    be cut under it.)"""
    probe = CompiledNLP(_rosenbrock_in_a_disc(), method=SolveMethod(compiled=str(tmp_path / "probe")))
    (library,) = (tmp_path / "probe").glob("*.so")
    (tmp_path / "cut").mkdir()
    cut = tmp_path / "cut" / library.name
    cut.write_bytes(b"")
    again = CompiledNLP(_rosenbrock_in_a_disc(), method=SolveMethod(compiled=str(tmp_path / "cut")))
    assert again.compile_s > 0.0 and cut.stat().st_size > 0
    a, b = (nlp.solve(0, np.array([-1.2, 1.0])) for nlp in (probe, again))
    assert a.x.tobytes() == b.x.tobytes()


def test_cc_may_carry_arguments_as_make_reads_it(tmp_path, monkeypatch):
    """CC="cc -O1" (ccache gcc, gcc -std=c99, ...): the first word is the program, the rest its arguments."""
    monkeypatch.setenv("CC", f"{shlex.join(compiler())} -O1")
    nlp = CompiledNLP(_rosenbrock_in_a_disc(), method=SolveMethod(compiled=str(tmp_path)))
    assert nlp.compile_s > 0.0 and nlp.solve(0, np.array([-1.2, 1.0])).return_status == "Solve_Succeeded"


def test_a_cc_that_is_no_command_is_said_in_one_line(monkeypatch):
    monkeypatch.setenv("CC", "gcc '-O1")
    with pytest.raises(CompilerMissing, match=r"\$CC = .* is no command .*: set \$CC to a compiler \(e\.g\. gcc\), or "
                                              r"solve without --compiled$"):
        compiler()


def test_a_folder_that_may_not_run_code_is_refused_before_compiling(tmp_path, monkeypatch):
    """A noexec mount would take the compile, then refuse to load its library: said before the compile."""
    import synthesis.core.compiled_code as code
    monkeypatch.setattr(code, "_no_exec", lambda folder: True)
    before = code.compile_seconds()
    with pytest.raises(code.CompiledCodeError, match="may not run code \\(noexec\\)"):
        CompiledNLP(_rosenbrock_in_a_disc(), method=SolveMethod(compiled=str(tmp_path)))
    assert not list(tmp_path.iterdir()) and code.compile_seconds() == before


@pytest.mark.skipif(not (hasattr(os, "statvfs") and hasattr(os, "ST_NOEXEC")), reason="no statvfs / ST_NOEXEC")
def test_the_noexec_check_reads_the_mount_flag(tmp_path, monkeypatch):
    import types

    import synthesis.core.compiled_code as code
    executable = not (os.statvfs(tmp_path).f_flag & os.ST_NOEXEC)
    assert code._no_exec(tmp_path) is not executable
    for flags, said in ((os.ST_NOEXEC | os.ST_NOSUID, True), (os.ST_NOSUID, False)):
        monkeypatch.setattr(code.os, "statvfs", lambda folder, f=flags: types.SimpleNamespace(f_flag=f))
        assert code._no_exec(tmp_path) is said


def test_a_library_that_cannot_be_loaded_is_said_with_the_loaders_reason(tmp_path):
    """CasADi tries several search prefixes; the reason is the path's own (a cut file: "file too short"), not a
    made-up path's "No such file"."""
    import synthesis.core.compiled_code as code
    cut = tmp_path / "cut.so"
    cut.write_bytes(b"\0" * 10)
    with pytest.raises(RuntimeError) as raised:
        ca.external("nlp", str(cut))
    said = str(code._not_loadable(cut, raised.value))
    assert "\n" not in said and str(cut) in said and "file too short" in said and "No such file" not in said
