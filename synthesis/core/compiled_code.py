"""IPOPT's functions as compiled C, cached on disk: the NLP's objective, rows and CasADi's exact derivatives of them
(the gradient, the rows' Jacobian, the Lagrangian's Hessian) generated as C by CasADi's code generator, compiled by
the machine's C compiler into a shared library once per NLP, and loaded by every later build of the same NLP.

Why: CasADi evaluates an SX function by interpreting its instruction list; a start of the planting arm spends most
of its IPOPT time in the Hessian of the Lagrangian (about 530,000 instructions).  Compiled, the same instructions
run about 3x faster per start, and a build that finds its library skips the symbolic Hessian as well.  The price is
the first compile: seconds for a small NLP, about two minutes for the planting arm's (gcc -O1 on 19 MB of C).

The answer is the interpreter's to the bit: the generated C performs the interpreter's operations in its order, and
is compiled without reassociation or contraction of floating-point operations (``-O1 -ffp-contract=off``, no
``-ffast-math``), calling the same C math library (tests/test_compiled_code.py compares the two solves of library
specs of several kinds, bit for bit).

The library's name is a hash of what makes it: CasADi's version, the compiler's identity and flags, and the NLP's
function (x, p) -> (f, g) serialised -- so a change of the spec that reaches the NLP's expressions (a constant, a
sample count) is a new library, and one that does not (bounds, rule limits, which are IPOPT's bounds) finds the
old one.  Libraries are written beside each other under one folder (the run's output folder's ``.compiled/``), each
compiled in a temporary folder there and moved into place in one step, so two runs compiling the same NLP at once
leave one whole library.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca

from synthesis.errors import AgrisynthError, OutputError

#: no reassociation, no fused multiply-add: the interpreter's operations in its order (module docstring)
FLAGS = ("-O1", "-ffp-contract=off", "-fno-fast-math", "-fPIC", "-shared")
#: the compiler: $CC, else cc
COMPILER_VARIABLE = "CC"
#: the libraries' folder in a run's output folder (solve --compiled, bench --compiled)
CACHE_FOLDER = ".compiled"


class CompilerMissing(AgrisynthError):
    """Compiled derivatives were asked for and the machine has no C compiler to make them (exit 2)."""


def compiler() -> str:
    """The C compiler's path ($CC or cc), or CompilerMissing saying what to do."""
    name = os.environ.get(COMPILER_VARIABLE) or "cc"
    found = shutil.which(name)
    if found is None:
        raise CompilerMissing(f"compiled derivatives need a C compiler, and {name!r} was not found"
                              f"{' ($' + COMPILER_VARIABLE + ')' if os.environ.get(COMPILER_VARIABLE) else ''}: "
                              f"install gcc (Debian: apt-get install gcc) or set $CC, or solve without --compiled")
    return found


@functools.lru_cache(maxsize=None)
def _compiler_identity(path: str) -> str:
    """The compiler's version and target (a library made by another compiler is another library)."""
    said = [subprocess.run([path, flag], capture_output=True, text=True, check=False).stdout.strip()
            for flag in ("--version", "-dumpmachine")]
    return "\n".join([path, *said])


def library_name(problem: str, nlp: dict, cc: str) -> str:
    """The library's file name for this NLP (module docstring: what its hash covers)."""
    oracle = ca.Function("nlp", [nlp["x"], nlp.get("p", ca.SX(0, 1))], [nlp["f"], nlp["g"]])
    key = hashlib.sha256()
    for part in (str(getattr(ca, "__version__")), _compiler_identity(cc), " ".join(FLAGS), oracle.serialize()):
        key.update(part.encode())
        key.update(b"\0")
    safe = "".join(c if c.isalnum() or c == "_" else "_" for c in problem)
    return f"{safe}-{key.hexdigest()[:24]}{'.dll' if os.name == 'nt' else '.so'}"


def library_for(problem: str, nlp: dict, opts: dict, folder: Path, build) -> tuple[Path, float]:
    """(the compiled library of the NLP, the seconds spent compiling it: 0 when it was there).  ``build(nlp, opts)``
    makes the interpreted solver whose functions are generated (the exact derivatives CasADi would evaluate)."""
    cc = compiler()
    folder = Path(folder)
    path = folder / library_name(problem, nlp, cc)
    if path.is_file():
        return path, 0.0
    t0 = time.perf_counter()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tmp = tempfile.mkdtemp(dir=folder, prefix=".compiling-")
    except OSError as exc:
        raise OutputError(f"compiled derivatives: cannot write the library into {folder}: "
                          f"{exc.strerror or exc}") from None
    try:
        solver = build(nlp, opts)
        code = ca.CodeGenerator("nlp_functions.c")
        code.add(solver.oracle())               # "nlp": (x, p) -> (f, g), which nlpsol reads first
        for name in solver.get_function():      # nlp_f, nlp_g, nlp_grad, nlp_grad_f, nlp_jac_g, nlp_hess_l
            code.add(solver.get_function(name))
        source = Path(code.generate(tmp + os.sep))
        made = Path(tmp) / path.name
        run = subprocess.run([cc, *FLAGS, str(source), "-o", str(made), "-lm"], capture_output=True, text=True,
                             check=False)
        if run.returncode != 0 or not made.is_file():
            said = (run.stderr or run.stdout).strip().splitlines()
            raise CompilerMissing(f"compiled derivatives: {cc} could not compile the NLP of {problem} (exit "
                                  f"{run.returncode}{': ' + said[-1] if said else ''}); solve without --compiled")
        os.replace(made, path)
    except OSError as exc:          # the disk filled, the folder went away
        raise OutputError(f"compiled derivatives: cannot write the library into {folder}: "
                          f"{exc.strerror or exc}") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return path, time.perf_counter() - t0
