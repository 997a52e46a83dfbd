"""Files a training run writes next to the library's own: the run metadata
(``embodichain_rl.json``), the learning curve (``curve.csv``, ``curve.png``) and videos."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from embodichain_rl.episodes import EpisodeStats
from embodichain_rl.flatten import ObsFlattener

__all__ = ["META_FILE", "CurveWriter", "write_meta", "read_meta", "write_mp4", "plot_curve"]

#: Name of the run metadata file in a training output directory.
META_FILE = "embodichain_rl.json"
_FIELDS = ("env_steps", "wall_s", "episodes", "mean_return", "mean_length", "success_rate")


class CurveWriter:
    """Appends one row per call to a CSV learning curve (the header first).

    Args:
        path: the CSV file (overwritten).
    """

    def __init__(self, path: Path):
        self.path = path
        with path.open("w", newline="", encoding="utf-8") as fh:
            csv.writer(fh).writerow(_FIELDS)

    def add(self, env_steps: int, wall_s: float, stats: EpisodeStats) -> None:
        """Write a row; empty cells where no episode finished."""
        row = [env_steps, wall_s, stats.episodes, stats.mean_return, stats.mean_length, stats.success_rate]
        with self.path.open("a", newline="", encoding="utf-8") as fh:
            csv.writer(fh).writerow(["" if v is None else v for v in row])


def write_meta(out: Path, *, task: str, library: str, flattener: ObsFlattener, **extra: Any) -> Path:
    """Write ``embodichain_rl.json``: what a later ``--play`` needs to rebuild the env."""
    path = out / META_FILE
    data = {"task": task, "library": library, "flattener": flattener.to_dict(), **extra}
    path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    return path


def read_meta(checkpoint: Path) -> dict[str, Any]:
    """The run metadata of a checkpoint: ``embodichain_rl.json`` in its directory or a parent."""
    for folder in [checkpoint.parent, *checkpoint.parent.parents][:3]:
        if (folder / META_FILE).is_file():
            return json.loads((folder / META_FILE).read_text(encoding="utf-8"))
    raise FileNotFoundError(
        f"{checkpoint}: no {META_FILE} in its directory or the two above it; "
        "pass a checkpoint written by 'embodichain train-rl'"
    )


def write_mp4(frames: Sequence[np.ndarray], fps: float, path: Path) -> Path:
    """Encode ``(H, W, 3|4)`` uint8 frames as an mp4 (imageio's ffmpeg)."""
    import imageio.v2 as imageio

    if not frames:
        raise ValueError("no frames to write")
    path.parent.mkdir(parents=True, exist_ok=True)
    writer: Any
    with imageio.get_writer(str(path), fps=float(fps), codec="libx264", macro_block_size=1) as writer:
        for frame in frames:
            writer.append_data(np.ascontiguousarray(frame[..., :3]))
    return path


def plot_curve(csv_path: Path, png_path: Path, title: str) -> Path | None:
    """Plot the success rate of finished episodes against env steps (per row, and over a
    moving window of ~1/15 of the rows, weighted by episodes) as a PNG; ``None`` when no
    episode finished.

    Drawn with :func:`embodichain_tasks.rl.png_plot.line_plot_png` (numpy only, no matplotlib).
    """
    from embodichain_tasks.rl.png_plot import line_plot_png

    with csv_path.open(encoding="utf-8") as fh:
        rows = [r for r in csv.DictReader(fh) if r["success_rate"]]
    if not rows:
        return None
    steps = np.array([float(r["env_steps"]) for r in rows])
    rate = np.array([float(r["success_rate"]) for r in rows])
    episodes = np.array([float(r["episodes"]) for r in rows])
    kernel = np.ones(max(1, len(rate) // 15))
    smooth = np.convolve(rate * episodes, kernel)[: len(rate)] / np.convolve(episodes, kernel)[: len(rate)]
    png_path.write_bytes(
        line_plot_png(
            [steps, steps],
            [rate, smooth],
            title=title,
            xlabel="env steps",
            ylabel="success rate",
            labels=["per iteration", "smoothed"],
        )
    )
    return png_path
