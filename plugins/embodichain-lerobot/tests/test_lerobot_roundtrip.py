"""The round trip a user makes: record with the default (streaming) video path, then
read with lerobot's defaults (``LeRobotDataset(repo_id, root=DIR)``, torchcodec),
lerobot's visualization script and ``lerobot-train``; frame-count checks of the encoder."""

from __future__ import annotations

import ctypes.util
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("embodichain_sensors")

from lerobot_helpers import arm_cfg, datasets_under, recorder_cfg, reset, run_script, stereo_camera  # noqa: E402

SCRIPT = [["."], ["."], ["."], ["s"], ["."], ["."], ["s"]]  # two episodes: 4 and 3 frames
needs_ffmpeg = pytest.mark.skipif(
    ctypes.util.find_library("avcodec") is None, reason="no FFmpeg shared libraries: scripts/setup_env.sh installs them"
)


def record(make_env: Any, tmp_path: Path, width: int = 64, height: int = 48, log: Any = None, **params: Any) -> Path:
    env = make_env(
        arm_cfg(1, dataset=recorder_cfg(tmp_path, use_videos=True, **params), sensors=[stereo_camera(width, height)])
    )
    reset(env)
    run_script(env, SCRIPT, log)
    env.close()
    return Path(env.dataset_manager.finalize()[0])


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(255.0**2 / mse)


@needs_ffmpeg
def test_lerobot_defaults_decode_the_videos_close_to_the_rendered_frames(make_env: Any, tmp_path: Path) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    log: list = []
    root = record(make_env, tmp_path, 160, 120, log)
    ds = LeRobotDataset(f"local/{root.name}", root=root)  # lerobot's defaults: torchcodec
    assert ds.video_backend == "torchcodec"
    assert ds.num_frames == 7
    rendered = log[0][0]["sensor"]["head"]["color"][0, ..., :3]  # the observation of frame 0
    decoded = np.rint(ds[0]["observation.images.head"].numpy().transpose(1, 2, 0) * 255)
    assert psnr(decoded, rendered) >= 30.0
    assert np.abs(ds[0]["observation.depth.head"].numpy()).sum() > 0  # depth PNGs decode too


def test_streaming_off_encodes_after_the_episode(make_env: Any, tmp_path: Path) -> None:
    from embodichain_lerobot.reading import load_dataset

    ds = load_dataset(record(make_env, tmp_path, streaming_encoding=False))
    assert [int(n) for n in ds.meta.episodes["length"]] == [4, 3]
    assert ds[6]["observation.images.head_right"].shape == (3, 48, 64)


def test_a_video_with_lost_frames_stops_the_recording(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from lerobot.datasets.video_utils import StreamingVideoEncoder

    from embodichain_lerobot.reading import load_dataset

    feed, calls = StreamingVideoEncoder.feed_frame, []

    def lossy_feed(self: Any, key: str, image: np.ndarray) -> None:
        calls.append(key)
        if len(calls) != 10:  # the right camera's frame 0 of the 2nd episode
            feed(self, key, image)

    monkeypatch.setattr(StreamingVideoEncoder, "feed_frame", lossy_feed)
    with pytest.raises(RuntimeError, match=r"has 2 frames but the episode has 3: the video encoder lost frames"):
        record(make_env, tmp_path)
    (root,) = datasets_under(tmp_path)
    ds = load_dataset(root)  # the first episode was published before the failure
    assert ds.num_episodes == 1
    assert ds.num_frames == 4


def test_vcodec_auto_resolves_to_an_encoder_that_opens_here() -> None:
    import av

    from embodichain_lerobot.encoding import resolve_vcodec

    codec = resolve_vcodec("auto")
    ctx = av.CodecContext.create({"h264": "libx264"}.get(codec, codec), "w")
    ctx.width, ctx.height, ctx.pix_fmt = 64, 64, "yuv420p"
    from fractions import Fraction

    ctx.time_base = Fraction(1, 30)
    ctx.open()
    assert resolve_vcodec("h264") == "h264"


def test_lerobot_visualization_logs_an_episode(make_env: Any, tmp_path: Path) -> None:
    pytest.importorskip("rerun")
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from lerobot.scripts.lerobot_dataset_viz import visualize_dataset

    from embodichain_lerobot.reading import video_backend

    root = record(make_env, tmp_path / "data")
    ds = LeRobotDataset(f"local/{root.name}", root=root, episodes=[1], video_backend=video_backend())
    rrd = visualize_dataset(ds, episode_index=1, save=True, output_dir=tmp_path / "viz")
    assert rrd is not None
    assert Path(rrd).stat().st_size > 1000


@pytest.mark.slow
@needs_ffmpeg
def test_lerobot_train_runs_act_on_a_fresh_recording(make_env: Any, tmp_path: Path) -> None:
    root = record(make_env, tmp_path / "data")
    train = Path(sys.executable).with_name("lerobot-train")
    cmd = [
        str(train),
        f"--dataset.repo_id=local/{root.name}",
        f"--dataset.root={root}",
        "--policy.type=act",
        "--policy.pretrained_backbone_weights=null",
        "--policy.device=cpu",
        "--policy.push_to_hub=false",
        "--steps=2",
        "--batch_size=2",
        "--num_workers=0",
        "--save_checkpoint=false",
        "--wandb.enable=false",
        "--log_freq=1",
        f"--output_dir={tmp_path / 'train'}",
    ]
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "HF_DATASETS_OFFLINE": "1"}
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    assert "step:2" in (out.stdout + out.stderr).replace(" ", "")


def test_batched_image_embedding_writes_what_lerobot_writes(tmp_path: Path) -> None:
    import datasets
    from lerobot.datasets.utils import embed_images
    from PIL import Image

    from embodichain_lerobot.encoding import _embed_images_batched

    paths = []
    for i in range(3):
        paths.append(str(tmp_path / f"{i}.png"))
        Image.fromarray(np.full((4, 5, 3), 40 * i, np.uint8)).save(paths[-1])
    features = datasets.Features({"img": datasets.Image(), "x": datasets.Value("float32")})
    ds = datasets.Dataset.from_dict({"img": paths, "x": [0.0, 1.0, 2.0]}, features=features)
    ours, theirs = _embed_images_batched(ds), embed_images(ds)
    assert ours.with_format("arrow")[:].equals(theirs.with_format("arrow")[:])
    assert ours.with_format("arrow")[:]["img"][2]["bytes"].as_py() == Path(paths[2]).read_bytes()
    plain = datasets.Dataset.from_dict({"x": [1.0]})
    assert _embed_images_batched(plain) is plain  # nothing to embed: no map at all


@pytest.mark.parametrize(
    "params, message",
    [
        (
            {"depth_format": "png"},
            r"params\.depth_format: must be one of \('video', 'png16', 'raw'\), got 'png'\. Did you mean 'png16'\?",
        ),
        (
            {"depth_format": "video"},
            r"params\.depth_format: 'video' stores depth and masks as lossless videos, which needs use_videos: true",
        ),
        (
            {"depth_format": "video", "use_videos": True, "streaming_encoding": False},
            r"params\.depth_format: 'video' .* needs use_videos: true and streaming_encoding: true",
        ),
        ({"streaming_encoding": "yes"}, r"params\.streaming_encoding: must be true or false, got 'yes'"),
        ({"encoder_threads": -1}, r"params\.encoder_threads: must be an int >= 0, got -1"),
        ({"writer_process": "yes"}, r"params\.writer_process: must be true, false or null, got 'yes'"),
    ],
)
def test_bad_encoding_params_name_their_key(params: dict, message: str) -> None:
    from embodichain_core.config.errors import ConfigError
    from embodichain_lerobot.recorder import LeRobotRecorder

    with pytest.raises(ConfigError, match=message):
        LeRobotRecorder.preflight({"save_path": "/tmp", **params}, "env.dataset.rec")


@pytest.mark.parametrize("low, high", [(0, 255), (37, 38), (90, 200)])
def test_value_count_stats_equal_lerobots_running_stats(low: int, high: int) -> None:
    from lerobot.datasets.compute_stats import DEFAULT_QUANTILES, RunningQuantileStats

    from embodichain_lerobot.encoding import SampledFrameStats
    from embodichain_lerobot.frame_stats import stats_from_counts, value_counts

    rng = np.random.default_rng(low)
    frames = [rng.integers(low, high + 1, (480, 3)).astype(np.uint8) for _ in range(12)]
    reference = RunningQuantileStats()
    reference.update(np.concatenate(frames).astype(np.float64))
    expected = reference.get_statistics()
    ours = stats_from_counts(sum(value_counts(f) for f in frames), DEFAULT_QUANTILES)
    assert set(ours) == set(expected)
    for key in expected:
        np.testing.assert_allclose(ours[key], expected[key], rtol=1e-12, atol=1e-9, err_msg=key)
    sampled = SampledFrameStats()
    for frame in frames:
        sampled.update(frame)
    stats = sampled.get_statistics()  # every frame is sampled below 100 frames
    np.testing.assert_allclose(stats["q50"], expected["q50"], rtol=1e-12)
    assert int(stats["count"][0]) == len(frames)


def test_video_stats_come_from_the_frames_in_memory(make_env: Any, tmp_path: Path) -> None:
    import json

    log: list = []
    root = record(make_env, tmp_path, log=log)
    stats = json.loads((root / "meta" / "stats.json").read_text())["observation.images.head"]
    rendered = np.stack([obs["sensor"]["head"]["color"][0, ..., :3] for obs, _ in log]).astype(np.float64) / 255
    np.testing.assert_allclose(np.ravel(stats["mean"]), rendered.mean(axis=(0, 1, 2)), atol=1e-5)
    np.testing.assert_allclose(np.ravel(stats["std"]), rendered.std(axis=(0, 1, 2)), atol=1e-4)
    np.testing.assert_allclose(np.ravel(stats["max"]), rendered.max(axis=(0, 1, 2)), atol=1e-6)
    assert stats["count"] == [7]  # sampled frames (all 7 of the two episodes)


def test_overlapping_lerobot_swaps_restore_the_original_after_the_last_block() -> None:
    """Two recorders saving on two threads: the first to finish must not undo the second's swap."""
    import types

    from embodichain_lerobot.encoding import _original, _swapped

    module = types.SimpleNamespace(attr="lerobot's")
    first, second = _swapped(module, "attr", "ours"), _swapped(module, "attr", "ours")
    first.__enter__()
    second.__enter__()
    first.__exit__(None, None, None)
    assert module.attr == "ours"
    assert _original(module, "attr") == "lerobot's"
    second.__exit__(None, None, None)
    assert module.attr == "lerobot's"
