"""``python -m synthesis.cli ARGS``: the agrisynth command line, as the console script runs it."""

from synthesis.cli import main

main()
