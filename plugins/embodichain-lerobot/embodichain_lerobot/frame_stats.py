"""lerobot's image statistics of uint8 frames, from per-channel value counts.

lerobot's ``RunningQuantileStats`` computes a camera's statistics (min, max, mean,
std and the q01..q99 quantiles from a 5000-bin histogram) over every sampled pixel
in float64; its histogram sorts the pixels of each channel, which made the stats
the largest CPU cost of saving an episode (about 0.17 s per 100-frame 320x180
camera, more than encoding its video). Pixels of a uint8 frame take only 256
values, so a frame is reduced to a ``(channels, 256)`` count table when it arrives
(:func:`value_counts`), and :func:`stats_from_counts` gives lerobot's numbers from
the summed table: the same histogram edges and bin assignment (``numpy.histogram``
of the 256 values weighted by their counts), the same linear interpolation inside
the bin for the quantiles, and mean/std from the exact sums. The test suite checks
the result against lerobot's class on random frames, so a change on lerobot's side
shows up there.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

_VALUES = np.arange(256, dtype=np.float64)


def value_counts(pixels: np.ndarray) -> np.ndarray:
    """Per-channel counts of the 256 values of uint8 ``pixels`` ``(N, C)``; shape ``(C, 256)``."""
    channels = pixels.shape[-1]
    flat = pixels.reshape(-1, channels).astype(np.intp)
    flat += np.arange(channels, dtype=np.intp) * 256  # channel c's values land in [256c, 256c + 256)
    return np.bincount(flat.ravel(), minlength=256 * channels).reshape(channels, 256)


def _quantile(hist: np.ndarray, edges: np.ndarray, target: float) -> float:
    """The value below which ``target`` of the histogram's counts lie (linear inside the bin)."""
    cumsum = np.cumsum(hist)
    idx = int(np.searchsorted(cumsum, target))
    if idx == 0:
        return float(edges[0])
    if idx >= len(cumsum):
        return float(edges[-1])
    before = cumsum[idx - 1]
    inside = cumsum[idx] - before
    if inside == 0:
        return float(edges[idx])
    return float(edges[idx] + (target - before) / inside * (edges[idx + 1] - edges[idx]))


def stats_from_counts(counts: np.ndarray, quantiles: Sequence[float], num_bins: int = 5000) -> dict[str, np.ndarray]:
    """lerobot's ``RunningQuantileStats`` statistics of the pixels summarized by ``counts``.

    Args:
        counts: ``(C, 256)`` value counts (:func:`value_counts`, summed over frames).
        quantiles: the quantiles to report (lerobot's ``DEFAULT_QUANTILES``), keyed ``q01`` etc.
        num_bins: lerobot's histogram bins.

    Returns:
        ``min``, ``max``, ``mean``, ``std`` (shape ``(C,)``), ``count`` (pixels, shape ``(1,)``)
        and one entry per quantile.

    Example:
        >>> px = np.array([[0, 10], [255, 20]], dtype=np.uint8)
        >>> stats_from_counts(value_counts(px), [0.5])["mean"].tolist()
        [127.5, 15.0]
    """
    counts = counts.astype(np.float64)
    total = counts.sum(axis=1)
    if not (total >= 2).all():
        raise ValueError("Cannot compute statistics for less than 2 vectors.")
    mean = counts @ _VALUES / total
    mean_sq = counts @ (_VALUES**2) / total
    present = counts > 0
    lo = np.array([_VALUES[row].min() for row in present])
    hi = np.array([_VALUES[row].max() for row in present])
    stats = {
        "min": lo,
        "max": hi,
        "mean": mean,
        "std": np.sqrt(np.maximum(0.0, mean_sq - mean**2)),
        "count": np.array([int(total[0])]),
    }
    hists = []
    for c in range(counts.shape[0]):
        edges = np.linspace(lo[c] - 1e-10, hi[c] + 1e-10, num_bins + 1)
        hist, _ = np.histogram(_VALUES, bins=edges, weights=counts[c])
        hists.append((hist, edges))
    for q in quantiles:
        stats[f"q{int(q * 100):02d}"] = np.array([_quantile(h, e, q * total[0]) for h, e in hists])
    return stats
