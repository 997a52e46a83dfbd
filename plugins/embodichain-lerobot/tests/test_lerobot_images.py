"""Camera streams (embodichain-sensors) in recorded datasets: stereo colour as
``observation.images.<uid>`` / ``<uid>_right``, depth (millimetres) and masks (id + 1)
as packed 16-bit PNG image features, or lossless videos beside video colour
(``depth_format: raw``: numeric features), colour as PNG images (exact) and as video
(lossy), for num_envs 1 and 3."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("embodichain_sensors")

from embodichain_lerobot.packing import depth_metres, depth_millimetres, mask_ids  # noqa: E402
from lerobot_helpers import (  # noqa: E402
    arm_cfg,
    as_np,
    episode_items,
    expected_episodes,
    load,
    recorder_cfg,
    reset,
    run_script,
    stereo_camera,
)

SCRIPTS = {
    1: [["."], ["s"], ["."], ["."], ["s"]],
    3: [[".", ".", "."], ["s", ".", "f"], [".", "s", "."], [".", ".", "s"], ["s", ".", "."]],
}


def record(make_env: Any, tmp_path: Path, num_envs: int, width: int = 32, height: int = 24, **params: Any):
    env = make_env(arm_cfg(num_envs, dataset=recorder_cfg(tmp_path, **params), sensors=[stereo_camera(width, height)]))
    log: list = []
    reset(env)
    run_script(env, SCRIPTS[num_envs], log)
    env.close()
    return load(env.dataset_manager.finalize()[0]), expected_episodes(SCRIPTS[num_envs], log, num_envs)


def _millimetres(depth_m: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(depth_m[..., 0].astype(np.float64) * 1000), 0, 65535)


def _hwc(value: Any) -> np.ndarray:
    """A dataset camera item ``(C, H, W)`` float in [0, 1] as ``(H, W, C)`` uint8."""
    return np.round(as_np(value).transpose(1, 2, 0) * 255).astype(np.uint8)


@pytest.mark.parametrize("num_envs", [1, 3])
def test_stereo_images_depth_and_masks_round_trip(make_env: Any, tmp_path: Path, num_envs: int) -> None:
    ds, expected = record(make_env, tmp_path, num_envs)
    f = ds.features
    assert f["observation.images.head"] == {
        "dtype": "image",
        "shape": (24, 32, 3),
        "names": ["height", "width", "channels"],
    }
    assert f["observation.images.head_right"]["shape"] == (24, 32, 3)
    assert f["observation.depth.head"]["dtype"] == "image"
    assert f["observation.depth.head"]["shape"] == (24, 32, 3)
    assert f["observation.mask.head_right"]["dtype"] == "image"
    assert f["observation.mask.head_right"]["shape"] == (24, 32, 3)
    assert ds.num_episodes == len(expected)
    for e, (_, rows) in enumerate(expected):
        for item, (obs, _) in zip(episode_items(ds, e), rows):
            cam = obs["sensor"]["head"]
            np.testing.assert_array_equal(_hwc(item["observation.images.head"]), cam["color"][..., :3])
            np.testing.assert_array_equal(_hwc(item["observation.images.head_right"]), cam["color_right"][..., :3])
            np.testing.assert_array_equal(depth_millimetres(item["observation.depth.head"]), _millimetres(cam["depth"]))
            np.testing.assert_array_equal(mask_ids(item["observation.mask.head_right"]), cam["mask_right"][..., 0])
    first = episode_items(ds, 0)[0]
    metres = expected[0][1][0][0]["sensor"]["head"]["depth"][..., 0]
    np.testing.assert_allclose(depth_metres(first["observation.depth.head"]), metres, atol=5e-4)
    assert as_np(first["observation.images.head"]).std() > 0  # a rendering, not a blank frame
    assert len(np.unique(mask_ids(first["observation.mask.head"]))) > 1  # entities and background


def test_raw_depth_format_keeps_float_depth_and_int_masks(make_env: Any, tmp_path: Path) -> None:
    ds, expected = record(make_env, tmp_path, 1, depth_format="raw")
    assert ds.features["observation.depth.head"]["dtype"] == "float32"
    assert ds.features["observation.depth.head"]["shape"] == (24, 32, 1)
    assert ds.features["observation.mask.head_right"]["dtype"] == "int32"
    assert ds.meta.camera_keys == ["observation.images.head", "observation.images.head_right"]
    item, (obs, _) = episode_items(ds, 0)[1], expected[0][1][1]
    np.testing.assert_array_equal(as_np(item["observation.depth.head"]), obs["sensor"]["head"]["depth"])
    np.testing.assert_array_equal(as_np(item["observation.mask.head_right"]), obs["sensor"]["head"]["mask_right"])


def test_unsupported_camera_streams_are_skipped_with_a_warning(make_env: Any, tmp_path: Path) -> None:
    from embodichain_sensors.cfg import CameraCfg

    cam = CameraCfg(
        uid="wrist",
        width=16,
        height=12,
        enable_normal=True,
        extrinsics=CameraCfg.ExtrinsicsCfg(eye=(1.0, 0.0, 1.0), target=(0.0, 0.0, 0.3)),
    )
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path), sensors=[cam]))
    with pytest.warns(RuntimeWarning, match="sensor/wrist/normal"):
        reset(env)
    run_script(env, [["s"]])
    env.close()
    ds = load(env.dataset_manager.finalize()[0])
    assert "observation.images.wrist" in ds.features
    assert not any("normal" in k for k in ds.features)


@pytest.mark.parametrize("func", ["LeRobotRecorder", "AsyncLeRobotRecorder"])
def test_videos_encode_and_decode(make_env: Any, tmp_path: Path, func: str) -> None:
    ds, expected = record(make_env, tmp_path, 1, 64, 48, use_videos=True, func=func)
    assert ds.features["observation.images.head"]["dtype"] == "video"
    maps = [
        "observation.depth.head",
        "observation.depth.head_right",
        "observation.mask.head",
        "observation.mask.head_right",
    ]
    assert sorted(ds.meta.video_keys) == sorted(["observation.images.head", "observation.images.head_right", *maps])
    assert ds.meta.info["features"]["observation.depth.head"]["info"]["video.pix_fmt"] == "gbrp"  # lossless RGB
    assert [int(x) for x in ds.meta.episodes["length"]] == [len(r) for _, r in expected]
    for e, (_, rows) in enumerate(expected):
        for item, (obs, _) in zip(episode_items(ds, e), rows):
            cam = obs["sensor"]["head"]
            frame = _hwc(item["observation.images.head"]).astype(float)
            assert frame.shape == (48, 64, 3)
            assert np.abs(frame - cam["color"][..., :3]).mean() < 12  # lossy AV1
            # depth and masks are lossless videos: exact through lerobot's default decoder
            np.testing.assert_array_equal(depth_millimetres(item["observation.depth.head"]), _millimetres(cam["depth"]))
            np.testing.assert_array_equal(
                depth_millimetres(item["observation.depth.head_right"]), _millimetres(cam["depth_right"])
            )
            np.testing.assert_array_equal(mask_ids(item["observation.mask.head"]), cam["mask"][..., 0])
            np.testing.assert_array_equal(mask_ids(item["observation.mask.head_right"]), cam["mask_right"][..., 0])


def test_png16_depth_beside_video_colour(make_env: Any, tmp_path: Path) -> None:
    ds, expected = record(make_env, tmp_path, 1, 64, 48, use_videos=True, depth_format="png16")
    assert ds.meta.video_keys == ["observation.images.head", "observation.images.head_right"]
    assert ds.features["observation.depth.head"]["dtype"] == "image"
    item, (obs, _) = episode_items(ds, 0)[1], expected[0][1][1]
    np.testing.assert_array_equal(
        depth_millimetres(item["observation.depth.head"]), _millimetres(obs["sensor"]["head"]["depth"])
    )
