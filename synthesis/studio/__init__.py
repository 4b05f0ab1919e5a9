"""``agrisynth studio``: a local interactive design page.

Move a design value, see the mechanism, its path and every rule margin of the kind's own ``check``
redrawn; solve from there with the kind's NLP (the solve run of ``agrisynth solve``, in a worker process);
save the values as a spec.  Served on 127.0.0.1 only, behind a random token; needs the ``studio`` extra
(starlette, uvicorn).  :mod:`.session` evaluates, :mod:`.grids` says on which grid, :mod:`.drawing`
reads what to draw from the check's result, :mod:`.solver` runs solves in :mod:`.worker` (the run's events
sent as JSON lines), :mod:`.server` serves the page.
"""

from __future__ import annotations

from pathlib import Path

#: the folder the running ``synthesis`` package was imported from
_PACKAGE = Path(__file__).resolve().parent.parent


def install_command(package: Path = _PACKAGE) -> str:
    """The command that adds the studio extra to the install at hand: a source checkout (the package's folder has
    the project's pyproject.toml beside it: an editable install or a checkout on PYTHONPATH) is installed editable
    from that folder; an installed copy (site-packages) from the package index."""
    root = Path(package).parent
    if (root / "pyproject.toml").is_file():
        return f"pip install -e '{root}[studio]'"
    return "pip install 'agrisynth[studio]'"


def missing_extra_text(module: str | None, package: Path = _PACKAGE) -> str:
    """The one line `agrisynth studio` says when a module of the studio extra is missing."""
    return f"agrisynth studio needs the studio extra ({module} is missing): {install_command(package)}"
