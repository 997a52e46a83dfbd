"""Smoke test of ``benchmarks/gym_compare.py``: the ``--quick`` run works and writes the
documented JSON. No timing is asserted (the box is shared and noisy)."""

from __future__ import annotations

import math

import pytest
from bench_testlib import import_benchmarks, run_benchmark

CONTENDERS = ("ours", "raw", "sync", "async")


@pytest.mark.timeout(300)
def test_quick_run_writes_json(tmp_path):
    proc, data = run_benchmark("gym_compare.py", "--quick", "--async-max", "1", out=tmp_path / "gym_compare.json")
    assert "| num_envs |" in proc.stdout
    assert "ours / Sync" in proc.stdout

    assert data["benchmark"] == "gym_compare"
    assert data["settings"]["quick"] is True
    assert data["settings"]["async_max"] == 1
    assert [r["num_envs"] for r in data["results"]] == [1, 2]
    one, two = data["results"]
    for rec in (one, two):
        assert rec["steps"] == 3
        assert rec["repeats"] == 1
        for name in ("ours", "raw", "sync"):
            rate = rec[f"{name}_steps_per_s"]
            assert isinstance(rate, float), name
            assert math.isfinite(rate), name
            assert rate > 0, name
            assert len(rec[f"{name}_times_s"]) == 1
        assert rec["ours_over_sync"] == pytest.approx(rec["ours_steps_per_s"] / rec["sync_steps_per_s"])
        assert rec["ours_over_raw"] == pytest.approx(rec["ours_steps_per_s"] / rec["raw_steps_per_s"])
        assert rec["ours_outside_physics_us"] is None  # only with --split
    assert one["async_steps_per_s"] > 0  # async runs up to --async-max envs, not beyond
    assert two["async_steps_per_s"] is None
    assert two["ours_over_async"] is None


@pytest.mark.timeout(300)
def test_cpu_clock_leaves_out_the_async_contender_and_split_times_the_python(tmp_path):
    args = ("--quick", "--num-envs", "1", "--clock", "cpu", "--split")
    _, data = run_benchmark("gym_compare.py", *args, out=tmp_path / "gym_compare_cpu.json")
    assert data["settings"]["clock"] == "cpu"
    (rec,) = data["results"]
    assert rec["async_steps_per_s"] is None
    assert rec["ours_steps_per_s"] > 0
    assert data["settings"]["split"] is True
    for name in ("ours", "sync"):  # CPU time outside the physics call: positive, below the whole step
        outside = rec[f"{name}_outside_physics_us"]
        assert 0 < outside < 1e6 / rec[f"{name}_steps_per_s"] * 50, name


def test_the_gym_env_runs_the_env_model(tmp_path):
    """The MujocoEnv subclass loads the very model of the env, with its frame skip and actuators."""
    (gym_compare,) = import_benchmarks("gym_compare")
    ours = gym_compare.make_ours(1)
    try:
        gym_env = gym_compare.gym_factory(ours, str(tmp_path))()
        inner = gym_env.unwrapped
        model = ours.scene.model
        assert (inner.model.nq, inner.model.nv, inner.model.nu, inner.model.ngeom) == (
            model.nq,
            model.nv,
            model.nu,
            model.ngeom,
        )
        assert inner.frame_skip == ours.sim_steps_per_control * ours.sim.substeps == 20
        gym_env.reset(seed=0)
        action = gym_env.action_space.sample()
        obs, *_ = gym_env.step(action)
        assert obs.shape == (model.nq + model.nv,)
        driven = ours.robot.pos_act[: len(action)].numpy()
        assert (inner.data.ctrl[driven] == action.astype(float)).all()
        gym_env.close()
    finally:
        ours.close()
