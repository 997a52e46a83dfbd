"""The main job on the device route: PickFork-v1 as ``main_job.json`` configures it (the W1, its
stereo head camera through the Warp renderer, the visual and physical randomization, the
scripted demonstration) on backend ``warp``, 2 envs on Warp's CPU device, built and run inside
the device audit (the code paths a GPU takes; the recorder is left out: copying frames to the
host is its job).

Two promises for the GPU run: no op mixes device and host tensors anywhere in the build, the
demonstration planning and the steps (on CUDA each would raise), and a step of the scripted
episode, with the data-generation loop's bookkeeping, waits for the device at most twice (the
env's done flags and the loop's one read of the per-env flags). Slow: the Warp kernels of the
W1 scene and the renderer compile once (about a minute cold).
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Iterator

import pytest

from embodichain_core.sim.backend.device_audit import HostWaitAudit

pytest.importorskip("embodichain_tasks")
pytest.importorskip("embodichain_sensors")

sys.path.insert(0, os.path.join(os.path.dirname(__file__), os.pardir, "benchmarks"))
from main_job_syncs import main_job_env  # noqa: E402

WAIT_BUDGET = 2
STEPS = 5


def _make_env(work: str) -> Any:
    """The main job's env on backend warp, Warp's CPU device, 2 envs, 64x36 camera, no recorder."""
    args = argparse.Namespace(device="cpu", renderer="warp", encoder_processes="auto", image_size=(64, 36))
    return main_job_env(2, args, work)


def _plan(env: Any) -> tuple[list, Any]:
    """The scripted demonstration from a reset with seed 7, and its IK success flags."""
    env.reset(seed=7, options={"save_data": False})
    return env.unwrapped.create_demo_action_list(), env.unwrapped.demo_ik_ok


@pytest.fixture(scope="module")
def host_plan(tmp_path_factory: pytest.TempPathFactory) -> tuple[list, Any]:
    """:func:`_plan` on the host route (built and run before any audit)."""
    env = _make_env(str(tmp_path_factory.mktemp("host_route")))
    try:
        assert env.unwrapped.sim.capabilities.host_arrays
        return _plan(env)
    finally:
        env.close()


@pytest.fixture(scope="module")
def audited(host_plan: tuple, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Any, HostWaitAudit]]:
    audit = HostWaitAudit("cpu")
    with audit:
        env = _make_env(str(tmp_path_factory.mktemp("main_job")))
        try:
            yield env, audit
        finally:
            env.close()


def test_the_main_job_runs_with_no_op_mixing_device_and_host_tensors(audited: tuple) -> None:
    from embodichain_core.cli.run_loops import RunStats, run_episodes

    env, audit = audited
    HostWaitAudit.check_env(env.unwrapped)
    stats = RunStats()
    run_episodes(env, {"max_episodes": 2}, stats)  # reset, plan, step, commit: one scripted round
    assert stats.episodes >= 2
    assert stats.env_steps > 0
    mixed = audit.per_step(1)["mixed"]  # counted since the build
    assert not mixed, "ops that raise on CUDA:\n" + "\n".join(f"{m['count']} x {m['site']}" for m in mixed)


def test_a_scripted_step_waits_for_the_device_at_most_twice(audited: tuple) -> None:
    from embodichain_core.cli.run_loops import _done_success

    env, audit = audited
    base = env.unwrapped
    env.reset(options={"save_data": False})
    actions = base.create_demo_action_list()
    n = base.num_envs
    env.step(actions[0])  # first-step work (lazy caches) stays out of the count
    audit.clear()
    for action in actions[1 : STEPS + 1]:  # mid-episode: no reset in these steps
        _, _, terminated, truncated, info = env.step(action)
        _done_success(terminated, truncated, info, n)
    report = audit.per_step(STEPS)
    sites = "\n".join(f"{s['per_step']:.2f} {s['kind']}: {s['site']}" for s in report["sites"])
    assert report["per_step"] <= WAIT_BUDGET, f"{report['per_step']} host waits per step:\n{sites}"
    assert report["per_step"] >= 1, "the done flags are read every step: the audit counted nothing"
    assert not report["mixed"]
    assert base.sensors["eye_in_head"].get_data()["color"].device == base.device


def test_the_scripted_plan_is_the_same_on_both_routes(audited: tuple, host_plan: tuple) -> None:
    """The demonstration planned on the device route (IK started on the device, restarts on
    the CPU for what it leaves) is the one planned on the host route, from the same reset."""
    import torch

    env, _ = audited
    (device_plan, device_ok), (plan, ok) = _plan(env), host_plan
    assert torch.equal(device_ok.cpu(), ok.cpu())
    assert len(device_plan) == len(plan) > 50
    for step, (a, b) in enumerate(zip(device_plan, plan)):
        assert torch.allclose(a.cpu(), b.cpu(), atol=1e-5), f"step {step}: {(a.cpu() - b.cpu()).abs().max()}"
