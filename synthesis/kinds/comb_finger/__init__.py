"""Kind comb_finger: the eccentric rotating comb fingers of seed 002 §四.3 (eq 14-22, Fig. 26-28).

geometry.py  the front view of Fig. 28b reconstructed, eq 17-22 derived and as printed (floats, CasADi)
dynamics.py  the inverse dynamics of one unit at constant speed (an optional [dynamics] table; imported only then)
check.py, nlp.py, solve.py, plots.py: the kind of the CLI
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Poses, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/comb_finger/parts.py)."""
    from synthesis.kinds.comb_finger import parts

    return parts


class CombFinger(Kind):
    name = "comb_finger"
    summary = "eccentric rotating comb fingers: largest combing angle with root-zone and unit clearances (seed 002 §四.3 eq 17-22)"
    objectives = {"max_combing_angle": "largest combing angle theta at the machine speed (eq 21), deg"}
    example = "comb_finger/redesign_max_combing.toml"
    bench_specs = ("comb_finger/redesign_max_combing.toml", "comb_finger/redesign_tip_speed.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.comb_finger.spec import CombFingerSpec

        return CombFingerSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"comb_finger.png": _parts().finger_figure,
                "comb_finger.svg": _parts().finger_figure}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figure


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE

    def poses(self) -> Poses:
        return _parts().POSES


KIND = CombFinger()

