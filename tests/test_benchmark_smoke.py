"""Smoke test of ``benchmarks/env_throughput.py``: the ``--quick`` run works and writes
the documented JSON. No timing is asserted (the box is shared and noisy)."""

from __future__ import annotations

import math
import os

import pytest
from bench_testlib import import_benchmarks, run_benchmark, run_script

RECORD_KEYS = {
    "num_envs",
    "sim_steps_per_control",
    "physics_substeps",
    "mujoco_steps_per_env_step",
    "nthread",
    "steps",
    "repeats",
    "env_steps_per_s",
    "raw_steps_per_s",
    "raw_sim_steps_per_s",
    "ratio",
    "manager_overhead_ms",
    "env_ms_per_call",
    "raw_ms_per_call",
    "env_times_s",
    "raw_times_s",
    "breakdown",
    "ratio_matched",
    "ratio_matched_paired_median",
    "matched_ms_per_call",
    "framework_overhead_ms",
    "matched_times_s",
}
BREAKDOWN_KEYS = {
    "env_ms_per_call",
    "env_batch_step_ms",
    "env_batch_forward_ms",
    "env_batch_reset_ms",
    "env_python_ms",
    "raw_ms_per_call",
    "physics_excess_ms",
    "forward_calls_per_step",
    "reset_calls_per_step",
    "functors_ms",
    "functor_entity_ms",
    "task_functor_ms",
    "framework_python_ms",
    "ceiling_ratio",
}


@pytest.mark.timeout(300)
def test_quick_run_writes_json(tmp_path):
    out = tmp_path / "env_throughput.json"
    proc, data = run_benchmark("env_throughput.py", "--quick", "--num-envs", "2", "--steps", "3", out=out)
    assert "| num_envs |" in proc.stdout  # the table is printed

    assert data["benchmark"] == "env_throughput"
    assert data["settings"]["quick"] is True
    assert data["machine"]["mujoco"]
    assert len(data["results"]) == 1
    rec = data["results"][0]
    assert RECORD_KEYS <= set(rec), RECORD_KEYS - set(rec)
    assert rec["num_envs"] == 2
    assert rec["sim_steps_per_control"] == 4
    assert rec["steps"] == 3
    assert rec["mujoco_steps_per_env_step"] == rec["sim_steps_per_control"] * rec["physics_substeps"]
    assert rec["nthread"] == min(os.cpu_count() or 1, 2)
    for key in ("env_steps_per_s", "raw_steps_per_s", "ratio", "env_ms_per_call", "raw_ms_per_call"):
        assert isinstance(rec[key], float), key
        assert math.isfinite(rec[key]), key
        assert rec[key] > 0, key
    assert isinstance(rec["manager_overhead_ms"], float)
    assert math.isfinite(rec["manager_overhead_ms"])
    assert rec["ratio"] == pytest.approx(rec["env_steps_per_s"] / rec["raw_steps_per_s"])
    assert rec["ratio_matched"] == pytest.approx(rec["matched_ms_per_call"] / rec["env_ms_per_call"])
    assert rec["framework_overhead_ms"] == pytest.approx(rec["env_ms_per_call"] - rec["matched_ms_per_call"])
    assert len(rec["env_times_s"]) == len(rec["raw_times_s"]) == rec["repeats"] == 1
    assert BREAKDOWN_KEYS <= set(rec["breakdown"]), BREAKDOWN_KEYS - set(rec["breakdown"])


def test_bad_arguments_are_rejected():
    proc = run_script("env_throughput.py", "--num-envs", "0", "--out", "", timeout=120)
    assert proc.returncode == 2
    assert "must be positive" in proc.stderr


@pytest.mark.timeout(300)
def test_reset_randomization_quick_run_writes_json(tmp_path):
    _, data = run_benchmark("reset_randomization.py", "--quick", out=tmp_path / "reset.json")
    rec = data["records"][0]
    keys = {
        "plain_reset_ms",
        "randomized_reset_ms",
        "extra_ms",
        "meets_target",
        "full_set_const_per_reset",
        "closed_form_per_reset",
        "constants_ms_per_reset",
        "raw_forward_ms",
        "extra_in_raw_forwards",
    }
    assert keys <= set(rec), keys - set(rec)
    assert rec["num_envs"] == 2
    assert rec["events"] == 10
    # the mass and centre-of-mass events touch free bodies only: the closed form, once per reset
    assert rec["full_set_const_per_reset"] == 0
    assert rec["closed_form_per_reset"] == 1
    assert len(data["per_event"]["2"]) == 10


def test_matched_twin_repeats_the_envs_pushes_and_resets():
    """The matched raw twin does the env's physics work: an episode's end puts the cubes
    at random poses on the table and the arm near its defaults, and a push every
    ``push_interval`` steps of an episode gives the cubes a horizontal velocity."""
    import numpy as np

    et, matched_twin = import_benchmarks("env_throughput", "matched_twin")
    MatchedTwin, Workload = matched_twin.MatchedTwin, matched_twin.Workload
    env = et.make_env(2)
    base = env.unwrapped
    work = Workload(episode_length=100, **et.WORKLOAD)
    twin = MatchedTwin(base, nthread=1, nstep=4, stagger=np.array([98, 5]), workload=work, seed=1)
    action = et.make_actions(env)[0].numpy().astype(np.float64)
    before = twin.qpos.copy()
    twin.step(action)
    twin.step(action)  # env 0 reaches step 100 of its episode and restarts
    assert twin.elapsed.tolist() == [0, 7]
    assert twin.pushes.tolist() == [0, 2]
    assert twin.dirty.tolist() == [True, False]
    for adr, _ in twin.cubes:
        xy, z, quat = twin.qpos[0, adr : adr + 2], twin.qpos[0, adr + 2], twin.qpos[0, adr + 3 : adr + 7]
        assert np.all(xy >= work.xy_low)
        assert np.all(xy <= work.xy_high)
        assert z == work.cube_z
        assert quat[1] == quat[2] == 0.0
        assert np.isclose(np.linalg.norm(quat), 1.0)
        assert not np.allclose(twin.qpos[0, adr : adr + 2], before[0, adr : adr + 2])
    assert np.all(np.abs(twin.qpos[0, twin.arm_qpos] - twin.arm_default) <= work.arm_noise)
    for _ in range(work.push_interval - 2):
        twin.step(action)
    assert twin.pushes.tolist() == [8, 10]  # env 1 is pushed on step 10 of its episode
    for _, dof in twin.cubes:
        vel = twin.qvel[1, dof : dof + 6]
        assert np.any(vel[:2] != 0)
        assert np.all(np.abs(vel[:2]) <= work.max_speed)
        assert not vel[2:].any()
    assert twin.dirty.tolist() == [False, True]
    env.close()


def test_step_overhead_verdicts_judge_both_baselines():
    (et,) = import_benchmarks("env_throughput")
    lines = et._step_overhead_verdicts(
        [
            {"num_envs": 16, "ratio": 0.78, "ratio_matched": 0.86},
            {"num_envs": 2, "ratio": 0.1, "ratio_matched": 0.1},  # no target at 2 envs
            {"num_envs": 64, "ratio": 0.9, "ratio_matched": 0.95},
        ]
    )
    assert lines == [
        "num_envs=16: target >= 0.8: ratio 0.780 MISSES, ratio_matched 0.860 meets",
        "num_envs=64: target >= 0.9: ratio 0.900 meets, ratio_matched 0.950 meets",
    ]
