"""The data-generation job (``configs/main_job.json``: PickFork-v1, the W1 robot, its stereo
camera, the fork's mesh, mass and pose, the light and the table material randomized, scripted
demos, the asynchronous LeRobot recorder) on backend warp, Warp's CPU device, 2 envs: it
records its episodes, and ``embodichain dataset replay --all`` replays every one of them
within the warp tolerance (numbers to 1e-3, colour frames above the PSNR floor), one after
the other in one env.

On Warp's CPU device MuJoCo Warp's ray tracer runs on one thread, several times slower than
the OpenGL renderer at the job's 320x180 (docs/performance.md, section 5), so the camera
renders with ``renderer: "opengl"`` here (``benchmarks/gpu_main_job.py --smoke`` runs the job
on the Warp renderer). Slow: several minutes on 2 cores (the replay rebuilds the env).
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
CLI = [sys.executable, "-m", "embodichain_core.cli.main"]


def _run(args: list[str], timeout: float) -> subprocess.CompletedProcess:
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "HF_DATASETS_OFFLINE": "1"}
    return subprocess.run(CLI + args, capture_output=True, text=True, timeout=timeout, env=env)


@pytest.mark.slow
def test_the_job_records_on_warp_and_every_episode_replays(tmp_path: Path) -> None:
    cfg = json.loads(MAIN_JOB.read_text())
    cfg["env"]["dataset"]["lerobot"]["params"]["save_path"] = str(tmp_path / "datasets")
    cfg.update(backend="warp", device="cpu", num_envs=2, max_episodes=2)
    for sensor in cfg["sensor"]:
        sensor["renderer"] = "opengl"
    path = tmp_path / "main_job_warp.json"
    path.write_text(json.dumps(cfg))
    run = _run(["run-env", "--gym_config", str(path), "--headless", "--seed", "0"], timeout=1200)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "Backend  warp (MuJoCo Warp on cpu, float32)" in run.stdout + run.stderr
    datasets = sorted((tmp_path / "datasets").iterdir())
    assert len(datasets) == 1, datasets
    info = json.loads((datasets[0] / "meta" / "info.json").read_text())
    assert info["total_episodes"] == 2
    replay = _run(["dataset", "replay", str(datasets[0]), "--all"], timeout=1800)
    assert replay.returncode == 0, replay.stdout[-3000:] + replay.stderr[-3000:]
    assert "replayed 2 episode(s): 2 within tolerance, 0 not" in replay.stdout
    assert "ok (atol 0.001" in replay.stdout
