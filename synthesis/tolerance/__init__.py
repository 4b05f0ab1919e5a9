"""Tolerance analysis and tolerance-robust synthesis for every kind that solves.

:mod:`.design` maps a kind's NLP to its design (coordinates, units, the tolerance box);
:mod:`.analysis` the exact sensitivities, the linearised stack-up and the seeded Monte-Carlo re-check (batches of
samples on the core's process pool, why a sample cannot be evaluated counted by reason);
:mod:`.robust` the ``[tolerance]`` option of ``solve``; :mod:`.output` the run folder (report.md's full tables) and
the one-screen summary ``agrisynth tolerance`` prints.
"""
