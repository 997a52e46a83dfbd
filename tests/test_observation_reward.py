"""ObservationManager (add with a/b/c nesting, modify by return or in place, errors)
and RewardManager (weights, unweighted info["rewards"], replace)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import pytest
import torch

from core_testlib import CUBE_INIT, ids_list, zero_action

from embodichain_core.envs import EmbodiedEnv
from embodichain_core.managers import Functor, ObservationCfg, RewardCfg, SceneEntityCfg


# -- observation functors -------------------------------------------------------------------------
def cube_pos(env: Any, obs: dict, entity_cfg: SceneEntityCfg) -> torch.Tensor:
    return env.scene[entity_cfg.uid].get_local_pose()[:, :3]


def env_index(env: Any, obs: dict) -> torch.Tensor:
    return torch.arange(env.num_envs, dtype=torch.float32).unsqueeze(-1)


def plus_ten(env: Any, data: torch.Tensor) -> torch.Tensor:
    return data + 10.0  # a new tensor: the manager must keep it


def fill_in_place(env: Any, data: torch.Tensor, value: float) -> None:
    data.fill_(value)  # mutates, returns None


def scale(env: Any, data: torch.Tensor, factor: float) -> torch.Tensor:
    return data * factor


def test_add_nested_name_creates_levels_and_space(make_env) -> None:
    env = make_env(
        observations={
            "cube": ObservationCfg(
                func=cube_pos, mode="add", name="object/cube/pos", params={"entity_cfg": SceneEntityCfg(uid="cube")}
            ),
            "idx": ObservationCfg(func=env_index, mode="add", name="robot/index"),
        }
    )
    obs, _ = env.reset()
    assert torch.allclose(obs["object"]["cube"]["pos"], torch.tensor([CUBE_INIT] * 2))
    assert set(obs["robot"]) == {"qpos", "qvel", "qf", "index"}
    assert obs["robot"]["index"][:, 0].tolist() == [0.0, 1.0]
    space = env.single_observation_space
    assert isinstance(space["object"]["cube"], gym.spaces.Dict)
    assert space["object"]["cube"]["pos"].shape == (3,)
    assert env.observation_space["object"]["cube"]["pos"].shape == (2, 3)
    assert space["robot"]["index"].shape == (1,)
    obs, *_ = env.step(zero_action(env))
    assert obs["object"]["cube"]["pos"].shape == (2, 3)


def test_modify_keeps_returned_tensor(make_env) -> None:
    env = make_env(observations={"shift": ObservationCfg(func=plus_ten, mode="modify", name="robot/qpos")})
    obs, _ = env.reset()
    adr = env.robot.qpos_adr[env.active_joint_ids]
    raw = env.sim.qpos[:, adr].float()
    assert torch.allclose(obs["robot"]["qpos"], raw + 10.0)
    obs, *_ = env.step(zero_action(env))
    assert torch.allclose(obs["robot"]["qpos"], env.sim.qpos[:, adr].float() + 10.0)


def test_modify_in_place_and_declaration_order(make_env) -> None:
    env = make_env(
        observations={
            "idx": ObservationCfg(func=env_index, mode="add", name="extra/idx"),
            "fill": ObservationCfg(func=fill_in_place, mode="modify", name="robot/qvel", params={"value": 3.0}),
            "scale_idx": ObservationCfg(func=scale, mode="modify", name="extra/idx", params={"factor": 4.0}),
        }
    )
    obs, _ = env.reset()
    assert torch.all(obs["robot"]["qvel"] == 3.0)
    assert obs["extra"]["idx"][:, 0].tolist() == [0.0, 4.0]  # modify ran after the add it reads


def test_modify_missing_key_names_the_functor(make_env) -> None:
    from embodichain_core.config.errors import ConfigError

    with pytest.raises(ConfigError, match=r"env\.observations\.norm") as err:
        make_env(observations={"norm": ObservationCfg(func=plus_ten, mode="modify", name="robot/joint_pos")})
    assert "joint_pos" in str(err.value)


def test_observation_needs_a_name(make_env) -> None:
    from embodichain_core.config.errors import ConfigError

    with pytest.raises(ConfigError, match=r"observations\.x\.name"):
        make_env(observations={"x": ObservationCfg(func=env_index, mode="add")})


# -- rewards ----------------------------------------------------------------------------------------
def const(env: Any, obs: Any, action: Any, info: dict, value: float) -> torch.Tensor:
    return torch.full((env.num_envs,), float(value))


def by_index(env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
    return torch.arange(env.num_envs, dtype=torch.float32)


def scalar(env: Any, obs: Any, action: Any, info: dict) -> float:
    return 0.25


class TaskRewardEnv(EmbodiedEnv):
    def get_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        return torch.full((self.num_envs,), 100.0)


def test_add_terms_are_weighted_and_info_is_unweighted(make_env) -> None:
    env = make_env(
        num_envs=3,
        rewards={
            "c": RewardCfg(func=const, weight=0.5, params={"value": 2.0}),
            "i": RewardCfg(func=by_index, weight=-3.0),
            "s": RewardCfg(func=scalar, weight=4.0),
        },
    )
    env.reset()
    _, reward, _, _, info = env.step(zero_action(env))
    assert reward.shape == (3,)
    assert reward.dtype == torch.float32
    assert torch.allclose(reward, torch.tensor([0.5 * 2 + 1.0, 0.5 * 2 - 3 + 1.0, 0.5 * 2 - 6 + 1.0]))
    assert set(info["rewards"]) == {"c", "i", "s"}
    assert torch.allclose(info["rewards"]["c"], torch.full((3,), 2.0))
    assert torch.allclose(info["rewards"]["i"], torch.tensor([0.0, 1.0, 2.0]))
    assert torch.allclose(info["rewards"]["s"], torch.full((3,), 0.25))


def test_task_reward_plus_terms(make_env, make_cfg) -> None:
    env = make_env(
        make_cfg(rewards={"c": RewardCfg(func=const, weight=2.0, params={"value": 1.5})}), env_cls=TaskRewardEnv
    )
    env.reset()
    _, reward, *_ = env.step(zero_action(env))
    assert torch.allclose(reward, torch.full((2,), 103.0))


def test_replace_overrides_task_reward_and_earlier_terms(make_env, make_cfg) -> None:
    env = make_env(
        make_cfg(
            rewards={
                "before": RewardCfg(func=const, weight=1.0, params={"value": 1.0}),
                "over": RewardCfg(func=const, mode="replace", weight=2.0, params={"value": 3.0}),
                "after": RewardCfg(func=const, weight=2.0, params={"value": 0.5}),
            }
        ),
        env_cls=TaskRewardEnv,
    )
    env.reset()
    _, reward, _, _, info = env.step(zero_action(env))
    assert torch.allclose(reward, torch.full((2,), 2.0 * 3.0 + 2.0 * 0.5))
    assert torch.allclose(info["rewards"]["over"], torch.full((2,), 3.0))
    assert torch.allclose(info["rewards"]["before"], torch.full((2,), 1.0))


def test_reward_with_wrong_shape_names_the_term(make_env) -> None:
    def bad(env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
        return torch.zeros(env.num_envs, 2)

    env = make_env(rewards={"bad": RewardCfg(func=bad)})
    env.reset()
    with pytest.raises(ValueError, match=r"env\.rewards\.bad"):
        env.step(zero_action(env))


def test_reward_mode_is_checked(make_env) -> None:
    from embodichain_core.config.errors import ConfigError

    with pytest.raises(ConfigError, match=r"env\.rewards\.c\.mode"):
        make_env(rewards={"c": RewardCfg(func=const, mode="multiply", params={"value": 1.0})})


# -- class functors are reset with the right ids (quirk Q3 fixed) ----------------------------------------
class CachedObs(Functor):
    """Caches a per-env value; ``reset`` clears the cache of the reset envs."""

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.cache = torch.full((env.num_envs, 1), float("nan"))
        self.resets: list = []

    def __call__(self, env: Any, obs: dict) -> torch.Tensor:
        fresh = torch.isnan(self.cache[:, 0])
        self.cache[fresh] = env._elapsed_steps[fresh].float().unsqueeze(-1) + 1.0
        return self.cache.clone()

    def reset(self, env_ids: Any = None) -> None:
        self.resets.append(ids_list(env_ids))
        self.cache[torch.as_tensor(env_ids).long() if env_ids is not None else slice(None)] = float("nan")


class ProgressReward(Functor):
    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.total = torch.zeros(env.num_envs)
        self.resets: list = []

    def __call__(self, env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
        self.total += 1.0
        return self.total.clone()

    def reset(self, env_ids: Any = None) -> None:
        self.resets.append(ids_list(env_ids))
        self.total[torch.as_tensor(env_ids).long()] = 0.0


def test_class_functors_reset_with_reset_ids(make_env) -> None:
    env = make_env(
        num_envs=3,
        observations={"cached": ObservationCfg(func=CachedObs, mode="add", name="cached")},
        rewards={"progress": RewardCfg(func=ProgressReward)},
    )
    obs_functor = env.observation_manager.get_functor("cached")
    rew_functor = env.reward_manager.get_functor("progress")
    env.reset()
    assert obs_functor.resets == [[0, 1, 2]]
    assert rew_functor.resets == [[0, 1, 2]]
    for _ in range(3):
        obs, reward, *_ = env.step(zero_action(env))
    assert reward.tolist() == [3.0, 3.0, 3.0]
    obs, _ = env.reset(options={"reset_ids": [1]})
    assert obs_functor.resets[-1] == [1]
    assert rew_functor.resets[-1] == [1]
    # env 1's cache was cleared, so it was recomputed at the reset's observation
    assert obs["cached"][:, 0].tolist() == [1.0, 1.0, 1.0]
    assert env.observation_manager.get_functor("cached").cache[:, 0].tolist() == [1.0, 1.0, 1.0]
    _, reward, *_ = env.step(zero_action(env))
    assert reward.tolist() == [4.0, 1.0, 4.0]
