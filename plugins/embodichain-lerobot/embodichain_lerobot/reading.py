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

from embodichain_lerobot.folders import (
    STAGING,
    IncompleteDatasetError,
    folder_status,
    incomplete_message,
    looks_like_recording,
)
from embodichain_lerobot.writer import SIDECAR


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
    """``path`` as a dataset folder: its ``meta/info.json`` counts at least one episode.

    Raises:
        IncompleteDatasetError: a recording left the folder before saving its first
            episode (see :mod:`embodichain_lerobot.folders`).
        FileNotFoundError: not a LeRobot dataset folder.
    """
    root = Path(path).expanduser()
    if not root.is_dir():
        raise FileNotFoundError(f"{root} is not a LeRobot dataset (no such folder)")
    status = folder_status(root)
    if status.complete:
        return root
    if looks_like_recording(root):  # meta/info.json counting 0 episodes, or staging, marker or data only
        raise IncompleteDatasetError(incomplete_message(status))
    raise FileNotFoundError(f"{root} is not a LeRobot dataset (no meta/info.json)")


def load_dataset(path: str | os.PathLike, episodes: Optional[list[int]] = None) -> Any:
    """``LeRobotDataset`` of a local folder (offline; the video backend that works here)."""
    go_offline()
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = check_dataset_dir(path)
    return LeRobotDataset(f"local/{root.name}", root=root, episodes=episodes, video_backend=video_backend())


def read_sidecar(root: Path, total: Optional[int] = None) -> list[dict]:
    """The lines of ``meta/embodichain_episodes.jsonl`` of the published episodes, in order.

    A line is written just before its episode is published, so lines of episodes
    ``meta/info.json`` does not count (a save that failed or was killed), and a torn
    last line, are skipped.

    Args:
        root: the dataset folder.
        total: the published episodes (default: ``total_episodes`` of ``meta/info.json``).
    """
    path = root / SIDECAR
    if not path.is_file():
        return []
    if total is None:
        total = int(json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))["total_episodes"])
    records: dict[int, dict] = {}
    for position, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines()):
        try:
            record = json.loads(line)
        except ValueError:
            continue
        index = record.get("lerobot_episode_index", position) if isinstance(record, dict) else None
        if isinstance(index, int) and 0 <= index < total:
            records[index] = record
    return [records[i] for i in sorted(records)]


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
    sidecar = read_sidecar(root, total)
    seeds = [r.get("episode_seed") for r in sidecar]
    features = {
        name: {"dtype": ft["dtype"], "shape": list(ft["shape"]), "names": ft.get("names")}
        for name, ft in info.get("features", {}).items()
    }
    return {
        "path": str(root),
        "codebase_version": info.get("codebase_version"),
        "robot_type": info.get("robot_type"),
        "fps": info.get("fps"),
        "episodes": total,
        "frames": int(info.get("total_frames", 0)),
        "tasks": _tasks(root),
        "features": features,
        "cameras": [n for n, f in features.items() if f["dtype"] in ("image", "video")],
        "episode_lengths": _episode_lengths(root, total),
        "successes": sum(1 for r in sidecar if r.get("success")) if sidecar else None,
        "episode_seeds": seeds if any(s is not None for s in seeds) else None,
        "episode_successes": [r.get("success") for r in sidecar] if sidecar else None,
        "unfinished": folder_status(root).unfinished,
    }


def format_summary(summary: dict) -> str:
    """Human-readable lines of :func:`dataset_summary`."""
    lengths = summary["episode_lengths"]
    span = (
        f" (length min {min(lengths)}, mean {sum(lengths) / len(lengths):.1f}, max {max(lengths)})" if lengths else ""
    )
    lines = [
        f"dataset   {summary['path']}",
        f"format    LeRobot {summary['codebase_version']}, robot_type {summary['robot_type']}, {summary['fps']} fps",
        f"episodes  {summary['episodes']}{span}",
        f"frames    {summary['frames']}",
        f"tasks     {len(summary['tasks'])}: " + "; ".join(repr(t) for t in summary["tasks"]),
    ]
    if summary["successes"] is not None:
        lines.append(f"success   {summary['successes']}/{summary['episodes']} (embodichain episode metadata)")
    seeds = summary.get("episode_seeds")
    if seeds is not None:
        known = [s for s in seeds if s is not None]
        shown = ", ".join(str(s) for s in known[:3]) + (", ..." if len(known) > 3 else "")
        lines.append(f"seeds     {len(known)}/{summary['episodes']} episodes have an episode_seed ({shown})")
    if summary["unfinished"]:
        lines.append(
            f"note      the recording was not finalized ({STAGING}/ or the recording marker is left): "
            "the run stopped early or is still running; every episode listed here is complete"
        )
    lines.append(f"features  {len(summary['features'])}:")
    width = max((len(n) for n in summary["features"]), default=0)
    for name, ft in summary["features"].items():
        lines.append(f"  {name:<{width}}  {ft['dtype']:<8} {tuple(ft['shape'])}")
    return "\n".join(lines)


def format_episodes(summary: dict, limit: Optional[int] = None) -> str:
    """One line per episode: index, length, and the embodichain metadata (success, env, seed).

    Args:
        summary: a :func:`dataset_summary`.
        limit: list at most this many episodes (``None``: all), then say how many are left out.
    """
    records = read_sidecar(Path(summary["path"]), summary["episodes"])
    by_index = {r.get("lerobot_episode_index"): r for r in records}
    lines = [f"{'episode':>7}  {'length':>6}  {'success':<7}  {'env':>3}  episode_seed"]
    lengths = summary["episode_lengths"]
    for index, length in enumerate(lengths[:limit] if limit is not None else lengths):
        record = by_index.get(index, {})
        success = {True: "yes", False: "no", None: "-"}.get(record.get("success"), "-")
        seed = record.get("episode_seed")
        lines.append(
            f"{index:>7}  {length:>6}  {success:<7}  {record.get('env_id', '-'):>3}  {'-' if seed is None else seed}"
        )
    if limit is not None and len(lengths) > limit:
        lines.append(f"    ... {len(lengths) - limit} more episode(s) (--episodes lists every one)")
    return "\n".join(lines)
