"""Success rates with their uncertainty, and the choice of a checkpoint on validation episodes.

A success rate measured on ``n`` episodes is an estimate: :func:`wilson_interval` gives its
95% Wilson score interval (well behaved at rates near 0 or 1 and for small ``n``, where the
normal approximation is not). :func:`rate_summary` turns the episodes of an
``embodichain eval-policy --json`` file into the rate, the interval and one row per episode
(seed, success, length). :func:`choose_checkpoint` picks the checkpoint a pipeline reports:
the best rate on validation episodes, never on the test episodes it is then reported on.

Example:
    >>> lo, hi = wilson_interval(55, 100)
    >>> round(lo, 3), round(hi, 3)
    (0.452, 0.644)
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

__all__ = ["wilson_interval", "rate_summary", "choose_checkpoint", "format_rate"]

#: The normal quantile of a two-sided 95% interval.
Z95 = 1.959963984540054


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a success rate (95% by default).

    Args:
        successes: successful episodes, ``0 <= successes <= n``.
        n: episodes; ``n == 0`` gives ``(0.0, 1.0)`` (nothing is known).
        z: the normal quantile of the interval's confidence.

    Raises:
        ValueError: ``successes`` is outside ``[0, n]`` or ``n`` is negative.
    """
    if n < 0 or not 0 <= successes <= n:
        raise ValueError(f"need 0 <= successes <= n, got successes={successes}, n={n}")
    if n == 0:
        return 0.0, 1.0
    z2 = z * z
    centre = (successes + z2 / 2) / (n + z2)
    half = z * math.sqrt(successes * (n - successes) / n + z2 / 4) / (n + z2)
    return max(0.0, centre - half), min(1.0, centre + half)


def rate_summary(episodes: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The success rate of evaluated episodes, its 95% interval and one row per episode.

    Args:
        episodes: the ``episodes`` list of an ``eval-policy --json`` file (each with
            ``success``, ``length`` and ``episode_seed``).
    """
    n = len(episodes)
    k = sum(bool(e["success"]) for e in episodes)
    lo, hi = wilson_interval(k, n)
    rows: list[dict[str, Any]] = [
        {"seed": e.get("episode_seed"), "success": bool(e["success"]), "length": int(e["length"])} for e in episodes
    ]
    return {
        "success_rate": k / n if n else 0.0,
        "successes": k,
        "episodes": n,
        "ci95": [round(lo, 4), round(hi, 4)],
        "mean_length": sum(r["length"] for r in rows) / n if n else 0.0,
        "per_episode": rows,
    }


def choose_checkpoint(rows: Sequence[Mapping[str, Any]]) -> Mapping[str, Any]:
    """The checkpoint row with the highest validation success rate (the later step on a tie).

    Args:
        rows: one mapping per checkpoint with ``step`` and ``success_rate`` (validation).

    Raises:
        ValueError: no checkpoint was evaluated.
    """
    if not rows:
        raise ValueError("no checkpoint was evaluated on the validation episodes")
    return max(rows, key=lambda r: (r["success_rate"], r["step"]))


def format_rate(summary: Mapping[str, Any]) -> str:
    """``0.55 [0.45, 0.64] (55/100)``: a rate with its interval and counts."""
    lo, hi = summary["ci95"]
    return f"{summary['success_rate']:.2f} [{lo:.2f}, {hi:.2f}] ({summary['successes']}/{summary['episodes']})"
