"""Depth and masks as lossless videos (embodichain_lerobot.lossless_video): every packed
value comes back exactly through lerobot's decoders, and the encoder keeps lerobot's
streaming-encoder contract (routing, cancel, statistics)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from embodichain_lerobot.encoding import planar_rgb_channels
from embodichain_lerobot.lossless_video import LosslessEpisodeVideo, RoutedEncoder
from embodichain_lerobot.packing import pack_u16, unpack_u16


def packed_frames(n: int = 12, h: int = 24, w: int = 40) -> np.ndarray:
    """Packed 16-bit values with the hard parts: a smooth ramp, noise, and a moving block of extremes."""
    rng = np.random.default_rng(0)
    ramp = np.linspace(150, 4300, w)[None, :].repeat(h, 0)
    frames = []
    for t in range(n):
        values = ramp + rng.integers(0, 3, (h, w))
        values[4:10, t : t + 6] = 65535 if t % 2 else 0
        frames.append(values)
    return pack_u16(np.stack(frames).astype(np.uint16))


def encode(frames: np.ndarray, folder: Path, g: Any = 2) -> Path:
    video = LosslessEpisodeVideo(folder / "v" / "depth.mp4", fps=10, g=g)
    for frame in frames:
        video.add(frame)
    path, stats = video.finish()
    assert stats is not None
    assert stats["max"].shape == (3,)
    return path


@pytest.mark.parametrize("backend", ["torchcodec", "pyav"])
def test_every_value_comes_back_through_lerobots_decoders(tmp_path: Path, backend: str) -> None:
    from lerobot.datasets.video_utils import decode_video_frames

    frames = packed_frames()
    path = encode(frames, tmp_path)
    decoded = decode_video_frames(path, [i / 10 for i in range(len(frames))], 1e-4, backend)  # float (N, 3, H, W)
    np.testing.assert_array_equal(unpack_u16(decoded), unpack_u16(frames))


def test_long_keyframe_interval_is_exact_too(tmp_path: Path) -> None:
    from lerobot.datasets.video_utils import decode_video_frames

    frames = packed_frames()
    path = encode(frames, tmp_path, g=None)
    decoded = decode_video_frames(path, [0.7, 1.1], 1e-4, "pyav")
    np.testing.assert_array_equal(unpack_u16(decoded), unpack_u16(frames[[7, 11]]))


def test_lerobot_describes_the_video_as_three_channels(tmp_path: Path) -> None:
    from lerobot.datasets.video_utils import get_video_info

    path = encode(packed_frames(), tmp_path)
    with pytest.raises(ValueError, match="Unknown format"):  # lerobot alone does not know gbrp
        get_video_info(path)
    with planar_rgb_channels():
        info = get_video_info(path)
    assert (info["video.pix_fmt"], info["video.channels"], info["video.codec"]) == ("gbrp", 3, "h264")


class FakeColour:
    fps, g = 10, 2

    def __init__(self) -> None:
        self.keys: list = []
        self.fed: list = []
        self.calls: list = []

    def start_episode(self, video_keys: list, temp_dir: Path) -> None:
        self.keys = list(video_keys)
        self.calls.append("start")

    def feed_frame(self, key: str, image: np.ndarray) -> None:
        self.fed.append(key)

    def finish_episode(self) -> dict:
        return {key: (Path(f"/colour/{key}.mp4"), None) for key in self.keys}

    def cancel_episode(self) -> None:
        self.calls.append("cancel")

    def close(self) -> None:
        self.calls.append("close")


def test_routed_encoder_sends_colour_to_lerobot_and_maps_to_lossless_videos(tmp_path: Path) -> None:
    colour = FakeColour()
    enc = RoutedEncoder(colour, lossless=["depth"])
    frames = packed_frames(3)
    enc.start_episode(["rgb", "depth"], tmp_path)
    for frame in frames:
        enc.feed_frame("rgb", frame)
        enc.feed_frame("depth", frame)
    assert colour.keys == ["rgb"]
    assert colour.fed == ["rgb"] * 3
    results = enc.finish_episode()
    assert results["rgb"][0] == Path("/colour/rgb.mp4")
    depth_path, stats = results["depth"]
    assert depth_path.parent.parent == tmp_path
    assert stats is not None
    enc.start_episode(["rgb", "depth"], tmp_path)
    enc.feed_frame("depth", frames[0])
    live_folder = next(p for p in tmp_path.iterdir() if p != depth_path.parent)
    enc.cancel_episode()
    assert colour.calls == ["start", "start", "cancel"]
    assert not live_folder.exists()  # a cancelled episode leaves nothing behind
    with pytest.raises(RuntimeError, match="no episode is being encoded for 'depth'"):
        enc.feed_frame("depth", frames[0])


def test_one_frame_episode_has_no_stats_like_lerobots_encoder(tmp_path: Path) -> None:
    video = LosslessEpisodeVideo(tmp_path / "v" / "d.mp4", fps=10, g=2)
    video.add(packed_frames(1)[0])
    path, stats = video.finish()
    assert path.is_file()
    assert stats is None
