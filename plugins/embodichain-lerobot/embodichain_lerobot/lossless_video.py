"""Depth and mask maps as lossless video features, encoded while the episode runs.

Depth (millimetres) and masks (entity id + 1) are 16-bit values packed into RGB
frames (:mod:`embodichain_lerobot.packing`). Stored as PNG images they cost about
10 KB per camera frame; consecutive maps differ only where something moved, which
PNG cannot use and a video codec does. Here they are H.264 videos that FFmpeg's
``libx264rgb`` encodes losslessly (``qp 0``, RGB planes, no YUV conversion), with
the dataset's keyframe interval: about 5 KB per camera frame at lerobot's
``g=2`` (fast random access), and less CPU than the PNG writer.

lerobot's own encoders cannot be asked for this: its codec options set ``crf``
only for ``h264``/``hevc``/``libsvtav1``, which encode YUV (lossy for packed
values), and its codec list rejects ``libx264rgb``. So :class:`RoutedEncoder`
stands in for lerobot's ``StreamingVideoEncoder`` (same methods, the ones
``LeRobotDataset`` calls): colour keys go to lerobot's encoder, the lossless keys
to :class:`LosslessEpisodeVideo` (PyAV, FFmpeg's encoder). lerobot then moves,
concatenates and describes these videos like any other, and its video backends
(torchcodec, pyav) decode them exactly: the decoded RGB equals the packed frame
(tested). One more thing lerobot needs: H.264 RGB decodes to the planar pixel format
``gbrp``, which lerobot's ``get_video_pixel_channels`` does not know (it looks for
``"rgb"`` in the name); :func:`~embodichain_lerobot.encoding.planar_rgb_channels`
teaches it while an episode is saved (the only time lerobot describes a video).

Example:
    >>> import numpy as np, tempfile, pathlib
    >>> video = LosslessEpisodeVideo(pathlib.Path(tempfile.mkdtemp()) / "d.mp4", fps=10, g=2)
    >>> for value in range(3):
    ...     video.add(np.full((8, 8, 3), value, np.uint8))
    >>> path, stats = video.finish()
    >>> path.suffix
    '.mp4'
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
from fractions import Fraction
from pathlib import Path
from typing import Any, Iterable, Optional

import numpy as np

from embodichain_lerobot.encoding import SampledFrameStats

#: FFmpeg's H.264 encoder of RGB input (part of x264; PyAV's wheels ship it).
LOSSLESS_CODEC = "libx264rgb"


class LosslessEpisodeVideo:
    """One feature's video of one episode: each frame is encoded as it is added.

    Args:
        path: the mp4 to write (its folder is created; lerobot moves the file and
            removes the folder when it saves the episode).
        fps: frames per second.
        g: keyframe interval (lerobot's ``g``; ``None``: the codec's default).
    """

    def __init__(self, path: Path, fps: int, g: Optional[int]):
        self.path, self.fps, self.g = Path(path), int(fps), g
        self.frames = 0
        self._container: Any = None
        self._stream: Any = None
        self._stats = SampledFrameStats()

    def _open(self, height: int, width: int) -> None:
        import av

        options = {"qp": "0", "preset": "veryfast", "threads": "1"}
        if self.g is not None:
            options["g"] = str(self.g)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._container = av.open(str(self.path), "w")
        self._stream = self._container.add_stream(LOSSLESS_CODEC, self.fps, options=options)
        self._stream.pix_fmt, self._stream.width, self._stream.height = "rgb24", width, height
        self._stream.time_base = Fraction(1, self.fps)

    def add(self, frame: np.ndarray) -> None:
        """Encode one ``(H, W, 3)`` uint8 frame (and keep it for the episode's statistics)."""
        import av
        from lerobot.datasets.compute_stats import auto_downsample_height_width

        frame = np.ascontiguousarray(frame, dtype=np.uint8)
        if self._container is None:
            self._open(*frame.shape[:2])
        video_frame = av.VideoFrame.from_ndarray(frame, format="rgb24")
        video_frame.pts, video_frame.time_base = self.frames, Fraction(1, self.fps)
        self._container.mux(self._stream.encode(video_frame))
        small = auto_downsample_height_width(frame.transpose(2, 0, 1))
        self._stats.update(small.transpose(1, 2, 0).reshape(-1, small.shape[0]))
        self.frames += 1

    def finish(self) -> tuple[Path, Optional[dict]]:
        """Flush and close the video; its path and lerobot's statistics (``None`` under 2 frames,
        as lerobot's encoder does)."""
        if self._container is not None:
            self._container.mux(self._stream.encode())
            self._container.close()
            self._container = None
        return self.path, (self._stats.get_statistics() if self.frames >= 2 else None)

    def cancel(self) -> None:
        """Close the video and remove its folder."""
        if self._container is not None:
            with contextlib.suppress(Exception):
                self._container.close()
            self._container = None
        shutil.rmtree(self.path.parent, ignore_errors=True)


class RoutedEncoder:
    """lerobot's streaming-encoder interface over two encoders: lerobot's ``StreamingVideoEncoder``
    for colour, :class:`LosslessEpisodeVideo` for the ``lossless`` keys (depth and masks).

    Args:
        colour: lerobot's streaming encoder (the dataset's, or a fresh one per env).
        lossless: the video keys encoded losslessly.
    """

    def __init__(self, colour: Any, lossless: Iterable[str] = ()):
        self.colour = colour
        self.lossless = frozenset(lossless)
        self._live: dict[str, LosslessEpisodeVideo] = {}

    def fresh(self) -> "RoutedEncoder":
        """A new encoder with the same settings (lerobot's colour encoder never drops a frame)."""
        c = self.colour
        colour = type(c)(
            fps=c.fps,
            vcodec=c.vcodec,
            pix_fmt=c.pix_fmt,
            g=c.g,
            crf=c.crf,
            preset=c.preset,
            queue_maxsize=0,  # the episode's frame count is checked at save
            encoder_threads=c.encoder_threads,
        )
        return RoutedEncoder(colour, self.lossless)

    def start_episode(self, video_keys: list[str], temp_dir: Path) -> None:
        """Start the episode's encoders (one lossless video per lossless key)."""
        self._cancel_lossless()
        self.colour.start_episode(video_keys=[k for k in video_keys if k not in self.lossless], temp_dir=temp_dir)
        for key in video_keys:
            if key in self.lossless:
                folder = Path(tempfile.mkdtemp(dir=temp_dir))
                path = folder / f"{key.replace('/', '_')}_lossless.mp4"
                self._live[key] = LosslessEpisodeVideo(path, int(self.colour.fps), self.colour.g)

    def feed_frame(self, video_key: str, image: np.ndarray) -> None:
        """One frame of ``video_key``."""
        if video_key in self.lossless:
            if video_key not in self._live:
                raise RuntimeError(f"no episode is being encoded for {video_key!r}; call start_episode() first")
            self._live[video_key].add(image)
        else:
            self.colour.feed_frame(video_key, image)

    def finish_episode(self) -> dict[str, tuple[Path, Optional[dict]]]:
        """``{video_key: (mp4 path, stats or None)}`` of every key of the episode."""
        live, self._live = self._live, {}
        try:
            results = dict(self.colour.finish_episode())
            for key, video in live.items():
                results[key] = video.finish()
        except BaseException:
            for video in live.values():
                video.cancel()
            raise
        return results

    def cancel_episode(self) -> None:
        """Drop the episode's videos."""
        self.colour.cancel_episode()
        self._cancel_lossless()

    def _cancel_lossless(self) -> None:
        live, self._live = self._live, {}
        for video in live.values():
            video.cancel()

    def backlog(self) -> int:
        """Frames queued in the colour encoder (lossless frames are encoded as they come)."""
        return sum(q.qsize() for q in getattr(self.colour, "_frame_queues", {}).values())

    def close(self) -> None:
        """Stop everything (lerobot calls this when the dataset closes)."""
        self._cancel_lossless()
        self.colour.close()
