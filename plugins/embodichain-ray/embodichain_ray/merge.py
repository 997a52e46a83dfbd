"""Merge shard episodes into one LeRobot dataset ordered by run episode index, with lerobot.

Workers take episodes from a shared queue, so a shard holds an interleaved subset
(worker 0: 0, 2, 5, ...). lerobot's ``aggregate_datasets`` appends whole datasets, so
the merge feeds lerobot's own per-source steps (``aggregate_videos``,
``aggregate_data``, ``aggregate_metadata``, ``finalize_aggregation`` of
``lerobot.datasets.aggregate``) one *episode view* at a time, in episode order: a view
is the shard's metadata restricted to one episode (the recorder writes one data, video
and metadata file per episode, which is what makes a one-episode view exact).
lerobot shifts ``episode_index``/``index`` by the destination's running totals; the
view's shard-local offsets are subtracted from those totals while it is copied.

Cost stays linear in the number of episodes: lerobot appends every source to the
destination's *current* data, video and metadata files by reading and rewriting them
(re-muxing, for a video), so one growing file makes a merge quadratic. The merge starts
new destination files every ``per_file`` episodes (lerobot's own
``update_chunk_file_indices``), which bounds the cost of every append. Nothing here writes
LeRobot files by hand.

lerobot computes the ``meta/episodes/chunk_index``/``file_index`` columns of a merged
episode as the source's value plus the destination's (right only for a source whose
metadata is one file); lerobot's loaders do not read them, and the merge leaves them as
lerobot writes them.

lerobot 0.4.4 copies data files through pandas, which cannot write back a column that
pyarrow read as one of ``datasets``' ``Array2D``..``Array5D`` extension types (a
matrix feature such as the main job's 4x4 ``fork_pose``): :func:`plain_nd_arrays` lets
pyarrow read such columns as their plain nested-list storage while lerobot copies them;
loading the merged dataset casts them back from the features in ``meta/info.json``.
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from embodichain_lerobot.env_meta import merge_env_meta
from embodichain_ray.shards import ShardEpisode, remove_tree, write_sidecars

#: Episodes per destination file: every append re-writes the current file, so a file of ``P``
#: episodes costs O(P²) and a merge of ``N`` episodes O(N·P) (measured: see docs/scale_out.md).
EPISODES_PER_FILE = 25
#: lerobot's own size limits of a destination data / video file (it starts a new file beyond them).
DATA_MB = 32
VIDEO_MB = 32


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


class EpisodeView:
    """Shard metadata restricted to one episode, as lerobot's aggregation steps read it.

    Raises:
        ValueError: the episode shares a data, video or metadata file with another
            episode (not a shard written by the recorder).
    """

    def __init__(self, meta: Any, rows: dict, index: int):
        import pandas as pd
        from lerobot.datasets.utils import DEFAULT_EPISODES_PATH, unflatten_dict

        if index not in rows:
            raise ValueError(f"{meta.root}: no metadata row of episode {index}")
        row = meta.episodes[rows[index]]
        self.root, self.tasks, self.index = meta.root, meta.tasks, index
        self.episodes = {key: [value] for key, value in row.items()}
        self.total_episodes, self.from_index = 1, int(row["dataset_from_index"])
        self.total_frames = int(row["dataset_to_index"]) - self.from_index
        path = meta.root / DEFAULT_EPISODES_PATH.format(
            chunk_index=row["meta/episodes/chunk_index"], file_index=row["meta/episodes/file_index"]
        )
        frame = pd.read_parquet(path)
        if len(frame) != 1:
            raise ValueError(
                f"{path} holds {len(frame)} episodes; a one-episode view needs the recorder's "
                "one-file-per-episode layout"
            )
        stats = {k[len("stats/") :]: _array(v) for k, v in frame.iloc[0].items() if k.startswith("stats/")}
        self.stats = unflatten_dict(stats)


def _new_destination(metas: Sequence[Any], root: Path, repo_id: str) -> Any:
    """An empty destination dataset with the union of the shards' tasks (as lerobot does)."""
    import pandas as pd
    from lerobot.datasets.aggregate import validate_all_metadata
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata

    fps, robot_type, features = validate_all_metadata(list(metas))
    videos = [k for k in features if features[k]["dtype"] == "video"]
    dst = LeRobotDatasetMetadata.create(
        repo_id=repo_id,
        fps=fps,
        robot_type=robot_type,
        features=features,
        root=root,
        use_videos=bool(videos),
        data_files_size_in_mb=DATA_MB,
        video_files_size_in_mb=VIDEO_MB,
    )
    tasks = pd.concat([m.tasks for m in metas]).index.unique()
    dst.tasks = pd.DataFrame({"task_index": range(len(tasks))}, index=tasks)
    dst.episodes = {}
    return dst, videos


def _next_files(data_idx: dict, meta_idx: dict, videos_idx: dict) -> None:
    """Start new destination data, metadata and video files (in place)."""
    from lerobot.datasets.utils import DEFAULT_CHUNK_SIZE, update_chunk_file_indices

    for idx in (data_idx, meta_idx, *videos_idx.values()):
        idx["chunk"], idx["file"] = update_chunk_file_indices(idx["chunk"], idx["file"], DEFAULT_CHUNK_SIZE)


def _merge_views(
    episodes: Sequence[ShardEpisode], root: Path, metas: dict[Path, tuple[Any, dict[int, int]]], per_file: int
) -> None:
    """Copy ``episodes`` (in order) into a new dataset at ``root`` with lerobot's aggregation steps."""
    from lerobot.datasets import aggregate as agg
    from lerobot.datasets.utils import DEFAULT_CHUNK_SIZE

    dst, videos = _new_destination([meta for meta, _ in metas.values()], root, f"local/{root.name}")
    meta_idx, data_idx = {"chunk": 0, "file": 0}, {"chunk": 0, "file": 0}
    videos_idx = {k: {"chunk": 0, "file": 0, "latest_duration": 0, "episode_duration": 0} for k in videos}
    views, frames = [], 0
    for position, ep in enumerate(episodes):
        if position and position % per_file == 0:
            _next_files(data_idx, meta_idx, videos_idx)
        meta, rows = metas[ep.root]
        view = EpisodeView(meta, rows, ep.index)
        # lerobot adds the destination totals to the source's own indices: subtract the view's
        dst.info["total_episodes"], dst.info["total_frames"] = position - ep.index, frames - view.from_index
        videos_idx = agg.aggregate_videos(view, dst, videos_idx, VIDEO_MB, DEFAULT_CHUNK_SIZE)
        data_idx = agg.aggregate_data(view, dst, data_idx, DATA_MB, DEFAULT_CHUNK_SIZE)
        meta_idx = agg.aggregate_metadata(view, dst, meta_idx, data_idx, videos_idx)
        data_idx.pop("src_to_dst", None)
        frames += view.total_frames
        views.append(view)
    dst.info["total_episodes"], dst.info["total_frames"] = len(episodes), frames
    agg.finalize_aggregation(dst, views)


def merge_episodes(episodes: Sequence[ShardEpisode], output: Path, per_file: int = EPISODES_PER_FILE) -> Path:
    """Merge ``episodes`` (in the given order) into a new dataset at ``output``.

    The dataset is built in ``.<name>.merging`` beside ``output`` and renamed into place
    when complete, with the recorder's sidecars (:func:`~embodichain_ray.shards.write_sidecars`).

    Args:
        episodes: the shard episodes, in the merged order (an episode may appear twice).
        output: the new dataset folder.
        per_file: episodes per destination data/video/metadata file.

    Raises:
        FileExistsError: ``output`` exists.
        ValueError: no episode, or the shards disagree (fps, features, robot type, subtasks).
    """
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.utils.utils import SuppressProgressBars

    output = Path(output)
    if output.exists():
        raise FileExistsError(f"{output} exists; the merged dataset needs a new folder")
    if not episodes:
        raise ValueError("no episode to merge")
    work = output.parent / f".{output.name}.merging"
    remove_tree(work)
    work.parent.mkdir(parents=True, exist_ok=True)
    metas: dict[Path, tuple[Any, dict[int, int]]] = {}
    for root in sorted({ep.root for ep in episodes}):
        meta = LeRobotDatasetMetadata(f"local/{root.name}", root=root)
        metas[root] = (meta, {int(i): r for r, i in enumerate(meta.episodes["episode_index"])})
    try:
        # lerobot's validation draws a tqdm bar on stderr; its errors come as exceptions
        with plain_nd_arrays(), SuppressProgressBars(), contextlib.redirect_stderr(io.StringIO()):
            _merge_views(episodes, work, metas, max(1, per_file))
        write_sidecars(work, episodes)
        merge_env_meta(sorted({ep.root for ep in episodes}), work)  # what a replay rebuilds the env from
    except BaseException:
        remove_tree(work)
        raise
    os.replace(work, output)
    return output
