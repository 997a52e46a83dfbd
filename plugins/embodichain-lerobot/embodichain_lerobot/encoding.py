"""The lerobot machinery the writer leans on: its lazy import, video codecs, frame
counts and a faster image embedding for ``save_episode``.

* :func:`preload_lerobot` imports ``lerobot.datasets.lerobot_dataset`` (seconds) on a
  daemon thread, so building an env never waits for it; :func:`wait_lerobot` joins it.
* :func:`resolve_vcodec` resolves ``"auto"`` to a hardware encoder that really opens
  here (lerobot's own ``"auto"`` may pick one that is only listed), else ``libsvtav1``.
* :func:`video_frame_count` counts the frames of an mp4 (the writer checks every video
  of an episode against the episode length before publishing it).
* :func:`sampled_video_stats` makes the streaming encoder's per-camera statistics
  lerobot's sampled image statistics (the frames ``sample_indices`` picks, computed once
  at the end of the episode from per-channel value counts) instead of a 5000-bin histogram
  update per frame (about 3.4 ms of CPU a frame, in uint8 arithmetic that wraps ``x**2``).
* :func:`planar_rgb_channels` lets lerobot describe the lossless depth and mask videos
  (:mod:`embodichain_lerobot.lossless_video`), whose pixel format ``gbrp`` its
  ``get_video_pixel_channels`` does not know.
* :func:`batched_image_embedding` makes lerobot's ``save_episode`` embed PNG bytes into
  the parquet table in one batched ``datasets`` map instead of one map call per frame
  (which cost about 6 ms a frame, also for datasets without image features).
"""

from __future__ import annotations

import contextlib
import functools
import sys
import threading
from fractions import Fraction
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from embodichain_lerobot.frame_stats import stats_from_counts, value_counts

_PRELOAD: dict[str, threading.Thread] = {}


def preload_lerobot() -> None:
    """Import lerobot's dataset module on a daemon thread (once per process), off the caller's path."""
    if "thread" not in _PRELOAD and "lerobot.datasets.lerobot_dataset" not in sys.modules:
        _PRELOAD["thread"] = threading.Thread(target=_import_lerobot, name="lerobot-import", daemon=True)
        _PRELOAD["thread"].start()


def _import_lerobot() -> None:
    try:
        import lerobot.datasets.lerobot_dataset  # noqa: F401
    except Exception:  # raised again, with its traceback, by the import that needs it
        pass


def wait_lerobot() -> None:
    """Wait for :func:`preload_lerobot` (if it was started) to finish."""
    thread = _PRELOAD.get("thread")
    if thread is not None:
        thread.join()


def _embed_images_batched(dataset: Any) -> Any:
    """lerobot's ``embed_images`` as one batched ``map`` (lerobot maps row by row: ~6 ms a frame)."""
    from datasets.table import embed_table_storage

    if not any(type(ft).__name__ == "Image" for ft in dataset.features.values()):
        return dataset  # nothing to embed
    fmt = dataset.format
    out = dataset.with_format("arrow").map(embed_table_storage, batched=True, batch_size=max(1, len(dataset)))
    return out.with_format(**fmt)


_SWAPS: dict[tuple[int, str], list[Any]] = {}  # (id(module), name) -> [original, blocks inside]
_SWAP_LOCK = threading.Lock()


@contextlib.contextmanager
def _swapped(module: Any, name: str, replacement: Any) -> Iterator[None]:
    """Within the block, ``module.name`` is ``replacement``.

    Blocks may overlap (recorders saving on several threads): the original comes back
    when the last open block ends.
    """
    key = (id(module), name)
    with _SWAP_LOCK:
        slot = _SWAPS.setdefault(key, [getattr(module, name), 0])
        slot[1] += 1
        setattr(module, name, replacement)
    try:
        yield
    finally:
        with _SWAP_LOCK:
            slot[1] -= 1
            if slot[1] == 0:
                setattr(module, name, slot[0])
                del _SWAPS[key]


def _original(module: Any, name: str) -> Any:
    """``module.name`` as lerobot defines it, also inside a :func:`_swapped` block."""
    with _SWAP_LOCK:
        slot = _SWAPS.get((id(module), name))
        return slot[0] if slot is not None else getattr(module, name)


@contextlib.contextmanager
def batched_image_embedding() -> Iterator[None]:
    """Within the block, lerobot's ``save_episode`` embeds PNG bytes with :func:`_embed_images_batched`."""
    import lerobot.datasets.lerobot_dataset as lerobot_dataset

    with _swapped(lerobot_dataset, "embed_images", _embed_images_batched):
        yield


def video_frame_count(path: Path) -> int:
    """Frames of the first video stream of ``path`` (from the container; decoded when it does not say)."""
    import av

    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        count = int(stream.frames) if stream.frames else sum(1 for _ in container.decode(stream))
    return count


def quiet_encoder_statistics() -> None:
    """Keep FFmpeg's informational messages off the terminal in this process: libx264 (the
    ``h264`` codec) prints ten lines of statistics each time a video is closed. Warnings and
    errors still print. (lerobot hands FFmpeg's own log callback back after each video, so
    the level, which that callback reads, is what is set here.)"""
    import av.logging

    av.logging.set_libav_level(av.logging.WARNING)


@functools.lru_cache(maxsize=None)
def resolve_vcodec(vcodec: str) -> str:
    """``vcodec``, with ``"auto"`` resolved to a hardware encoder that opens here, else ``"libsvtav1"``.

    (lerobot's own ``"auto"`` picks an encoder PyAV merely lists, such as ``h264_nvenc``
    on a machine without an NVIDIA GPU, and then fails at the first episode.)
    """
    if vcodec != "auto":
        return vcodec
    import av
    from lerobot.datasets.video_utils import HW_ENCODERS

    for name in HW_ENCODERS:
        try:
            ctx = av.CodecContext.create(name, "w")
            ctx.width, ctx.height, ctx.pix_fmt, ctx.time_base = 64, 64, "yuv420p", Fraction(1, 30)
            ctx.open()
            return name
        except Exception:  # listed but unusable here (no GPU, no driver)
            continue
    return "libsvtav1"


class SampledFrameStats:
    """Stands in for lerobot's ``RunningQuantileStats`` inside its streaming encoder threads.

    :meth:`update` keeps each frame's (already downsampled) uint8 pixels ``(H*W, C)`` as
    per-channel value counts (:mod:`embodichain_lerobot.frame_stats`);
    :meth:`get_statistics` computes lerobot's statistics over the frames lerobot's
    ``sample_indices`` picks (as its non-streaming path does for images), with
    ``count`` the number of sampled frames. Used for anything else (one ``update``
    with all the data, as ``get_feature_stats`` does), it gives the same result as the
    class it stands in for.
    """

    def __init__(self, quantile_list: Any = None, num_quantile_bins: int = 5000):
        self._args = (quantile_list, num_quantile_bins)
        self._batches: list = []  # per frame: (C, 256) value counts (uint8 pixels) or (N, D) values
        self._counted: bool | None = None

    def _keep(self, item: np.ndarray, counted: bool) -> None:
        if self._counted not in (None, counted):
            raise ValueError("SampledFrameStats got uint8 frames and other batches in one feature")
        self._counted = counted
        self._batches.append(item)

    def update(self, batch: Any) -> None:
        """Keep one frame's pixels (uint8: as value counts) or one batch of vectors."""
        if batch.dtype == np.uint8:
            self._keep(value_counts(batch), counted=True)
        else:
            self._keep(batch.reshape(-1, batch.shape[-1]), counted=False)

    def get_statistics(self) -> dict:
        """lerobot's statistics (min, max, mean, std, count, quantiles) of the sampled batches."""
        from lerobot.datasets import compute_stats

        picked = [self._batches[i] for i in compute_stats.sample_indices(len(self._batches))]
        quantiles, num_bins = self._args
        if self._counted:
            stats = stats_from_counts(sum(picked), quantiles or compute_stats.DEFAULT_QUANTILES, num_bins)
        else:
            running = _original(compute_stats, "RunningQuantileStats")(*self._args)
            running.update(np.concatenate(picked).astype(np.float64))
            stats = running.get_statistics()
        if len(self._batches) > 1:
            stats["count"] = np.array([len(picked)])
        return stats


@contextlib.contextmanager
def sampled_video_stats() -> Iterator[None]:
    """Within the block, lerobot's statistics class is :class:`SampledFrameStats` (see the module docstring)."""
    from lerobot.datasets import compute_stats

    with _swapped(compute_stats, "RunningQuantileStats", SampledFrameStats):
        yield


#: Planar RGB pixel formats (as H.264/HEVC RGB decode) and their channel counts.
_PLANAR_RGB = {"gbrp": 3, "gbrap": 4}


def _pixel_channels(pix_fmt: str) -> int:
    from lerobot.datasets import video_utils

    return _PLANAR_RGB.get(pix_fmt) or _original(video_utils, "get_video_pixel_channels")(pix_fmt)


@contextlib.contextmanager
def planar_rgb_channels() -> Iterator[None]:
    """Within the block, lerobot's ``get_video_pixel_channels`` counts ``gbrp`` as 3 channels."""
    from lerobot.datasets import video_utils

    with _swapped(video_utils, "get_video_pixel_channels", _pixel_channels):
        yield
