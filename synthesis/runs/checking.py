"""``check``: evaluate a spec's given design against its rules and write the run folder OUT/<name>-check/."""

from __future__ import annotations

from synthesis import kinds
from synthesis.core import interrupt
from synthesis.core.library_log import captured_warnings
from synthesis.result import CHECK_SUFFIX
from synthesis.runs.events import Subscriber
from synthesis.runs.output import RunOutput, text_file
from synthesis.runs.requests import CheckRequest, CheckWritten, Outcome
from synthesis.runs.specs import described, in_file, loaded_spec
from synthesis.spec.operating import ranges_of


def check(request: CheckRequest, emit: Subscriber) -> Outcome:
    """Evaluate, write result.json, report.html and the kind's figures; exit code 0 when every rule holds, 1 when
    one is violated.  The written result is handed over as ``ResultWritten`` (details: :class:`CheckWritten`)."""
    interrupt.install(keep_ignored=True)     # a signal the process was started ignoring stays ignored
    loaded = loaded_spec(request.spec, emit)
    with RunOutput(request.out, loaded.name, force=request.force, spec=loaded.path, suffix=CHECK_SUFFIX) as output:
        with captured_warnings() as said:        # scipy/CasADi warnings: into warnings.log, not the terminal
            result = described(in_file(loaded, kinds.checker(loaded.kind)), loaded)
        files = {"warnings.log": text_file(said())} if said() else {}
        # a signal CasADi swallowed inside a solve of the evaluation (a fit) cut it short: stop here, write nothing
        interrupt.check()
        # evaluated: from here a signal is noted, the result written and its summary handed over (one deferral over
        # both, so no moment between them obeys it)
        with output.finishing(emit):
            details = CheckWritten(loaded.path, sorted(ranges_of(loaded.model)),
                                   kinds.get(loaded.kind).headline(result))
            folder, _ = output.finish(emit, result, files, details=details)
    return Outcome(1 if result.violated() else 0, result, folder)
