"""``vcodec: "h264"`` records without libx264's statistics on the terminal (FFmpeg's
informational messages are kept off; its warnings and errors still print)."""

from __future__ import annotations

import ctypes.util
from pathlib import Path
from typing import Any

import pytest
from lerobot_helpers import arm_cfg, recorder_cfg, reset, run_script, stereo_camera


@pytest.mark.skipif(ctypes.util.find_library("avcodec") is None, reason="no FFmpeg shared libraries")
def test_h264_recording_prints_no_encoder_statistics(make_env: Any, tmp_path: Path, capfd: Any) -> None:
    import av.logging

    av.logging.set_libav_level(av.logging.INFO)  # FFmpeg's default: the statistics would print
    dataset = recorder_cfg(tmp_path, use_videos=True, vcodec="h264")
    env = make_env(arm_cfg(1, dataset=dataset, sensors=[stereo_camera(64, 48)]))
    reset(env)
    run_script(env, [["."], ["."], ["s"], ["."], ["s"]], None)  # two episodes: two videos per stream
    env.close()
    (root,) = env.dataset_manager.finalize()
    err = capfd.readouterr().err
    assert "libx264 @" not in err, err[-2000:]
    assert list(Path(root).rglob("*.mp4")), "no video was written"
