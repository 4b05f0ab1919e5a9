"""Where the problem library is: the folder of published designs and redesigns (``agrisynth problems``)."""

from __future__ import annotations

from pathlib import Path

#: the problem library's root folder: one folder per mechanism, one TOML spec per problem
LIBRARY = Path(__file__).resolve().parent.parent / "problems"
