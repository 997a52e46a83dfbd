"""Helpers of the embodichain-ray tests: load a merged dataset and its per-episode arrays."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np


def load(root: Path) -> Any:
    """``LeRobotDataset`` of ``root`` (decoded with PyAV)."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    return LeRobotDataset(f"local/{Path(root).name}", root=root, video_backend="pyav")


def episode_arrays(root: Path, keys: tuple = ("observation.state", "action")) -> list[dict]:
    """Per episode, ``{key: (T, ...) array}`` read from the data files."""
    ds = load(root)
    table = ds.hf_dataset.with_format("numpy")
    episodes = np.asarray(table["episode_index"])
    out = []
    for e in range(ds.num_episodes):
        rows = np.nonzero(episodes == e)[0]
        out.append({k: np.stack(table[k])[rows] for k in keys})
    return out


def sidecar(root: Path) -> list[dict]:
    """The merged ``meta/embodichain_episodes.jsonl`` lines."""
    text = (Path(root) / "meta" / "embodichain_episodes.jsonl").read_text()
    return [json.loads(line) for line in text.splitlines()]
