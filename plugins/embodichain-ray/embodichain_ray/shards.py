"""The workers' shards: which episodes they hold, and the recorder's metadata of the merge.

Each worker incarnation records into its own folder ``<shards>/worker-WWW/<prefix>_NNN``
(a restarted worker reserves the next ``_NNN``). A shard of a killed worker still holds
every episode whose ``meta/info.json`` was published; its extra lines and files are
ignored. An episode is identified by the seed the recorder stored with it
(``meta/embodichain_episodes.jsonl``), mapped back to ``(episode, attempt)`` with
:func:`~embodichain_ray.spec.seed_table`; seeds of no episode (idle env slots) and
second copies of an episode (a batch re-run after a worker died) are skipped.

lerobot's aggregation copies neither ``meta/embodichain_episodes.jsonl`` nor
``meta/subtasks.parquet``; :func:`write_sidecars` writes both for the merged dataset,
re-indexed to its episode order.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from embodichain_lerobot.folders import folder_status
from embodichain_lerobot.writer import SIDECAR, SUBTASKS


@dataclass(frozen=True)
class ShardEpisode:
    """One published episode of a shard.

    Attributes:
        root: the shard folder.
        index: the episode's index in the shard.
        episode: the run's episode index ``k``.
        attempt: the attempt that produced it (0 = first).
        record: its line of the shard's ``meta/embodichain_episodes.jsonl``.
    """

    root: Path
    index: int
    episode: int
    attempt: int
    record: dict = field(hash=False, compare=False)


@dataclass
class ShardScan:
    """The episodes found in the shards, first copy of each run episode."""

    episodes: dict = field(default_factory=dict)  # run episode -> ShardEpisode
    shards: list = field(default_factory=list)
    duplicates: int = 0
    unknown: int = 0


def shard_folders(shards: Path) -> list[Path]:
    """Every shard folder with at least one published episode, in name order."""
    if not shards.is_dir():
        return []
    found = [p.parent.parent for p in shards.glob("*/*/meta/info.json")]
    return sorted(p for p in found if folder_status(p).complete)


def published_records(root: Path) -> list[dict]:
    """The sidecar lines of the shard's published episodes (``lerobot_episode_index`` below
    ``total_episodes``; a line of an episode caught mid-publish is ignored)."""
    total = folder_status(root).episodes
    records: dict[int, dict] = {}
    path = root / SIDECAR
    lines = path.read_text(encoding="utf-8").splitlines() if path.is_file() else []
    for line in lines:
        try:
            rec = json.loads(line)
        except ValueError:  # a torn last line of a killed recording
            continue
        index = rec.get("lerobot_episode_index")
        if isinstance(index, int) and 0 <= index < total:
            records.setdefault(index, rec)
    return [records[i] for i in sorted(records)]


def scan_shards(shards: Path, table: dict[int, tuple[int, int]]) -> ShardScan:
    """Find the run's episodes in the shards under ``shards`` (see the module doc)."""
    scan = ShardScan()
    for root in shard_folders(shards):
        scan.shards.append(root)
        for rec in published_records(root):
            seed = rec.get("episode_seed")
            where = table.get(int(seed)) if isinstance(seed, int) else None
            if where is None:
                scan.unknown += 1
            elif where[0] in scan.episodes:
                scan.duplicates += 1
            else:
                scan.episodes[where[0]] = ShardEpisode(root, rec["lerobot_episode_index"], where[0], where[1], rec)
    return scan


def write_sidecars(output: Path, ordered: Iterable[ShardEpisode]) -> None:
    """Write the merged ``meta/embodichain_episodes.jsonl`` and ``meta/subtasks.parquet``.

    Line ``p`` is the shard's line of merged episode ``p`` with ``lerobot_episode_index``
    set to ``p`` and a ``generate`` entry (run episode, attempt, shard and shard index).

    Raises:
        ValueError: the shards number their subtasks differently (their ``subtask_index``
            columns cannot be merged as they are).
    """
    ordered = list(ordered)
    lines = []
    for p, ep in enumerate(ordered):
        origin = {
            "episode": ep.episode,
            "attempt": ep.attempt,
            "shard": f"{ep.root.parent.name}/{ep.root.name}",
            "shard_episode_index": ep.index,
        }
        lines.append(json.dumps({**ep.record, "lerobot_episode_index": p, "generate": origin}))
    (output / SIDECAR).write_text("".join(line + "\n" for line in lines), encoding="utf-8")
    roots = sorted({ep.root for ep in ordered})
    tables = [(root, _subtasks(root)) for root in roots]
    first = tables[0][1] if tables else None
    for root, table in tables:
        if table != first:
            raise ValueError(
                f"shard {root} numbers its subtasks {table}, shard {roots[0]} {first}: "
                "their subtask_index columns would collide in the merge"
            )
    if roots and (roots[0] / SUBTASKS).is_file():
        shutil.copyfile(roots[0] / SUBTASKS, output / SUBTASKS)


def _subtasks(root: Path) -> dict:
    import pandas as pd

    path = root / SUBTASKS
    if not path.is_file():
        return {}
    frame = pd.read_parquet(path)
    return {str(name): int(i) for name, i in zip(frame.index, frame["subtask_index"])}


def remove_tree(path: Path) -> None:
    """Remove ``path`` (a folder) if it exists."""
    if os.path.isdir(path):
        shutil.rmtree(path, ignore_errors=True)
