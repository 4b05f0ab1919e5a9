"""``agrisynth bench``: objective reached and wall time of several methods on the same problems.

Generic over problem kinds.  A kind declares a function that turns problems into
:class:`BenchCase` objects (its ``Kind.bench``, see :mod:`synthesis.kinds`); this module runs every method of every case ``repeats``
times, takes the median wall time (:mod:`synthesis.bench.case`), and writes ``OUT/bench/bench.json``, ``bench.md``
and ``error_vs_time.png`` (accuracy -- objective gap to the best known, worst fine-grid rule violation -- against
wall time; :mod:`synthesis.bench.output`).  ``--quick`` is an explicit argument of the functions that make the
cases (:func:`cases_for`, :func:`study_settings`).

Equal objective tolerance: each case has a target objective (best known + tolerance) and every
method stops as soon as it reaches it, or at its own convergence / budget otherwise.  A run reaches
the target when its objective is at most the target *and* every rule holds on the fine re-check
grid.  Each run's *time to target* is the moment it first met the target (:func:`time_to_target`;
a method that goes on past it is not charged for the rest); a row's ``time_to_target_s`` is the median
over its runs when every run reached the target, else null and "target not reached".  The time ratio
(method's median time to target / the reference method's) so compares times to the same target, and
exists only when every run of both methods reached it; otherwise ``time_ratio`` is null and
``time_ratio_note`` says "n/a (target not reached)" and by which methods.
"""

from __future__ import annotations

import dataclasses

from synthesis import kinds
from synthesis.bench.case import (NOT_REACHED, PEERS, TARGET_NOT_REACHED, BenchCase, MethodRun, reached, run_case,
                                  time_ratio, time_to_target)
from synthesis.bench.generic import FULL, LIBRARY, QUICK, StudySettings, case_for, library_cases
from synthesis.bench.output import (COUNT_COLUMNS, _write_bench_files, machine, markdown, summary, sweep_plot_name,
                                    write_bench, write_bench_files)
from synthesis.report.bench_plots import best_so_far, plot_error_vs_time, plot_sample_sweep
from synthesis.spec import load_spec

__all__ = ["NOT_REACHED", "PEERS", "TARGET_NOT_REACHED", "BenchCase", "MethodRun", "reached", "run_case", "time_ratio",
           "time_to_target", "FULL", "QUICK", "StudySettings", "COUNT_COLUMNS", "machine", "markdown", "summary",
           "sweep_plot_name", "write_bench", "best_so_far", "plot_error_vs_time", "plot_sample_sweep",
           "study_settings", "kinds_with_bench", "cases_for", "OWN_CASES_IN_EVERY_KIND_RUN", "_write_bench_files",
           "write_bench_files"]


def study_settings(quick: bool = False, compiled: str | None = None) -> StudySettings:
    """How much each generic study runs: ``--quick``'s settings or the full ones; ``compiled`` (a folder): with the
    compiled-derivatives method."""
    settings = QUICK if quick else FULL
    return settings if compiled is None else dataclasses.replace(settings, compiled=compiled)


def kinds_with_bench() -> list[str]:
    return [k.name for k in kinds.all_kinds() if k.benches]


#: an every-kind run (``agrisynth bench`` with no KIND) takes at most this many of a kind's own
#: (non-generic) default cases; ``agrisynth bench KIND`` runs them all
OWN_CASES_IN_EVERY_KIND_RUN = 1


def cases_for(kind: str, specs, seed: int, own_limit: int | None = None, quick: bool = False,
              compiled: str | None = None) -> list[BenchCase]:
    """The kind's bench cases on ``specs`` (None: its default set): its own (``Kind.bench_cases``), else the generic
    studies on the specs or its ``Kind.bench_specs`` (always the generic studies with ``quick`` on named specs).

    ``own_limit``: keep at most this many of the default cases of a kind with its own bench methods
    (not the generic studies).  ``quick`` (``--quick``): the first case of a default set only (specs a user names
    all run), the generic studies at :data:`QUICK` settings, and a kind with its own methods and a library example
    runs only the generic studies on that example (its own cases -- reference solve, its peers -- are the slow
    part; the case note says so).  ``compiled`` (a folder): the generic studies add the method ipopt_compiled."""
    the_kind = kinds.get(kind)
    # --quick on specs a user names: the generic studies at QUICK settings for every kind (a kind's own cases on
    # them -- fourbar_path's 64 starts, reference solve and peers -- ran while the report said 1 start, no peers)
    cases = None if quick and specs is not None else the_kind.bench_cases(specs, seed)
    if cases is None:
        cases = library_cases(specs, seed, list(the_kind.bench_specs), study_settings(quick, compiled),
                              studies=the_kind.bench_studies() or None)
    own = specs is None and the_kind.solves and not any(c.loaded is not None for c in cases)
    left_out = 0
    if own and quick and the_kind.example:
        left_out, cases = len(cases), []
    elif quick and specs is None:        # the first of a default set; the specs a user names all run
        cases = cases[:1]
    elif own and own_limit is not None and len(cases) > own_limit:
        left_out, cases = len(cases) - own_limit, cases[:own_limit]
    if own:
        for case in cases:      # peers (not IPOPT) run once in every case, as in the generic studies
            case.single_runs = set(case.single_runs) | (set(case.methods) & PEERS)
        if the_kind.example:     # a kind with its own bench methods: the generic studies too, on its library example
            case = case_for(load_spec(LIBRARY / the_kind.example), study_settings(quick, compiled), seed)
            case.problem = f"{case.problem} (generic studies)"
            if left_out:
                case.note += (f"; {left_out} case(s) of the kind's own bench set not run here"
                              f" ({'--quick' if quick else 'every-kind run'}: `agrisynth bench {kind}` runs them)")
            cases.append(case)
    return cases
