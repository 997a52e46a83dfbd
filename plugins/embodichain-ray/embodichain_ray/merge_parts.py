"""What the merge reads from a shard: its format, its tasks and one-episode views.

lerobot's aggregation steps (``lerobot.datasets.aggregate``) read a *source* through a
few attributes of ``LeRobotDatasetMetadata`` (``root``, ``tasks``, ``episodes``,
``total_episodes``, ``total_frames``, ``stats``). The recorder writes one data, video and
metadata file per episode, so a source restricted to one episode (:class:`EpisodeView`)
is exact, and the merge can take a growing shard's episodes one by one while it is still
being recorded: :class:`ShardMeta` reads only the metadata files it has not read yet
(loading ``LeRobotDatasetMetadata`` again for every new episode would read every
episode's metadata file each time).

lerobot 0.4.4 copies data files through pandas, which cannot write back a column that
pyarrow read as one of ``datasets``' ``Array2D``..``Array5D`` extension types (a matrix
feature such as the main job's 4x4 ``fork_pose``): :func:`plain_nd_arrays` lets pyarrow
read such columns as their plain nested-list storage while lerobot copies them; loading
the merged dataset casts them back from the features in ``meta/info.json``.
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path
from typing import Any

import numpy as np


@contextlib.contextmanager
def plain_nd_arrays() -> Any:
    """Unregister ``datasets``' N-d array extension types from pyarrow inside the block."""
    import pyarrow as pa
    from datasets.features import features as hf

    kinds = [
        hf.Array2DExtensionType((1, 2), "int64"),
        hf.Array3DExtensionType((1, 2, 3), "int64"),
        hf.Array4DExtensionType((1, 2, 3, 4), "int64"),
        hf.Array5DExtensionType((1, 2, 3, 4, 5), "int64"),
    ]
    removed = []
    for kind in kinds:
        try:
            pa.unregister_extension_type(kind.extension_name)
            removed.append(kind)
        except (KeyError, pa.ArrowKeyError):
            pass
    try:
        yield
    finally:
        for kind in removed:
            pa.register_extension_type(kind)


def _array(value: Any) -> np.ndarray:
    """A parquet cell (nested object arrays of lists) as one numeric numpy array."""
    if isinstance(value, np.ndarray) and value.dtype == object:
        return np.stack([_array(v) for v in value])
    return np.asarray(value)


class ShardMeta:
    """A shard's format (``meta/info.json``), tasks and the metadata file of each episode.

    Args:
        root: the shard folder.
    """

    def __init__(self, root: Path):
        from lerobot.datasets.utils import load_info

        self.root = Path(root)
        info = load_info(self.root)
        self.fps, self.robot_type, self.features = info["fps"], info.get("robot_type"), info["features"]
        self.tasks: Any = None
        self._files: dict[int, Path] = {}
        self._seen: set[Path] = set()

    def episode_file(self, index: int) -> Path:
        """The metadata file of shard episode ``index`` (the shard's new files are read on demand).

        Raises:
            ValueError: no metadata file holds episode ``index``, or one holds several
                episodes (not a shard written by the recorder).
        """
        if index not in self._files:
            self._refresh()
        if index not in self._files:
            raise ValueError(f"{self.root}: no metadata row of episode {index}")
        return self._files[index]

    def _refresh(self) -> None:
        import pandas as pd
        from lerobot.datasets.utils import load_tasks

        for path in sorted((self.root / "meta" / "episodes").glob("*/*.parquet")):
            if path in self._seen:
                continue
            column = pd.read_parquet(path, columns=["episode_index"])["episode_index"]
            if len(column) != 1:
                raise ValueError(
                    f"{path} holds {len(column)} episodes; a one-episode view needs the recorder's "
                    "one-file-per-episode layout"
                )
            self._seen.add(path)
            self._files[int(column.iloc[0])] = path
        self.tasks = load_tasks(self.root)

    def format_of(self) -> tuple[Any, Any, dict]:
        """``(fps, robot_type, features)``: what every merged shard must share."""
        return self.fps, self.robot_type, self.features


def check_same_format(first: ShardMeta, other: ShardMeta) -> None:
    """Raise ``ValueError`` naming what differs when ``other`` cannot be merged with ``first``."""
    for name, a, b in zip(("fps", "robot_type", "features"), first.format_of(), other.format_of()):
        if a != b:
            shown = json.dumps(b, default=str)[:200]
            raise ValueError(f"shard {other.root} has another {name} than shard {first.root}: {shown}")


class EpisodeView:
    """Shard metadata restricted to one episode, as lerobot's aggregation steps read it.

    Args:
        meta: the episode's shard.
        index: the episode's index in the shard.

    Raises:
        ValueError: the episode shares a metadata file with another episode.
    """

    def __init__(self, meta: ShardMeta, index: int):
        import pandas as pd
        from lerobot.datasets.utils import unflatten_dict

        frame = pd.read_parquet(meta.episode_file(index))
        row = frame.iloc[0].to_dict()
        self.root, self.tasks, self.index = meta.root, meta.tasks, index
        self.episodes = {key: [value] for key, value in row.items()}
        self.total_episodes, self.from_index = 1, int(row["dataset_from_index"])
        self.total_frames = int(row["dataset_to_index"]) - self.from_index
        stats = {k[len("stats/") :]: _array(v) for k, v in row.items() if k.startswith("stats/")}
        self.stats = unflatten_dict(stats)
