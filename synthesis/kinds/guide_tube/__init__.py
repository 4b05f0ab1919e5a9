"""Guide tubes of seed 001 §2.4: wall angles that make every pot seedling land at the same time.

drag.py   closed forms of straight-line motion with quadratic drag (floats and CasADi symbols)
drop.py   the five-phase drop through one tube (eq 13-23), closed form
slope.py  the analytic derivative dt_z/d(delta) of the closed form (checks CasADi's AD)
ode.py    the same drop integrated with scipy solve_ivp, phase switches as events
calibrate.py friction coefficient from a measured landing time
scene.py, check.py, nlp.py, solve.py, plots.py: the guide_tube kind of the CLI
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from synthesis.core.kind import FixedBy, Kind

if TYPE_CHECKING:
    from synthesis.core.kind import CoarseCheck, CompareWriter, FigureWriter, Solving, SpecModel
    from synthesis.result import Result
    from synthesis.spec import LoadedSpec


def _parts():
    """The kind's modules (check, solve, figures ...), imported once on first use: listing kinds imports
    none of them (synthesis/kinds/guide_tube/parts.py)."""
    from synthesis.kinds.guide_tube import parts

    return parts


class GuideTube(Kind):
    name = "guide_tube"
    summary = "guide-tube wall angles for equal landing times (seed 001 §2.4)"
    objectives = {"nearest": "smallest change of the free wall angles, deg^2",
                  "fastest": "earliest landing of tube 1, ms",
                  "uniform": "smallest worst plant-position error over the row spacings, mm"}
    example = "guide_tube/cai2020_delta2.toml"
    bench_specs = ("guide_tube/cai2020_delta2.toml", "guide_tube/fastest_equal_time.toml")

    def spec_model(self) -> type[SpecModel]:
        from synthesis.kinds.guide_tube.spec import GuideTubeSpec

        return GuideTubeSpec

    def check(self, loaded: LoadedSpec) -> Result:
        return _parts().run_check(loaded)

    def headline(self, result: Result) -> list[str]:
        return _parts().headline(result)

    def rule_fixed_by(self, rule_name: str) -> FixedBy | None:
        """A tube's own rules (``wall_exit_speed_<tube>``, ``free_fall_height_<tube>``) are fixed by that tube's entry
        where its angle is a number: a tube given whole is no design variable."""
        for prefix, limits in (("wall_exit_speed_", "[rules] min_exit_speed"),
                               ("free_fall_height_", "[rules] min_free_fall")):
            if rule_name.startswith(prefix):
                tube = rule_name[len(prefix):].split("@", 1)[0]
                return FixedBy(f"tube {tube}'s angle, l3, h5 and h6 in [[tubes]]", limits)
        return None

    def solving(self) -> Solving:
        return _parts().SOLVING

    def figures(self) -> dict[str, FigureWriter]:
        return {"drop_times.png": _parts().drop_times_figure,
                "drop_times.svg": _parts().drop_times_figure,
                "drop_profiles.png": _parts().drop_profile_figure,
                "sensitivity.png": _parts().sensitivity_figure}

    def compare_figures(self) -> CompareWriter:
        return _parts().compare_figures


    def coarse_check(self) -> CoarseCheck:
        return _parts().COARSE


KIND = GuideTube()

