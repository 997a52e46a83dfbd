"""The rsl_rl adapter: batched TensorDict groups, time-outs in the extras, rsl_rl's own
PPO runner learning end to end, checkpoints written."""

from __future__ import annotations

from pathlib import Path

import torch
from rsl_rl.env import VecEnv
from rsl_rl.runners import OnPolicyRunner

from embodichain_rl.rsl_rl_env import RslRlVecEnv
from embodichain_rl.train_rsl_rl import default_train_cfg


def test_steps_the_batch_and_reports_time_outs(push_cube) -> None:
    vec = RslRlVecEnv(push_cube(3, max_episode_steps=4))
    assert isinstance(vec, VecEnv)
    assert vec.num_envs == 3
    assert vec.num_actions == 7
    assert vec.max_episode_length == 4
    obs = vec.get_observations()
    assert obs.batch_size == torch.Size([3])
    assert obs["policy"].shape == (3, vec.flattener.state_dim)
    for step in range(1, 5):
        obs, reward, dones, extras = vec.step(torch.zeros(3, 7))
        assert reward.shape == (3,)
        assert dones.dtype == torch.long
        assert obs["policy"].ndim == 2
        assert extras["time_outs"].tolist() == [step == 4] * 3
        assert dones.tolist() == [int(step == 4)] * 3
        assert "/success" in extras["log"]
    assert vec.episode_length_buf.tolist() == [0, 0, 0]  # autoreset in the same step
    vec.episode_length_buf = torch.tensor([1, 2, 3])
    assert vec.env.elapsed_steps.tolist() == [1, 2, 3]


def test_actions_are_clamped_to_the_action_space(push_cube) -> None:
    vec = RslRlVecEnv(push_cube(2), clip_actions=0.5)
    qpos = vec.env.robot.get_qpos()[:, :7].clone()
    vec.step(torch.full((2, 7), 100.0))  # DeltaQposTerm, scale 0.1: at most 0.05 rad per step
    target = vec.env.sim.ctrl[:, vec.env.robot.pos_act[vec.env.active_joint_ids]].float()
    assert torch.all(target - qpos <= 0.05 + 1e-5)


def test_rsl_rl_ppo_learns_two_iterations(push_cube, tmp_path: Path) -> None:
    rows = []
    vec = RslRlVecEnv(
        push_cube(4, max_episode_steps=6), on_stats=lambda steps, s: rows.append((steps, s)), stats_every=8
    )
    cfg = default_train_cfg(num_steps_per_env=8, save_interval=1)
    runner = OnPolicyRunner(vec, cfg, log_dir=str(tmp_path), device="cpu")
    before = [p.clone() for p in runner.alg.get_policy().parameters()]
    runner.learn(2)
    after = list(runner.alg.get_policy().parameters())
    assert any(not torch.equal(a, b) for a, b in zip(before, after))
    assert (tmp_path / "model_1.pt").is_file()
    assert [steps for steps, _ in rows] == [32, 64]
    assert rows[1][1].episodes == 4
    actions = runner.get_inference_policy()(vec.get_observations())
    assert actions.shape == (4, 7)
    assert torch.isfinite(actions).all()


def test_the_env_stays_usable_after_steps_under_inference_mode(push_cube) -> None:
    vec = RslRlVecEnv(push_cube(2, max_episode_steps=3))
    with torch.inference_mode():  # as rsl_rl's runner collects rollouts
        for _ in range(4):
            vec.step(torch.full((2, 7), 0.3))
    vec.reset(seed=1)  # in-place updates of the env's buffers outside inference mode
    vec.step(torch.zeros(2, 7))
