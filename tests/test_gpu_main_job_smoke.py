"""Smoke test of ``benchmarks/gpu_main_job.py --smoke``: the data-generation job (PickFork-v1,
the W1 robot, its stereo camera, randomization, scripted demos, the LeRobot recorder) on
backend warp with 2 envs on Warp's CPU device, PushCube-v1 with a Warp camera in its
observation, and the job's host-wait count. It checks what the rows report (episodes saved
and loaded back, frames, phases that ran); no timing is asserted. Slow: a few minutes on 2
cores."""

from __future__ import annotations

import pytest

from bench_testlib import run_benchmark

PHASES = {"physics", "render", "demo_ik", "device_to_host", "encoding_writing_cpu"}


@pytest.mark.slow
def test_main_job_and_camera_rows(tmp_path) -> None:
    _, payload = run_benchmark("gpu_main_job.py", "--smoke", out=tmp_path / "job.json", timeout=1500)
    job, camera, syncs = payload["rows"]
    assert (job["case"], job["num_envs"], camera["case"], camera["num_envs"]) == ("main_job", 2, "camera", 2)
    assert job["episodes_saved"] >= 2, "the job records max_episodes = 2 envs x 1"
    assert job["frames_recorded"] >= 2 * job["episodes_saved"], "every saved episode has frames, loaded back"
    assert job["frames_recorded"] <= job["env_steps"] + job["episodes_saved"]  # + each episode's first frame
    assert job["recorded_env_steps_per_s"] > 0
    assert set(job["phases_s"]) == PHASES
    assert all(job["phases_s"][p] > 0 for p in PHASES), job["phases_s"]  # each instrumented call ran
    assert "backend warp on cpu" in job["changes"]
    assert camera["image_shape"][:3] == [2, 128, 128]
    assert camera["env_steps_per_s"] > 0
    assert (syncs["case"], syncs["num_envs"], syncs["torch_sync_check"]) == ("syncs", 2, False)
    assert syncs["steps"] == 2
    assert syncs["per_step"] >= 0
    assert syncs["plan_syncs"] >= 0
