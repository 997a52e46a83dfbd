"""PushCube-v1 on the warp backend (MuJoCo Warp on Warp's CPU device): 8 envs step 50 times
as on mujoco_batch within float32 tolerance, and the physics randomization functors give
per-env values that MuJoCo Warp simulates.

The actions stay small: where the fingers strike the table, MuJoCo Warp's contacts differ
from MuJoCo's and the trajectories drift apart (docs/backends.md, "What differs"). The cube
settling onto the table differs by up to 1e-4 m in the first step, then agrees to 1e-6.
"""

from __future__ import annotations

from typing import Any, Iterator

import gymnasium as gym
import numpy as np
import pytest
import torch

import embodichain_core  # noqa: F401  (loads the plugins)
from embodichain_core.managers import EventCfg, SceneEntityCfg
from embodichain_core.sim.backend.warp_sim import WarpSim
from embodichain_tasks.rl.push_cube import PushCubeCfg

import embodichain_functors.randomization as rand

NUM_ENVS = 8
STEPS = 50


def _push_cube(backend: str, num_envs: int = NUM_ENVS, events: Any = None) -> Any:
    cfg = PushCubeCfg()
    cfg.sim_cfg.backend = backend
    if events is not None:  # added to the task's own (which place the cube and the goal)
        cfg.events = {**vars(cfg.events), **events}
        cfg.custom_event_modes = sorted({e.mode for e in events.values()})
    return gym.make("PushCube-v1", cfg=cfg, num_envs=num_envs, seed=0, verbose=False).unwrapped


@pytest.fixture(scope="module")
def pair() -> Iterator[tuple[Any, Any]]:
    cpu, warp = _push_cube("mujoco_batch"), _push_cube("warp")
    yield cpu, warp
    cpu.close()
    warp.close()


def _flat(obs: Any, skip: str = "qf") -> torch.Tensor:
    """Every observation term, flattened per env (float64), but ``skip``."""
    if isinstance(obs, dict):
        return torch.cat([_flat(obs[k], skip) for k in sorted(obs) if k != skip], dim=-1)
    return obs.reshape(obs.shape[0], -1).double()


def _close(warp: Any, cpu: Any) -> bool:
    """Poses, positions and velocities within 2e-4; joint forces within 1e-2 N*m (a 1e4 N*m/rad
    drive turns float32 rounding of the joint angle, ~1e-7 rad, into ~1e-3 N*m)."""
    forces_close = torch.allclose(warp["robot"]["qf"].double(), cpu["robot"]["qf"].double(), atol=1e-2)
    return forces_close and torch.allclose(_flat(warp), _flat(cpu), atol=2e-4)


def test_push_cube_steps_as_on_mujoco_batch(pair: tuple) -> None:
    cpu, warp = pair
    assert isinstance(warp.sim, WarpSim)
    assert warp.sim.dtype == torch.float32
    obs_cpu, _ = cpu.reset(seed=0)
    obs_warp, _ = warp.reset(seed=0)
    assert _close(obs_warp, obs_cpu)  # the same seeded cube and goal poses
    rng = torch.Generator().manual_seed(1)
    for step in range(STEPS):
        action = (torch.rand(cpu.action_space.shape, generator=rng) * 2 - 1) * 0.3
        obs_cpu, reward_cpu, term_cpu, _, _ = cpu.step(action)
        obs_warp, reward_warp, term_warp, _, _ = warp.step(action)
        assert _close(obs_warp, obs_cpu), f"observations differ at step {step}"
        assert torch.allclose(reward_warp.double(), reward_cpu.double(), atol=1e-4), f"rewards differ at step {step}"
        assert torch.equal(term_warp, term_cpu)
    assert torch.allclose(warp.sim.qpos.double(), cpu.sim.qpos, atol=2e-4)
    assert torch.allclose(warp.sim.qvel.double(), cpu.sim.qvel, atol=1e-3)
    arm = cpu.scene["arm"]
    travel = (cpu.sim.qpos[:, arm.qpos_adr] - torch.as_tensor(cpu.scene.model.qpos0)[arm.qpos_adr]).abs().max()
    assert travel > 0.05, "the actions did not move the arm: the comparison is void"


def test_randomization_functors_give_per_env_values_on_warp() -> None:
    cube, arm = SceneEntityCfg(uid="cube"), SceneEntityCfg(uid="arm", joint_names=["joint[1-3]"])
    events = {
        "mass": EventCfg(
            func=rand.randomize_rigid_object_mass, mode="test", params={"entity_cfg": cube, "mass_range": [0.1, 1.0]}
        ),
        "friction": EventCfg(
            func=rand.randomize_rigid_object_friction,
            mode="test",
            params={"entity_cfg": cube, "friction_range": [0.2, 1.0]},
        ),
        "damping": EventCfg(
            func=rand.randomize_joint_damping, mode="test", params={"entity_cfg": arm, "damping_range": [0.5, 2.0]}
        ),
    }
    env = _push_cube("warp", num_envs=4, events=events)
    try:
        sim, body = env.sim, env.scene["cube"].body_id
        env.reset(seed=0)
        env.event_manager.apply("test", torch.arange(4))
        mass = np.array(sim.model_field("body_mass")[:, body])
        friction = np.array(sim.model_field("geom_friction")[:, env.scene["cube"].geom_ids[0], 0])
        damping = np.array(sim.model_field("dof_damping")[:, env.scene["arm"].dof_adr[:3]])
        for values, (low, high) in ((mass, (0.1, 1.0)), (friction, (0.2, 1.0)), (damping, (0.5, 2.0))):
            assert ((values >= low - 1e-6) & (values <= high + 1e-6)).all(), values
            assert len(np.unique(values.round(6), axis=0)) == 4, f"not one value per env: {values}"
        assert all(sim.is_per_env(f) for f in ("body_mass", "geom_friction", "dof_damping"))
        env.step(torch.zeros(env.action_space.shape))  # one set_const for the whole event pass, then the step
        for i in range(4):
            assert np.isclose(sim.get_model(i).body_subtreemass[body], mass[i], rtol=1e-6)
    finally:
        env.close()


def test_gpu_throughput_smoke_run_writes_json(tmp_path: Any) -> None:
    """``benchmarks/gpu_throughput.py --smoke`` (Warp's CPU device) runs and writes its record;
    no timing is asserted."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[3]
    out = tmp_path / "gpu.json"
    proc = subprocess.run(
        [sys.executable, str(root / "benchmarks" / "gpu_throughput.py"), "--smoke", "--out", str(out)],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=280,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "| num_envs |" in proc.stdout
    data = json.loads(out.read_text())
    (row,) = data["results"]
    assert (row["num_envs"], row["device"], row["steps"]) == (8, "cpu", 3)
    assert row["env_steps_per_s"] > 0
    assert row["raw_steps_per_s"] > 0
    assert row["ratio"] == pytest.approx(row["env_steps_per_s"] / row["raw_steps_per_s"])
    assert data["meets_targets"] is None  # no 4 096-env row in a smoke run
    bad = subprocess.run(
        [sys.executable, str(root / "benchmarks" / "gpu_throughput.py"), "--steps", "0"],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert bad.returncode == 2
    assert "--steps must be positive" in bad.stderr
