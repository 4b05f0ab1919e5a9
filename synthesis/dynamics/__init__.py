"""Inverse dynamics of the planar four-bar at constant crank speed, on floats and CasADi symbols alike
(docs/ARCHITECTURE.md "Dynamics").  Imports no spec model, NLP, CLI or report code."""
