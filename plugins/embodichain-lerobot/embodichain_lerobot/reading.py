"""Reading recorded datasets back, offline: summaries and ``LeRobotDataset`` loading.

Everything here reads local files only (``HF_HUB_OFFLINE`` is set before lerobot
is imported). Videos are decoded with torchcodec when its FFmpeg libraries load,
else with PyAV (``video_backend="pyav"``), which needs no system FFmpeg.

Example:
    >>> ds = load_dataset("outputs/datasets/arm7_table_push_000")  # doctest: +SKIP
    >>> summary = dataset_summary("outputs/datasets/arm7_table_push_000")  # doctest: +SKIP
"""

from __future__ import annotations

import functools
import json
import os
from pathlib import Path
from typing import Any, Optional

from embodichain_lerobot.writer import SIDECAR, STAGING


def go_offline() -> None:
    """Never reach the Hugging Face hub from this process (set before lerobot is imported)."""
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("HF_DATASETS_OFFLINE", "1")


@functools.lru_cache(maxsize=1)
def video_backend() -> str:
    """``"torchcodec"`` when it loads (it needs FFmpeg shared libraries), else ``"pyav"``."""
    try:
        import torchcodec.decoders  # noqa: F401

        return "torchcodec"
    except Exception:  # RuntimeError when libtorchcodec finds no FFmpeg
        return "pyav"


def check_dataset_dir(path: str | os.PathLike) -> Path:
    """``path`` as a dataset folder (it must hold ``meta/info.json``).

    Raises:
        FileNotFoundError: not a LeRobot dataset folder.
    """
    root = Path(path).expanduser()
    if not (root / "meta" / "info.json").is_file():
        raise FileNotFoundError(f"{root} is not a LeRobot dataset (no meta/info.json)")
    return root


def load_dataset(path: str | os.PathLike, episodes: Optional[list[int]] = None) -> Any:
    """``LeRobotDataset`` of a local folder (offline; the video backend that works here)."""
    go_offline()
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = check_dataset_dir(path)
    return LeRobotDataset(f"local/{root.name}", root=root, episodes=episodes, video_backend=video_backend())


def read_sidecar(root: Path) -> list[dict]:
    """The per-episode lines of ``meta/embodichain_episodes.jsonl`` (empty when absent)."""
    path = root / SIDECAR
    if not path.is_file():
        return []
    lines = path.read_text(encoding="utf-8").splitlines()
    return [json.loads(line) for line in lines if line.strip()]


def _episode_lengths(root: Path, total: int) -> list[int]:
    import pyarrow.parquet as pq

    lengths: dict[int, int] = {}
    for path in sorted((root / "meta" / "episodes").glob("*/*.parquet")):
        table = pq.read_table(path, columns=["episode_index", "length"]).to_pydict()
        lengths.update(zip(table["episode_index"], table["length"]))
    return [int(lengths[i]) for i in range(total) if i in lengths]


def _tasks(root: Path) -> list[str]:
    import pandas as pd

    path = root / "meta" / "tasks.parquet"
    if not path.is_file():
        return []
    return [str(t) for t in pd.read_parquet(path).sort_values("task_index").index]


def dataset_summary(path: str | os.PathLike) -> dict:
    """Episodes, frames, fps, tasks, features and per-episode lengths of a dataset folder."""
    root = check_dataset_dir(path)
    info = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))
    total = int(info.get("total_episodes", 0))
    sidecar = read_sidecar(root)[:total]
    features = {name: {"dtype": ft["dtype"], "shape": list(ft["shape"]), "names": ft.get("names")}
                for name, ft in info.get("features", {}).items()}
    return {
        "path": str(root), "codebase_version": info.get("codebase_version"), "robot_type": info.get("robot_type"),
        "fps": info.get("fps"), "episodes": total, "frames": int(info.get("total_frames", 0)),
        "tasks": _tasks(root), "features": features,
        "cameras": [n for n, f in features.items() if f["dtype"] in ("image", "video")],
        "episode_lengths": _episode_lengths(root, total),
        "successes": sum(1 for r in sidecar if r.get("success")) if sidecar else None,
        "unfinished": (root / STAGING).exists(),
    }


def format_summary(summary: dict) -> str:
    """Human-readable lines of :func:`dataset_summary`."""
    lengths = summary["episode_lengths"]
    span = f" (length min {min(lengths)}, mean {sum(lengths) / len(lengths):.1f}, max {max(lengths)})" if lengths else ""
    lines = [
        f"dataset   {summary['path']}",
        f"format    LeRobot {summary['codebase_version']}, robot_type {summary['robot_type']}, {summary['fps']} fps",
        f"episodes  {summary['episodes']}{span}",
        f"frames    {summary['frames']}",
        f"tasks     {len(summary['tasks'])}: " + "; ".join(repr(t) for t in summary["tasks"]),
    ]
    if summary["successes"] is not None:
        lines.append(f"success   {summary['successes']}/{summary['episodes']} (embodichain episode metadata)")
    if summary["unfinished"]:
        lines.append(f"note      the recording was not finalized ({STAGING}/ is left): the run stopped early; "
                     "every episode listed here is complete")
    lines.append(f"features  {len(summary['features'])}:")
    width = max((len(n) for n in summary["features"]), default=0)
    for name, ft in summary["features"].items():
        lines.append(f"  {name:<{width}}  {ft['dtype']:<8} {tuple(ft['shape'])}")
    return "\n".join(lines)
