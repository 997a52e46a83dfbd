"""Merge shard episodes into one LeRobot dataset ordered by run episode index, with lerobot,
while the run is still generating.

Workers take episodes from a shared queue, so a shard holds an interleaved subset
(worker 0: 0, 2, 5, ...). lerobot's ``aggregate_datasets`` appends whole datasets, so
the merge feeds lerobot's own per-source steps (``aggregate_videos``, ``aggregate_data``,
``aggregate_metadata``, ``finalize_aggregation`` of ``lerobot.datasets.aggregate``) one
*episode view* (:class:`~embodichain_ray.merge_parts.EpisodeView`) at a time, in episode
order. lerobot shifts ``episode_index``/``index`` by the destination's running totals; the
view's shard-local offsets are subtracted from those totals while it is copied.

:class:`StreamingMerge` appends in a background thread: episode ``k`` is appended as soon
as it and every episode before it are saved (or known to have failed), so when the last
batch returns only its own episodes and the final metadata are left to write. The result
is the dataset a merge of all episodes at the end gives (:func:`merge_episodes` is that
merge): the same episodes, frames and files in the same order.

Cost stays linear in the number of episodes: lerobot appends every source to the
destination's *current* data, video and metadata files by reading and rewriting them
(re-muxing, for a video), so one growing file makes a merge quadratic. The merge starts new
destination files every ``per_file`` episodes (lerobot's own ``update_chunk_file_indices``).
lerobot computes the ``meta/episodes/chunk_index``/``file_index`` columns of a merged episode
as the source's value plus the destination's (right only for a one-file source); lerobot's
loaders do not read them, and the merge leaves them as lerobot writes them.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from embodichain_lerobot.env_meta import merge_env_meta
from embodichain_ray.merge_parts import EpisodeView, ShardMeta, check_same_format, plain_nd_arrays
from embodichain_ray.shards import ShardEpisode, remove_tree, write_sidecars

#: Episodes per destination file: every append re-writes the current file, so a file of ``P``
#: episodes costs O(P²) and a merge of ``N`` episodes O(N·P) (measured: see docs/scale_out.md).
EPISODES_PER_FILE = 25
#: lerobot's own size limits of a destination data / video file (it starts a new file beyond them).
DATA_MB = 32
VIDEO_MB = 32


class _Destination:
    """The dataset being built at ``root`` and lerobot's running file indices."""

    def __init__(self, first: ShardMeta, root: Path, per_file: int):
        import pandas as pd
        from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata

        videos = [k for k, f in first.features.items() if f["dtype"] == "video"]
        self.meta = LeRobotDatasetMetadata.create(
            repo_id=f"local/{root.name}",
            fps=first.fps,
            robot_type=first.robot_type,
            features=first.features,
            root=root,
            use_videos=bool(videos),
            data_files_size_in_mb=DATA_MB,
            video_files_size_in_mb=VIDEO_MB,
        )
        self.meta.tasks = pd.DataFrame({"task_index": []}, index=pd.Index([], dtype=object))
        self.meta.episodes = {}
        self.first, self.per_file = first, per_file
        self.meta_idx, self.data_idx = {"chunk": 0, "file": 0}, {"chunk": 0, "file": 0}
        self.videos_idx = {k: {"chunk": 0, "file": 0, "latest_duration": 0, "episode_duration": 0} for k in videos}
        self.views: list[EpisodeView] = []
        self.frames = 0

    def _add_tasks(self, tasks: Any) -> None:
        import pandas as pd

        new = [t for t in tasks.index if t not in self.meta.tasks.index]
        if new:
            names = list(self.meta.tasks.index) + new
            index = pd.Index(names, name=tasks.index.name)
            self.meta.tasks = pd.DataFrame({"task_index": range(len(names))}, index=index)

    def append(self, meta: ShardMeta, ep: ShardEpisode) -> None:
        """Copy shard episode ``ep`` to the end of the dataset with lerobot's aggregation steps."""
        from lerobot.datasets import aggregate as agg
        from lerobot.datasets.utils import DEFAULT_CHUNK_SIZE, update_chunk_file_indices

        position = len(self.views)
        if position and position % self.per_file == 0:  # new destination files
            for idx in (self.data_idx, self.meta_idx, *self.videos_idx.values()):
                idx["chunk"], idx["file"] = update_chunk_file_indices(idx["chunk"], idx["file"], DEFAULT_CHUNK_SIZE)
        view = EpisodeView(meta, ep.index)
        self._add_tasks(view.tasks)
        dst = self.meta
        # lerobot adds the destination totals to the source's own indices: subtract the view's
        dst.info["total_episodes"], dst.info["total_frames"] = position - ep.index, self.frames - view.from_index
        self.videos_idx = agg.aggregate_videos(view, dst, self.videos_idx, VIDEO_MB, DEFAULT_CHUNK_SIZE)
        self.data_idx = agg.aggregate_data(view, dst, self.data_idx, DATA_MB, DEFAULT_CHUNK_SIZE)
        self.meta_idx = agg.aggregate_metadata(view, dst, self.meta_idx, self.data_idx, self.videos_idx)
        self.data_idx.pop("src_to_dst", None)
        self.frames += view.total_frames
        self.views.append(view)

    def finalize(self) -> None:
        """Write the tasks, ``meta/info.json`` and the stats (lerobot's ``finalize_aggregation``)."""
        from lerobot.datasets import aggregate as agg

        self.meta.info["total_episodes"], self.meta.info["total_frames"] = len(self.views), self.frames
        agg.finalize_aggregation(self.meta, self.views)


class StreamingMerge:
    """Builds the merged dataset at ``output`` while episodes arrive, in episode order.

    Call :meth:`add` for every saved episode and :meth:`skip` for every episode that failed
    all its attempts (in any order, from one thread); a background thread appends episode
    ``k`` once every episode before it is added or skipped. :meth:`finish` appends the rest
    in order (skipping the episodes never added) and moves the dataset into place;
    :meth:`abort` removes what was built. The dataset grows in ``.<name>.merging`` beside
    ``output``: nothing is at ``output`` until it is complete.

    Args:
        output: the new dataset folder.
        per_file: episodes per destination data/video/metadata file.

    Raises:
        FileExistsError: ``output`` exists.
    """

    def __init__(self, output: Path, per_file: int = EPISODES_PER_FILE):
        self.output = Path(output)
        if self.output.exists():
            raise FileExistsError(f"{self.output} exists; the merged dataset needs a new folder")
        self.work = self.output.parent / f".{self.output.name}.merging"
        self.per_file = max(1, per_file)
        self.merged: list[ShardEpisode] = []
        self._pending: dict[int, ShardEpisode] = {}
        self._skipped: set[int] = set()
        self._known: set[int] = set()
        self._next, self._draining, self._stopped = 0, False, False
        self._error: BaseException | None = None
        self._dst: _Destination | None = None
        self._shards: dict[Path, ShardMeta] = {}
        self._cond = threading.Condition()
        self._thread = threading.Thread(target=self._loop, name="embodichain-merge", daemon=True)
        self._thread.start()

    def add(self, ep: ShardEpisode) -> bool:
        """Take a saved episode (``False``: a copy of that run episode came before; it is ignored)."""
        with self._cond:
            if ep.episode in self._known:
                return False
            self._known.add(ep.episode)
            self._pending[ep.episode] = ep
            self._cond.notify()
        return True

    def skip(self, episode: int) -> None:
        """Episode ``episode`` has no copy to merge (it failed every attempt)."""
        with self._cond:
            if episode not in self._known:
                self._skipped.add(episode)
                self._cond.notify()

    @property
    def held(self) -> set[int]:
        """The run episodes taken so far (merged or waiting for the ones before them)."""
        with self._cond:
            return set(self._known)

    def _take(self) -> ShardEpisode | None:
        """The next episode to append, or ``None`` once there is nothing left (finish or abort)."""
        with self._cond:
            while True:
                if self._stopped or self._error is not None:
                    return None
                while self._next in self._skipped:
                    self._next += 1
                if self._next in self._pending:
                    self._next += 1
                    return self._pending.pop(self._next - 1)
                if self._draining:
                    if not self._pending:
                        return None
                    self._next = min(self._pending)
                    continue
                self._cond.wait()

    def _loop(self) -> None:
        from lerobot.utils.utils import SuppressProgressBars

        try:
            with plain_nd_arrays(), SuppressProgressBars():
                while (ep := self._take()) is not None:
                    self._append(ep)
                if self._dst is not None and not self._stopped:
                    self._dst.finalize()
        except BaseException as err:  # noqa: BLE001  (handed to finish(), which raises it)
            self._error = err

    def _append(self, ep: ShardEpisode) -> None:
        meta = self._shards.get(ep.root)
        if meta is None:
            meta = self._shards[ep.root] = ShardMeta(ep.root)
            if self._dst is not None:
                check_same_format(self._dst.first, meta)
        if self._dst is None:
            remove_tree(self.work)
            self.work.parent.mkdir(parents=True, exist_ok=True)
            self._dst = _Destination(meta, self.work, self.per_file)
        self._dst.append(meta, ep)
        self.merged.append(ep)

    def finish(self) -> int:
        """Append what is left, write the final metadata and move the dataset to ``output``.

        Returns:
            The number of merged episodes (0: nothing was saved, nothing is written).

        Raises:
            Exception: the merge's error (the partial dataset is removed).
        """
        with self._cond:
            self._draining = True
            self._cond.notify()
        self._thread.join()
        try:
            if self._error is not None:
                raise self._error
            if not self.merged:
                return 0
            write_sidecars(self.work, self.merged)
            merge_env_meta(sorted({ep.root for ep in self.merged}), self.work)  # what a replay rebuilds the env from
            os.replace(self.work, self.output)
        except BaseException:
            remove_tree(self.work)
            raise
        return len(self.merged)

    def abort(self) -> None:
        """Stop appending and remove the partial dataset."""
        with self._cond:
            self._stopped = True
            self._cond.notify()
        self._thread.join()
        remove_tree(self.work)


def merge_episodes(episodes: Sequence[ShardEpisode], output: Path, per_file: int = EPISODES_PER_FILE) -> Path:
    """Merge ``episodes`` (in the given order) into a new dataset at ``output``.

    Args:
        episodes: the shard episodes, in the merged order (their run episode indices ascend).
        output: the new dataset folder.
        per_file: episodes per destination data/video/metadata file.

    Raises:
        FileExistsError: ``output`` exists.
        ValueError: no episode, or the shards disagree (fps, features, robot type, subtasks).
    """
    if not episodes:
        raise ValueError("no episode to merge")
    merge = StreamingMerge(output, per_file)
    try:
        for ep in episodes:
            merge.add(ep)
    except BaseException:
        merge.abort()
        raise
    merge.finish()
    return Path(output)
