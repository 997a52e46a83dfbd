"""Crash-safe writing of a LeRobot dataset, one committed episode at a time.

lerobot keeps a parquet writer open across episodes (its files get their footer
only at ``finalize()``) and buffers episode metadata, so a killed recording
normally leaves nothing loadable. Here lerobot writes into a staging folder
inside the dataset (``<root>/.embodichain_staging``, invisible to loaders), and
after every ``save_episode``:

1. the writers are closed and lerobot is told to continue in new files (its own
   "resume recording" path), so each episode's parquet/mp4 files are complete;
2. the new files are *moved* into the dataset (``data/``, ``videos/``,
   ``meta/episodes/``), then ``tasks.parquet``, ``subtasks.parquet`` and
   ``stats.json`` are replaced atomically, and ``meta/info.json`` last: its
   ``total_episodes`` is the commit point.

The episode's line of ``meta/embodichain_episodes.jsonl`` is appended just before
``meta/info.json`` is replaced (readers ignore lines of unpublished episodes).

A ``SIGKILL`` at any moment leaves a dataset that ``LeRobotDataset(repo_id, root)``
loads with every episode whose ``info.json`` was published (an episode caught
mid-publish leaves complete, unreferenced files that loaders ignore); a kill before
the first episode is published leaves an *incomplete* folder
(:mod:`embodichain_lerobot.folders`). A full disk during a save raises
:class:`~embodichain_lerobot.storage.DiskFullError`; the episodes published before
stay intact. The price is one data file (and one video file per camera) per episode.

Videos are encoded while the frames are added (lerobot's streaming encoder, the
default): frames go to the encoder once, with no PNG round trip, and their stats
are computed from the frames in memory (lerobot's frame sampling, see
:func:`~embodichain_lerobot.encoding.sampled_video_stats`). The encoder's queue is unbounded (an
episode is added in one burst, so a bounded queue would drop frames), and before
an episode is published every video's frame count is checked against the episode
length: an encoder that lost frames stops the recording with an error instead of
publishing a video shorter than its data. Depth and mask video features are encoded
losslessly beside lerobot's colour encoder (:class:`~embodichain_lerobot.lossless_video.RoutedEncoder`
takes the place of ``LeRobotDataset._streaming_encoder``).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import signal
import threading
import warnings
from pathlib import Path
from typing import Any, Iterable, Iterator, Optional, Sequence

import numpy as np

from embodichain_lerobot.encoder_files import remove_encoding_folder
from embodichain_lerobot.env_meta import write_env_meta_text
from embodichain_lerobot.encoding import (
    batched_image_embedding,
    planar_rgb_channels,
    quiet_encoder_statistics,
    resolve_vcodec,
    sampled_video_stats,
    video_frame_count,
    wait_lerobot,
)
from embodichain_lerobot.folders import STAGING
from embodichain_lerobot.lossless_video import RoutedEncoder
from embodichain_lerobot.storage import DiskFullError, RecordingLock, is_disk_full, quiet_encoder_disk_full

SIDECAR = "meta/embodichain_episodes.jsonl"
SUBTASKS = "meta/subtasks.parquet"
SCHEMA_VERSION = 2
_MOVED_DIRS = ("data", "videos", "meta/episodes")
_REPLACED_FILES = ("meta/tasks.parquet", "meta/stats.json")  # then subtasks, then meta/info.json

# lerobot's histogram of boolean features (next.done, next.success) warns on every episode
warnings.filterwarnings("ignore", message="Converting input from bool", category=RuntimeWarning)


def atomic_copy(src: Path, dest: Path) -> None:
    """Copy ``src`` over ``dest`` so that readers see the old or the new file, never half."""
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest.with_name(f".{dest.name}.tmp")
    shutil.copyfile(src, tmp)
    os.replace(tmp, dest)


@contextlib.contextmanager
def deferred_sigint() -> Iterator[None]:
    """Hold a Ctrl-C (and a ``SIGTERM`` that has a Python handler, such as ``run-env``'s) back
    until the block is done; a second one interrupts at once.

    Only in the main thread, for ``SIGINT`` with Python's default handler installed; elsewhere a no-op.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: dict[int, Any] = {}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        held[signal.SIGINT] = signal.default_int_handler
    term = signal.getsignal(signal.SIGTERM)
    if callable(term):
        held[signal.SIGTERM] = term
    pending: list[int] = []

    def hold(signum: int, frame: Any) -> None:
        if pending:
            held[signum](signum, frame)
        pending.append(signum)

    for signum in held:
        signal.signal(signum, hold)
    try:
        yield
    finally:
        for signum, handler in held.items():
            signal.signal(signum, handler)
    if pending:
        held[pending[0]](pending[0], None)


def _json_default(value: Any) -> Any:
    """numpy scalars/arrays and tensors as JSON values; anything else as its string."""
    if isinstance(value, np.generic):
        return value.item()
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


class DatasetWriter:
    """Writes episodes into the (already reserved, empty) dataset folder ``root``.

    The folder's recording marker (:class:`~embodichain_lerobot.storage.RecordingLock`)
    is taken before lerobot writes anything and released by :meth:`finalize`.

    Args:
        root: the dataset folder (created by :func:`~embodichain_lerobot.config.reserve_dataset_dir`).
        fps: frames per second.
        features: lerobot features (without its default ones).
        robot_type: written into ``meta/info.json``.
        use_videos, vcodec, image_writer_threads, image_writer_processes: lerobot options
            (``vcodec="auto"`` is resolved by :func:`~embodichain_lerobot.encoding.resolve_vcodec`).
        streaming_encoding: encode videos while frames are added (see the module docstring).
        encoder_threads: threads per video encoder (``None``: the codec decides).
        lossless_keys: video features encoded losslessly (packed depth and masks,
            :mod:`~embodichain_lerobot.lossless_video`); they need ``streaming_encoding``.
        env_meta: the text of ``meta/embodichain_env.json``
            (:func:`~embodichain_lerobot.env_meta.env_meta_text`), written once the marker is
            taken: the recorder writes nothing into the folder before it.
    """

    def __init__(
        self,
        root: Path,
        fps: int,
        features: dict,
        robot_type: Optional[str],
        use_videos: bool,
        vcodec: str = "libsvtav1",
        image_writer_threads: int = 0,
        image_writer_processes: int = 0,
        streaming_encoding: bool = True,
        encoder_threads: Optional[int] = None,
        lossless_keys: Sequence[str] = (),
        env_meta: Optional[str] = None,
    ):
        if lossless_keys and not (use_videos and streaming_encoding):
            raise ValueError(
                f"lossless video features {list(lossless_keys)} (params.depth_format 'video') need "
                "params.use_videos and params.streaming_encoding"
            )
        wait_lerobot()
        quiet_encoder_disk_full()  # a full disk is reported once, by the save
        quiet_encoder_statistics()  # no libx264 statistics per video (vcodec "h264")
        from lerobot.datasets.lerobot_dataset import LeRobotDataset

        self.root = Path(root)
        self.staging = self.root / STAGING
        self.repo_id = f"local/{self.root.name}"
        self._lock = RecordingLock(self.root)
        try:
            self.dataset = LeRobotDataset.create(
                repo_id=self.repo_id,
                fps=fps,
                features=features,
                root=self.staging,
                robot_type=robot_type,
                use_videos=use_videos,
                vcodec=resolve_vcodec(vcodec) if use_videos else "libsvtav1",
                image_writer_threads=image_writer_threads,
                image_writer_processes=image_writer_processes,
                streaming_encoding=streaming_encoding,
                encoder_queue_maxsize=0,
                encoder_threads=encoder_threads,
            )
            if self.dataset._streaming_encoder is not None:  # lerobot's, for colour; ours for lossless_keys
                self.dataset._streaming_encoder = RoutedEncoder(self.dataset._streaming_encoder, lossless_keys)
            atomic_copy(self.staging / "meta/info.json", self.root / "meta/info.json")
            if env_meta is not None:  # what a replay rebuilds the env from
                write_env_meta_text(self.root, env_meta)
        except BaseException:
            self._lock.release()
            raise
        self.num_episodes = 0
        self.num_frames = 0
        self._subtasks: dict[str, int] = {}
        self._broken: Optional[BaseException] = None
        self._finalized = False
        self._result: Optional[Path] = None

    # -- episodes --------------------------------------------------------------------------------
    def subtask_index(self, subtask: str) -> int:
        """The stable index of ``subtask`` (new subtasks get the next index)."""
        return self._subtasks.setdefault(subtask, len(self._subtasks))

    def write_episode(self, frames: Iterable[dict], record: dict) -> int:
        """Add, save and publish one episode; return its lerobot episode index.

        ``record`` (JSON-able) becomes the episode's line in ``meta/embodichain_episodes.jsonl``.

        Raises:
            DiskFullError: the disk filled up while saving; the episodes before are intact.
            RuntimeError: the writer is finalized, or broken by an earlier failed save.
        """
        self._check_usable()
        with sampled_video_stats():  # the encoder threads start at the first frame
            length = self._add_frames(frames)
            if length == 0:
                return -1
            index = self.num_episodes
            line = {**record, "lerobot_episode_index": index, "length": length, "schema_version": SCHEMA_VERSION}
            with deferred_sigint():  # a Ctrl-C lands after this episode is saved and counted
                self._save_and_publish(line)
                self.num_episodes += 1
                self.num_frames += length
        return index

    def _add_frames(self, frames: Iterable[dict]) -> int:
        """``add_frame`` every frame; on an error nothing is kept (the writer stays usable)."""
        ds = self.dataset
        try:
            length = 0
            for frame in frames:
                ds.add_frame(frame)
                length += 1
        except BaseException as err:
            ds.clear_episode_buffer()
            if is_disk_full(err):  # lerobot writes image frames to disk as they are added
                raise self._disk_full_error(err) from err
            raise
        return length

    def _check_usable(self) -> None:
        if self._finalized:
            raise RuntimeError(f"dataset {self.root} is finalized; no more episodes can be written")
        if self._broken is not None:
            raise RuntimeError(
                f"dataset {self.root} stopped accepting episodes after an earlier failed save "
                f"({self._broken!r}); the episodes saved before it are intact"
            )

    def _save_and_publish(self, line: dict) -> None:
        from lerobot.utils.utils import SuppressProgressBars

        try:
            with SuppressProgressBars(), batched_image_embedding(), planar_rgb_channels():
                self.dataset.save_episode(parallel_encoding=False)
            self._check_video_frames(line["length"])
            self._continue_in_new_files()
            self._publish(line)
        except BaseException as err:
            self._broken = err
            if is_disk_full(err):
                raise self._disk_full_error(err) from err
            raise

    def _check_video_frames(self, length: int) -> None:
        """Every staged video of the episode has ``length`` frames (else nothing is published)."""
        for path in sorted((self.staging / "videos").rglob("*.mp4")):
            frames = video_frame_count(path)
            if frames != length:
                raise RuntimeError(
                    f"video {path.relative_to(self.staging)} of episode {self.num_episodes} has {frames} frames "
                    f"but the episode has {length}: the video encoder lost frames, so the episode is not saved; "
                    "set the recorder's params.streaming_encoding to false to encode after each episode instead"
                )

    def _disk_full_error(self, err: BaseException) -> DiskFullError:
        n = self.num_episodes
        return DiskFullError(
            errno.ENOSPC,
            f"no space left on device while saving episode {n} to {self.root} "
            f"({err}); the {n} episode(s) saved before it are intact; free disk "
            "space or choose another params.save_path",
        )

    def _continue_in_new_files(self) -> None:
        """Close lerobot's writers; its next episode starts new files (lerobot's resume path)."""
        ds = self.dataset
        ds._close_writer()
        ds.meta._close_writer()
        latest = ds.meta.latest_episode
        ds.meta.episodes = [{k: (v[0] if isinstance(v, list) else v) for k, v in latest.items()}]
        ds.meta.latest_episode = None
        ds.latest_episode = None

    def _publish(self, line: dict) -> None:
        """Move the episode's files into the dataset; ``meta/info.json`` goes last."""
        for sub in _MOVED_DIRS:
            src_root = self.staging / sub
            if not src_root.is_dir():
                continue
            for src in sorted(p for p in src_root.rglob("*") if p.is_file()):
                dest = self.root / src.relative_to(self.staging)
                dest.parent.mkdir(parents=True, exist_ok=True)
                os.replace(src, dest)
        for name in _REPLACED_FILES:
            if (self.staging / name).exists():
                atomic_copy(self.staging / name, self.root / name)
        self._write_subtasks()
        self._append_sidecar(line)
        atomic_copy(self.staging / "meta/info.json", self.root / "meta/info.json")

    def _write_subtasks(self) -> None:
        import pandas as pd

        names = sorted(self._subtasks, key=self._subtasks.__getitem__)
        frame = pd.DataFrame({"subtask_index": [self._subtasks[n] for n in names]}, index=names)
        dest = self.root / SUBTASKS
        tmp = dest.with_name(f".{dest.name}.tmp")
        frame.to_parquet(tmp)
        os.replace(tmp, dest)

    def _append_sidecar(self, line: dict) -> None:
        """One ``write`` of one line, flushed to disk before ``meta/info.json`` counts the episode."""
        data = (json.dumps(line, default=_json_default) + "\n").encode("utf-8")
        fd = os.open(self.root / SIDECAR, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            if os.write(fd, data) != len(data):
                raise OSError(errno.ENOSPC, f"short write to {SIDECAR}")
            os.fsync(fd)
        finally:
            os.close(fd)

    # -- closing ---------------------------------------------------------------------------------
    def finalize(self) -> Optional[Path]:
        """Close lerobot's writers, remove the staging folder and the marker (idempotent).

        Returns:
            The dataset folder, or ``None`` (and the folder removed) when no episode was saved.
        """
        if self._finalized:
            return self._result
        self._finalized = True
        error: Optional[BaseException] = None
        try:
            self.dataset.stop_image_writer()
            self.dataset.finalize()
        except Exception as err:  # a broken writer may fail to close; its published episodes are intact
            error = err
        shutil.rmtree(self.staging, ignore_errors=True)
        remove_encoding_folder(self.root)  # the encoder processes' videos of unsaved episodes
        self._lock.release()
        if self.num_episodes == 0:
            shutil.rmtree(self.root, ignore_errors=True)
        self._result = self.root if self.num_episodes else None
        if error is not None and self._broken is None:
            raise RuntimeError(f"finalizing dataset {self.root} failed: {error!r}") from error
        return self._result
