"""Closest-match suggestions for error messages."""

from __future__ import annotations

import difflib
from typing import Iterable


def closest(name: str, choices: Iterable[str], n: int = 3) -> list[str]:
    """Return up to ``n`` entries of ``choices`` that look like ``name``.

    Example:
        >>> closest("randomise_light", ["randomize_light", "randomize_mass"])
        ['randomize_light']
    """
    choices = sorted({str(c) for c in choices})
    found = difflib.get_close_matches(str(name), choices, n=n, cutoff=0.6)
    if not found:
        lowered = str(name).lower()
        found = [c for c in choices if lowered in c.lower() or c.lower() in lowered][:n]
    return found


def did_you_mean(name: str, choices: Iterable[str]) -> str:
    """A ``" Did you mean 'x'?"`` suffix, or the valid choices when few, or ``""``."""
    choices = sorted({str(c) for c in choices})
    found = closest(name, choices)
    if found:
        return " Did you mean " + " or ".join(repr(f) for f in found) + "?"
    if choices and len(choices) <= 12:
        return " Valid choices: " + ", ".join(repr(c) for c in choices) + "."
    return ""
