"""``solve`` of a spec with a ``[tolerance]`` table: every rule held at its linearised worst case in the
tolerance box (the core transcription's robust form, :mod:`synthesis.core.transcribe`), for every kind.

:func:`robust_kind` wraps a kind's :class:`~synthesis.core.kind.Solving`: its NLP is built inside
:func:`~synthesis.core.transcribe.tolerance_box` (so the kind's own Problem is transcribed robustly, the kind
knowing nothing of it), the robust extra variables get their start values at each start, and the result
gets the Monte-Carlo check of the answer under ``facts.tolerance``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from synthesis.core.kind import Finished, Kind, Setting, Solving
from synthesis.core.problem import Problem, Tolerance
from synthesis.core.transcribe import tolerance_box
from synthesis.design_info import describe
from synthesis.tolerance.design import AFFINE, UNITS, DesignMap, box_of


def _box_text(spec) -> str:
    tol = spec.tolerance
    parts = [f"±{tol.length:g} mm" for _ in [0] if tol.length] + [f"±{tol.angle:g} deg" for _ in [0] if tol.angle]
    parts += [f"{k} ±{v:g}" for k, v in tol.variables.items()]
    return ", ".join(parts) or "none"


class _Resolver:
    """Problem -> its Tolerance, from the spec (names in the NLP's order are the spec's variables)."""

    def __init__(self, kind_name: str, spec):
        self.kind_name, self.spec = kind_name, spec

    def __call__(self, problem: Problem) -> Tolerance | None:
        info = describe(self.spec)
        names = list(info)
        n = len(names)
        affine = AFFINE.get(self.kind_name)
        d0, J = (np.zeros(n), np.eye(n)) if affine is None else affine(_Stub(self.spec), n)
        dmap = DesignMap(names, names, [info[k]["unit"] or UNITS.get(self.kind_name, "") for k in names], d0, J)
        tol = self.spec.tolerance
        return Tolerance(n, box_of(dmap, tol.length, tol.angle, dict(tol.variables)), J)


class _Stub:
    """What an AFFINE entry reads of an NLP, for kinds whose map does not depend on it."""

    def __init__(self, spec):
        self.spec = spec


def _padded(compiled):
    """compiled.solve with the robust extras' start values appended to the kind's own extras."""
    solve = compiled.solve

    def run(start, x0, extra0=None, p=None):
        return solve(start, x0, compiled.t.full_extra(extra0, x0, p), p)
    return run


@dataclasses.dataclass(frozen=True)
class RobustBuild:
    base: object
    kind_name: str

    def __call__(self, setting: Setting, elastic: bool = False):
        with tolerance_box(_Resolver(self.kind_name, setting.spec)):
            nlp = self.base(setting, elastic)
        for compiled in [getattr(nlp, "compiled", None), *getattr(nlp, "stages", [])]:
            if compiled is not None and compiled.t.robust is not None:
                compiled.solve = _padded(compiled)
        return nlp


@dataclasses.dataclass(frozen=True)
class RobustFinish:
    base: object
    kind: Kind

    def __call__(self, setting: Setting, best) -> Finished:
        from synthesis.tolerance.analysis import monte_carlo
        finished = self.base(setting, best)
        spec, tol = setting.spec, setting.spec.tolerance
        facts = dict(finished.facts)
        if best.satisfied:
            info = describe(spec)
            names = list(info)
            n = len(names)
            dmap = DesignMap(names, names, [info[k]["unit"] or UNITS.get(self.kind.name, "") for k in names],
                             np.zeros(n), np.eye(n))
            box = box_of(dmap, tol.length, tol.angle, dict(tol.variables))
            design = {k: float(best.outcome.design[k]) for k in names}
            mc = monte_carlo(self.kind, spec, design, dmap, box, tol.samples, tol.seed)
            facts["tolerance"] = {"box": {k: float(b) for k, b in zip(names, box)}, "monte_carlo": mc,
                                  "held_at": "linearised worst case of every rule row in the box"}
        return dataclasses.replace(finished, facts=facts)


def robust_kind(kind: Kind, spec) -> Kind:
    """The kind, solving with the spec's ``[tolerance]`` box (the kind itself when the spec has none)."""
    if getattr(spec, "tolerance", None) is None:
        return kind
    base = kind.solver_side()
    hint = (f"The rules are held at their linearised worst case in the tolerance box ({_box_text(spec)}): "
            f"loosen the tolerances of the [tolerance] table, or those rules. ")
    solving = dataclasses.replace(base, build=RobustBuild(base.build, kind.name), finish=RobustFinish(base.finish, kind),
                                  relax_hint=hint + base.relax_hint)

    class _Kind(Kind):
        def solver_side(self) -> Solving:      # noqa: D102
            return solving
    return _Kind(**{f.name: getattr(kind, f.name) for f in dataclasses.fields(kind)})
