"""Helpers of the embodichain-ray tests: load a merged dataset and its per-episode arrays."""

from __future__ import annotations

import json
import os
import time
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


def _stat(pid: int) -> tuple[int, int] | None:
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return int(fields[1]), int(fields[19])
    except (OSError, IndexError, ValueError):
        return None


def ray_processes(driver: int, writers: bool = False) -> dict[int, str]:
    """The driver's descendant processes but its dataset writers (only those with ``writers``): pid -> command line."""
    parents = {int(p): s[0] for p in os.listdir("/proc") if p.isdigit() and (s := _stat(int(p))) is not None}
    found: dict[int, str] = {}
    for pid in parents:
        up = parents.get(pid)
        while up is not None and up != driver:
            up = parents.get(up)
        if up != driver:
            continue
        try:
            command = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if ("embodichain_lerobot.writer_child" in command) == writers:
            found[pid] = command
    return found


def still_running(pids: dict[int, str], within: float) -> dict[int, str]:
    """The processes of ``pids`` (not zombies) still running after up to ``within`` seconds."""
    deadline = time.monotonic() + within
    while True:
        left = {pid: cmd for pid, cmd in pids.items() if _running(pid)}
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.2)


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def generate_spec(tmp_path: Path, config: str, **kw: Any) -> Any:
    """A ``GenerateSpec`` of ``config`` writing under ``tmp_path`` (``out``, ``shards``); ``kw`` overrides."""
    from embodichain_ray.spec import GenerateSpec

    base = {"task": None, "gym_config": config, "episodes": 6, "workers": 1, "num_envs": 1, "seed": 7}
    return GenerateSpec(**{**base, "output": tmp_path / "out", "shards": tmp_path / "shards", **kw})
