"""How figures name a candidate: "(baseline)" marks the first only beside other candidates.

A report of one design has no baseline (a solve's report says "given" and "solved" in its tables); the
comparison page's first candidate is the one the others are measured against.
"""

from __future__ import annotations


def candidate_label(name: str, index: int, count: int) -> str:
    """The legend entry of candidate ``index`` of ``count``: its name, "(baseline)" after the first of several."""
    return f"{name} (baseline)" if index == 0 and count > 1 else name


def baseline_note(text: str, count: int) -> str:
    """``text`` (e.g. " (baseline first)") when several candidates are drawn, else ""."""
    return text if count > 1 else ""
