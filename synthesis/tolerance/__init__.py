"""Tolerance analysis and tolerance-robust synthesis for every kind that solves.

:mod:`.design` maps a kind's NLP to its design (coordinates, units, the tolerance box);
:mod:`.analysis` the exact sensitivities, the linearised stack-up and the seeded Monte-Carlo re-check;
:mod:`.robust` the ``[tolerance]`` option of ``solve``; :mod:`.output` the run folder.
"""
