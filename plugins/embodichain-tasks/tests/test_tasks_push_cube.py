"""PushCube-v1: construction paths, reward functors, success and truncation."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import pytest
import torch

from tasks_helpers import normalized_cfg

import embodichain_core  # noqa: F401  (loads the plugins)
from embodichain_core.config.loader import load_gym_config
from embodichain_tasks.plugin import CONFIG_DIR
from embodichain_tasks.rl.push_cube import CUBE_SIZE, PushCubeCfg, PushCubeEnv

CONFIG = CONFIG_DIR / "push_cube.json"
#: EmbodiChain's PushCubeRL reward weights.
WEIGHTS = {"reaching_reward": 0.03, "place_reward": 0.8, "action_penalty": 0.01, "success_bonus": 10.0}


@pytest.fixture(scope="module")
def env() -> Any:
    env = gym.make("PushCube-v1", num_envs=4, seed=0, verbose=False).unwrapped
    yield env
    env.close()


@pytest.mark.parametrize("num_envs", [1, 3])
def test_gym_make_default_cfg(num_envs: int, check_batched_env: Any) -> None:
    env = gym.make("PushCube-v1", num_envs=num_envs, verbose=False)
    assert isinstance(env.unwrapped, PushCubeEnv)
    assert env.unwrapped.num_envs == num_envs
    check_batched_env(env)
    env.close()


@pytest.mark.parametrize("num_envs", [1, 3])
def test_builds_from_the_json_config(num_envs: int, check_batched_env: Any) -> None:
    task_id, cfg, extras = load_gym_config(str(CONFIG), {"num_envs": num_envs, "verbose": False}, cfg_cls=PushCubeCfg)
    env = gym.make(task_id, cfg=cfg)
    assert env.unwrapped.num_envs == num_envs
    check_batched_env(env)
    env.close()


def test_json_config_is_equivalent_to_the_python_cfg() -> None:
    _, cfg, _ = load_gym_config(str(CONFIG))
    assert normalized_cfg(cfg) == normalized_cfg(PushCubeCfg())
    assert cfg.max_episode_steps == PushCubeCfg().max_episode_steps == 100


def test_run_env(embodichain_cli: Any) -> None:
    out = embodichain_cli("run-env", "PushCube-v1", "--max_episodes", "1", "--num_envs", "1")
    assert "run-env summary: PushCube-v1" in out.stdout
    assert "env steps    100" in out.stdout


def test_spaces_and_observations(env: Any) -> None:
    obs, _ = env.reset(seed=0)
    assert env.single_action_space.shape == (7,)
    assert float(env.single_action_space.low.min()) == -1.0
    assert float(env.single_action_space.high.max()) == 1.0
    assert obs["cube_pose"].shape == (4, 7)
    assert obs["goal_position"].shape == (4, 3)
    assert obs["eef_position"].shape == (4, 3)
    assert obs["robot"]["qpos"].shape == (4, 7)
    assert torch.allclose(obs["goal_position"], env.goal_pose[:, :3, 3])


def test_goal_is_random_and_ahead_of_the_cube(env: Any) -> None:
    goals, cubes = [], []
    for seed in (0, 1):
        obs, _ = env.reset(seed=seed)
        goals.append(obs["goal_position"].clone())
        cubes.append(obs["cube_pose"][:, :3].clone())
    assert not torch.allclose(goals[0], goals[1])
    offset = goals[0] - cubes[0]
    assert ((offset[:, 0] >= 0.15 - 1e-5) & (offset[:, 0] <= 0.25 + 1e-5)).all()
    assert (offset[:, 1].abs() <= 0.1 + 1e-5).all()
    assert (offset[:, 2].abs() < 1e-5).all()


def test_reward_is_the_sum_of_the_weighted_functors(env: Any) -> None:
    env.reset(seed=0)
    _, reward, _, _, info = env.step(torch.zeros(4, 7))
    terms = info["rewards"]  # unweighted
    assert set(terms) == set(WEIGHTS)
    assert torch.allclose(reward, sum(WEIGHTS[k] * v for k, v in terms.items()), atol=1e-5)
    distance = info["metrics"]["distance_to_goal"]
    assert torch.allclose(terms["place_reward"], torch.exp(-(distance**2) / (2 * 0.12**2)), atol=1e-4)
    assert ((terms["reaching_reward"] >= 0) & (terms["reaching_reward"] <= 1)).all()
    assert (terms["action_penalty"] <= 0).all()


def test_success_within_the_threshold_from_extensions(env: Any) -> None:
    env.reset(seed=0)
    assert env.success_threshold == 0.1
    cube = env.scene["cube"].get_local_pose()
    env.goal_pose[:, :3, 3] = cube[:, :3].float()
    env.goal_pose[0, 0, 3] += 0.05
    env.goal_pose[1, 0, 3] += 0.15
    _, reward, terminated, truncated, info = env.step(torch.zeros(4, 7))
    assert info["success"].tolist() == [True, False, True, True]
    assert torch.allclose(info["rewards"]["success_bonus"], info["success"].float())
    assert not terminated.any(), "success does not end the episode (ignore_terminations)"


def test_truncated_when_the_cube_falls_off_the_table(env: Any) -> None:
    env.reset(seed=0)
    cube = env.scene["cube"]
    pose = cube.get_local_pose()
    pose[2, 0] = 1.5  # beyond the table's front edge (x <= 0.95)
    cube.set_local_pose(pose[2:3], env_ids=[2])
    truncated = torch.zeros(4, dtype=torch.bool)
    for _ in range(15):
        _, _, _, step_truncated, info = env.step(torch.zeros(4, 7))
        truncated |= step_truncated
        if truncated[2]:
            break
    assert truncated.tolist() == [False, False, True, False]
    assert info["final_obs"]["cube_pose"][2, 2] < 0.43 - env.fall_depth
    assert abs(float(env.scene["cube"].get_local_pose()[2, 2]) - (0.4 + CUBE_SIZE / 2)) < 0.01, "auto-reset"
