"""Record every library spec's answers: ``check``'s whole result and, for specs with free variables, ``solve``'s
(the spec's own starts and seed, one worker), with what varies from run to run (wall times, versions) removed.

A restructuring that must change no answer is proven by recording before and after and comparing the two files
byte for byte::

    python studies/library_answers.py before.json [--all]
    ... change the code ...
    python studies/library_answers.py after.json [--all] && cmp before.json after.json

``--only TEXT`` records only the specs whose path under problems/ contains TEXT (e.g. ``--only picker/``).

Without ``--all`` the tolerance-robust and envelope specs (minutes each) are left out.  A study, not part of the
installed tool or the test suite.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

LIBRARY = Path(__file__).resolve().parents[1] / "problems"
#: specs whose solve takes minutes: only with --all
SLOW = ("robust_", "envelope_", "mu_envelope")
VOLATILE = ("time", "seconds", "wall", "versions", "elapsed", "cpu")


def _stable(value):
    """The value with every key naming a time or a version dropped, at any depth."""
    if isinstance(value, dict):
        return {k: _stable(v) for k, v in value.items() if not any(w in k.lower() for w in VOLATILE)}
    if isinstance(value, list):
        return [_stable(v) for v in value]
    return value


def answers(spec_path: Path, solve: bool) -> dict:
    from synthesis import kinds
    from synthesis.kinds import solve_spec
    from synthesis.errors import AgrisynthError
    from synthesis.spec import load_spec

    loaded = load_spec(spec_path)
    kind = kinds.get(loaded.kind)
    out = {"check": _stable(kind.check(loaded).to_json())}
    if kind.solves and solve:
        try:
            solved = solve_spec(loaded, workers=1)[0]
            out["solve"] = _stable(solved.to_json())
        except AgrisynthError as err:
            out["solve"] = {"exit": err.exit_code}
    return out


def main(argv: list[str]) -> int:
    out = Path(argv[0])
    every = "--all" in argv
    only = argv[argv.index("--only") + 1] if "--only" in argv else ""
    record = {}
    for path in sorted(LIBRARY.rglob("*.toml")):
        name = str(path.relative_to(LIBRARY))
        if only not in name:
            continue
        solve = every or not any(s in path.name for s in SLOW)
        print(name, "check + solve" if solve else "check", file=sys.stderr, flush=True)
        record[name] = answers(path, solve)
    out.write_text(json.dumps(record, indent=1, sort_keys=True, allow_nan=True) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
