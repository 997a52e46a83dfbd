"""The data-generation job recorded on the device route replays on the host route.

``configs/main_job.json`` (PickFork-v1, the W1, its stereo camera through the Warp renderer,
the randomization, the scripted demonstration, the LeRobot recorder) on backend warp, 2 envs
on Warp's CPU device, run inside ``cpu_device_route()``: the code paths a GPU takes (state
through torch views, the camera poses composed on the device, ``robot.compute_ik`` starting
on the device). ``embodichain dataset replay --all`` then rebuilds the env from the dataset's
recipe on the host route and replays every episode within the warp tolerance. The camera is
128x72 (Warp's CPU device traces rays on one thread; at 64x36 one compressed frame fell
below the replay's 25 dB PSNR floor, on either route). Slow: about a minute on 2 cores.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import embodichain_tasks

MAIN_JOB = Path(embodichain_tasks.__file__).parent / "configs" / "main_job.json"


def _small_camera(sensor: dict, width: int = 128, height: int = 72) -> None:
    sx, sy = width / sensor["width"], height / sensor["height"]
    for key in ("intrinsics", "intrinsics_right"):
        if sensor.get(key):
            fx, fy, cx, cy = sensor[key]
            sensor[key] = [fx * sx, fy * sy, cx * sx, cy * sy]
    sensor.update(width=width, height=height, renderer="warp")


@pytest.mark.slow
def test_a_dataset_recorded_on_the_device_route_replays_on_the_host_route(tmp_path: Path) -> None:
    from embodichain_core.cli.run_env import build_parser, prepare
    from embodichain_core.cli.run_loops import RunStats, make_env, run_episodes
    from embodichain_core.sim.backend.warp_device import cpu_device_route

    cfg = json.loads(MAIN_JOB.read_text())
    cfg["env"]["dataset"]["lerobot"]["params"]["save_path"] = str(tmp_path / "datasets")
    cfg.update(backend="warp", device="cpu", num_envs=2, max_episodes=2)
    for sensor in cfg["sensor"]:
        _small_camera(sensor)
    path = tmp_path / "main_job_device_route.json"
    path.write_text(json.dumps(cfg))
    argv = ["--gym_config", str(path), "--headless", "--quiet", "--max_episodes", "2", "--seed", "0"]
    with cpu_device_route():
        env = make_env(prepare(build_parser().parse_args(argv)))
        assert not env.unwrapped.sim.capabilities.host_arrays  # the GPU's code paths
        stats = RunStats()
        try:
            run_episodes(env, {"max_episodes": 2}, stats)
        finally:
            env.close()
    assert stats.saved == 2, stats
    [dataset] = sorted((tmp_path / "datasets").iterdir())
    replay = subprocess.run(
        [sys.executable, "-m", "embodichain_core.cli.main", "dataset", "replay", str(dataset), "--all"],
        capture_output=True,
        text=True,
        timeout=1800,
        env={**os.environ, "HF_HUB_OFFLINE": "1", "HF_DATASETS_OFFLINE": "1"},
    )
    assert replay.returncode == 0, replay.stdout[-3000:] + replay.stderr[-3000:]
    assert "replayed 2 episode(s): 2 within tolerance, 0 not" in replay.stdout
