"""``benchmarks/step_breakdown.py`` as a script (phases of ``EmbodiedEnv.step``, syncs,
profiles) and ``benchmarks/gpu_step_profile.py``'s sync counter. No timing is asserted."""

from __future__ import annotations

import warnings

import pytest
from bench_testlib import import_benchmarks, run_benchmark


@pytest.fixture(scope="module")
def bench():
    return import_benchmarks("step_breakdown", "gpu_step_profile")


@pytest.mark.timeout(300)
def test_smoke_run_writes_every_section(tmp_path):
    _, data = run_benchmark("step_breakdown.py", "--smoke", out=tmp_path / "sb.json")
    (row,) = data["results"]
    sections = ("warmup", "plain", "phases", "syncs", "cprofile", "torch_profiler")
    assert [s for s in sections if "error" in row[s] or "skipped" in row[s]] == []
    phases = row["phases"]
    assert {"physics", "observations", "reward", "dones", "auto_reset"} <= set(phases["phases"])
    assert phases["phases"]["auto_reset"]["calls"] == pytest.approx(0.25)  # 4 steps, 4-step episodes
    assert {"observation.eef_position", "reward.reaching_reward"} <= set(phases["functors"])
    assert row["cprofile"]["project_by_total_time"][0]["function"].startswith("embodichain_core/envs/")


def test_phase_timer_times_each_phase_once_and_restores_the_env(bench):
    sb, gsp = bench
    env = sb.make_env(2, "mujoco_batch", "cpu", episode_length=2)
    try:
        funcs = {n: e.func for n, e in env.reward_manager.entries.items()}
        run, sync = sb._stepper(env, cuda=False)
        with gsp.PhaseTimer(env, sync) as timer:
            run(4)
        summary = timer.summary(4, wall=1.0)
        assert summary["phases"]["observations"]["calls"] == 1.0  # get_obs inside the auto-reset counts there
        assert summary["phases"]["auto_reset"]["calls"] == 0.5
        assert summary["functors"]["observation.eef_position"]["calls"] == 1.5  # step and reset observations
        assert "get_obs" not in vars(env)
        assert "advance" not in vars(env.sim)  # the physics phase, restored
        assert {n: e.func for n, e in env.reward_manager.entries.items()} == funcs
        run(1)  # still steps once restored
    finally:
        env.close()


def test_sync_counter_counts_torch_and_warp_waits_and_restores(bench):
    _, gsp = bench
    wp = pytest.importorskip("warp")
    original = wp.synchronize
    with gsp.SyncCounter(cuda=False) as counter:
        warnings.warn("called a synchronizing CUDA operation")
        warnings.warn("something else")
        wp.synchronize()
    assert wp.synchronize is original
    summary = counter.summary(steps=2)
    assert summary["per_step_by_kind"] == {"torch": 0.5, "warp.synchronize": 0.5}
    assert summary["other_warnings"] == {"UserWarning: something else": 1}


def test_repo_path_maps_installed_files_to_the_tree(bench):
    _, gsp = bench
    assert gsp.repo_path("/tmp/site/embodichain_core/envs/base_env.py") == "embodichain_core/envs/base_env.py"
    assert (
        gsp.repo_path("/x/site-packages/embodichain_tasks/rl/push_cube.py")
        == "plugins/embodichain-tasks/embodichain_tasks/rl/push_cube.py"
    )
    assert gsp.repo_path("/usr/lib/python3/json/__init__.py") is None
