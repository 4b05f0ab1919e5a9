"""IPOPT's functions as compiled C, cached on disk: the NLP's objective, rows and CasADi's exact derivatives of them
(the gradient, the rows' Jacobian, the Lagrangian's Hessian) generated as C by CasADi's code generator, compiled by
the machine's C compiler into a shared library once per NLP, and loaded by every later build of the same NLP.

Why: CasADi evaluates an SX function by interpreting its instruction list; a start of the planting arm spends most
of its IPOPT time in the Hessian of the Lagrangian (about 530,000 instructions).  Compiled, a planting start takes
32 ms instead of 98, and a build that finds its library skips the symbolic Hessian: the 32-start multistart is 2.4x
faster.  The price is the first compile: seconds to minutes (steering's 12 s, the planting arm's about two and a half
minutes: gcc -O1 on 19 MB of C).

The answer is the interpreter's to the bit: the generated C performs the interpreter's operations in its order, and
is compiled without reassociation or contraction of floating-point operations (``-O1 -ffp-contract=off``, no
``-ffast-math``), calling the same C math library (tests/test_compiled_code.py compares the two solves of library
specs of several kinds, bit for bit).

The library's name is a hash of what makes it: CasADi's version, the compiler's identity and flags, the nlpsol
options that change which functions are generated (``GENERATION_OPTIONS``), and the NLP's function (x, p) -> (f, g)
serialised -- so a change of the spec that reaches the NLP's expressions (a constant, a
sample count) is a new library, and one that does not (bounds, rule limits, which are IPOPT's bounds) finds the
old one.  Libraries are written beside each other under one folder (the run's output folder's ``.compiled/``), each
compiled in a temporary folder there and moved into place in one step, so two runs compiling the same NLP at once
leave one whole library.
"""

from __future__ import annotations

import errno
import functools
import hashlib
import os
import shlex
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca

from synthesis.errors import AgrisynthError

#: no reassociation, no fused multiply-add: the interpreter's operations in its order (module docstring)
FLAGS = ("-O1", "-ffp-contract=off", "-fno-fast-math", "-fPIC", "-shared")
#: the compiler: $CC, else cc
COMPILER_VARIABLE = "CC"
#: the libraries' folder in a run's output folder (solve --compiled, bench --compiled)
CACHE_FOLDER = ".compiled"


#: a temporary compile folder this old was left by a killed run (a compile takes minutes at most): removed
STALE_S = 24 * 3600.0
#: nlpsol options that change which functions CasADi generates (the others -- IPOPT's tolerances, its barrier, the
#: printing, the iteration callback -- are read at run time, so one library serves them all)
GENERATION_OPTIONS = ("ipopt.hessian_approximation", "ipopt.gradient_approximation", "ipopt.jacobian_approximation")
RUN_TIME_OPTIONS = ("print_time", "show_eval_warnings", "iteration_callback")

_compiled_s = [0.0]     # seconds this process spent compiling (compile_seconds)


class CompiledCodeError(AgrisynthError):
    """Compiled derivatives were asked for and cannot be made or loaded here (exit 2).  Not an OutputError: the run
    has nothing to keep, so its staging folder is discarded like any failed set-up's."""


class CompilerMissing(CompiledCodeError):
    """Compiled derivatives were asked for and the machine has no C compiler to make them (exit 2)."""


def compile_seconds() -> float:
    """The seconds this process has spent compiling libraries so far (a run reads it before and after)."""
    return _compiled_s[0]


def compiler() -> list[str]:
    """The C compiler's command ($CC -- its first word the program, as make reads it, e.g. "ccache gcc" -- or cc),
    or CompilerMissing saying what to do."""
    given = os.environ.get(COMPILER_VARIABLE, "").strip()
    try:
        words = shlex.split(given) if given else ["cc"]
    except ValueError as exc:       # an unbalanced quote
        raise CompilerMissing(f"compiled derivatives: ${COMPILER_VARIABLE} = {given!r} is no command ({exc}): set $CC "
                              f"to a compiler (e.g. gcc), or solve without --compiled") from None
    found = shutil.which(words[0])
    if found is None:
        raise CompilerMissing(f"compiled derivatives need a C compiler, and {words[0]!r} was not found"
                              f"{' ($' + COMPILER_VARIABLE + ')' if given else ''}: "
                              f"install gcc (Debian: apt-get install gcc) or set $CC, or solve without --compiled")
    return [found, *words[1:]]


def cache_folder(out: Path) -> Path:
    """The libraries' folder of runs written into ``out`` (``out/.compiled``, absolute), once a compiler is found:
    CompilerMissing before any folder is made (solve --compiled, bench --compiled)."""
    compiler()
    return (Path(out) / CACHE_FOLDER).resolve()


@functools.lru_cache(maxsize=None)
def _compiler_identity(command: tuple[str, ...]) -> str:
    """The compiler's version and target (a library made by another compiler is another library)."""
    said = [subprocess.run([*command, flag], capture_output=True, text=True, check=False,
                           env={**os.environ, "LC_ALL": "C"}).stdout.strip()
            for flag in ("--version", "-dumpmachine")]
    return "\n".join([" ".join(command), *said])


def _generation_options(opts: dict) -> str:
    return repr(sorted((k, repr(v)) for k, v in opts.items()
                       if k in GENERATION_OPTIONS or not (k.startswith("ipopt.") or k in RUN_TIME_OPTIONS)))


def library_name(problem: str, nlp: dict, command: list[str], opts: dict | None = None) -> str:
    """The library's file name for this NLP (module docstring: what its hash covers; ``opts``: those of them that
    change the generated functions)."""
    oracle = ca.Function("nlp", [nlp["x"], nlp.get("p", ca.SX(0, 1))], [nlp["f"], nlp["g"]])
    key = hashlib.sha256()
    for part in (str(getattr(ca, "__version__")), _compiler_identity(tuple(command)), " ".join(FLAGS),
                 _generation_options(opts or {}), oracle.serialize()):
        key.update(part.encode())
        key.update(b"\0")
    safe = "".join(c if c.isalnum() or c == "_" else "_" for c in problem)
    return f"{safe}-{key.hexdigest()[:24]}{'.dll' if os.name == 'nt' else '.so'}"


def _cannot_write(folder: Path, exc: OSError) -> CompiledCodeError:
    return CompiledCodeError(f"compiled derivatives: cannot write the library into {folder}: {exc.strerror or exc}")


def _no_exec(folder: Path) -> bool:
    """Whether the folder's file system may not run code (mounted noexec; a platform without statvfs: not known,
    False)."""
    statvfs, flag = getattr(os, "statvfs", None), getattr(os, "ST_NOEXEC", 0)
    return bool(statvfs is not None and flag and statvfs(folder).f_flag & flag)


def _remove_stale(folder: Path) -> None:
    """Temporary compile folders a killed run left (older than STALE_S)."""
    now = time.time()
    for left in folder.glob(".compiling-*"):
        try:
            if now - left.stat().st_mtime > STALE_S:
                shutil.rmtree(left, ignore_errors=True)
        except OSError:
            continue


def library_for(problem: str, nlp: dict, opts: dict, folder: Path, build) -> tuple[Path, bool]:
    """(the compiled library of the NLP in ``folder``, whether it was compiled now: it was not there; the seconds are
    added to :func:`compile_seconds`).  ``build(nlp, opts)`` makes the interpreted solver whose functions are
    generated (the exact derivatives CasADi would evaluate)."""
    command = compiler()
    folder = Path(folder)
    path = folder / library_name(problem, nlp, command, opts)
    if path.is_file():
        return path, False
    t0 = time.perf_counter()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if _no_exec(folder):
            raise CompiledCodeError(f"compiled derivatives: {folder} is on a file system that may not run code "
                                    f"(noexec), so a library compiled there could not be loaded: give another --out, "
                                    f"or solve without --compiled")
        _remove_stale(folder)
        tmp = tempfile.mkdtemp(dir=folder, prefix=".compiling-")
    except OSError as exc:
        raise _cannot_write(folder, exc) from None
    try:
        solver = build(nlp, opts)
        code = ca.CodeGenerator("nlp_functions.c")
        code.add(solver.oracle())               # "nlp": (x, p) -> (f, g), which nlpsol reads first
        for name in solver.get_function():      # nlp_f, nlp_g, nlp_grad, nlp_grad_f, nlp_jac_g, nlp_hess_l
            code.add(solver.get_function(name))
        # written here, not by CasADi, whose writer says nothing when the disk fills (a cut file, then gcc's
        # syntax errors); gcc's own temporary files go into the same folder, under OUT, not $TMPDIR
        source = Path(tmp) / "nlp_functions.c"
        source.write_text(code.dump())
        made = Path(tmp) / path.name
        run = subprocess.run([*command, *FLAGS, str(source), "-o", str(made), "-lm"], capture_output=True,
                             text=True, check=False, env={**os.environ, "TMPDIR": tmp, "LC_ALL": "C"})
        if run.returncode != 0 or not made.is_file():
            said = (run.stderr or run.stdout).strip().splitlines()
            if any("No space left on device" in line for line in said):     # gcc's .s, .o or the library
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            first = next((line for line in said if "error" in line.lower()), said[0] if said else "")
            raise CompilerMissing(f"compiled derivatives: {' '.join(command)} could not compile the NLP of {problem} "
                                  f"(exit {run.returncode}{': ' + first.strip() if first else ''}); solve without "
                                  f"--compiled")
        with open(made, "rb") as handle:        # on disk before its name is: no empty library after a power loss
            os.fsync(handle.fileno())
        os.replace(made, path)
    except OSError as exc:          # the disk filled, the folder went away
        raise _cannot_write(folder, exc) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    _compiled_s[0] += time.perf_counter() - t0
    return path, True


def load(problem: str, nlp: dict, opts: dict, folder: Path, build, make) -> "ca.Function":
    """IPOPT's solver on the compiled library of the NLP (:func:`library_for`): ``make(path)``.  A library that was
    there but cannot be loaded (cut short by a power loss) is compiled once more; one compiled now that cannot be
    loaded is said in one line (CompiledCodeError)."""
    path, compiled_now = library_for(problem, nlp, opts, folder, build)
    try:
        return make(path)
    except RuntimeError as exc:
        if compiled_now:
            raise _not_loadable(path, exc) from None
        try:
            path.unlink(missing_ok=True)
        except OSError:
            pass
    path, _ = library_for(problem, nlp, opts, folder, build)
    try:
        return make(path)
    except RuntimeError as exc:
        raise _not_loadable(path, exc) from None


def _not_loadable(path: Path, exc: RuntimeError) -> CompiledCodeError:
    said = [line.strip() for line in str(exc).strip().splitlines()]
    # CasADi tries the path under several search prefixes and says each loader's reason on an "Error code: ..." line;
    # the one of the path itself is the reason (the others say that a made-up path does not exist)
    codes = [line for line in said if line.startswith("Error code")]
    why = next((line for line in codes if line.startswith(f"Error code: {path}:")),
               next((line for line in codes if "No such file" not in line), ""))
    return CompiledCodeError(f"compiled derivatives: the library {path} cannot be loaded"
                             f"{' (' + why + ')' if why else ''}: give another --out, or solve without --compiled")
