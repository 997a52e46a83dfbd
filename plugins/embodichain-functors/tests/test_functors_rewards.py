"""Reward functors: formulas, per-env state cleared on reset, bad params."""

from __future__ import annotations

import math

import pytest
import torch
from functors_testlib import BALL_POS, CUBE_POS, toy_ik_arm_cfg

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import RewardCfg
from embodichain_core.managers import SceneEntityCfg as E

import embodichain_functors.rewards as rewards

D_CUBE_BALL = math.dist(CUBE_POS, BALL_POS)


def terms(env, action=None) -> dict:
    action = torch.zeros(env.action_space.shape) if action is None else action
    return env.step(action)[4]["rewards"]


def test_distance_between_objects_linear_and_exponential(build) -> None:
    env = build(
        rewards={
            "lin": RewardCfg(
                func=rewards.distance_between_objects,
                params={"source_entity_cfg": E(uid="cube"), "target_entity_cfg": E(uid="ball")},
            ),
            "exp": RewardCfg(
                func=rewards.distance_between_objects,
                params={
                    "source_entity_cfg": E(uid="cube"),
                    "target_entity_cfg": E(uid="ball"),
                    "exponential": True,
                    "sigma": 0.2,
                },
            ),
        }
    )
    env.reset()
    t = terms(env)
    assert torch.allclose(t["lin"], torch.full((4,), -D_CUBE_BALL), atol=2e-3)
    assert torch.allclose(t["exp"], torch.full((4,), math.exp(-(D_CUBE_BALL**2) / 0.08)), atol=2e-3)


def test_distance_to_target_needs_the_key_and_supports_xy(build) -> None:
    env = build(
        rewards={
            "d": RewardCfg(
                func=rewards.distance_to_target,
                params={"source_entity_cfg": E(uid="cube"), "target_pose_key": "goal_pose", "use_xy_only": True},
            )
        }
    )
    with pytest.raises(KeyError, match="goal_pose"):  # before any reset: no goal yet
        terms(env)
    with pytest.raises(ConfigError, match="env.goal_pose, which does not exist after the first reset"):
        env.reset()  # no event stores it and the task did not set it
    env.goal_pose = torch.eye(4).repeat(4, 1, 1)
    env.goal_pose[:, :3, 3] = torch.tensor([0.5, 0.3, 1.0])
    assert torch.allclose(terms(env)["d"], torch.full((4,), -0.3), atol=2e-3)


def test_incremental_distance_state_is_cleared_on_reset(build) -> None:
    env = build(
        rewards={
            "inc": RewardCfg(
                func=rewards.incremental_distance_to_target,
                params={"source_entity_cfg": E(uid="cube"), "target_pose_key": "goal", "negative_weight": 2.0},
            )
        }
    )
    env.goal = torch.zeros(4, 3)
    env.reset()
    assert torch.equal(terms(env)["inc"], torch.zeros(4))  # first step
    cube = env.scene["cube"]
    pose = cube.get_local_pose()
    pose[:2, 0] -= 0.1  # envs 0, 1 get closer, 2, 3 farther
    pose[2:, 0] += 0.1
    cube.set_local_pose(pose)
    t = terms(env)["inc"]
    assert (t[:2] > 0).all()
    assert (t[2:] < 0).all()
    assert torch.allclose(t[2:], 2 * torch.tanh(torch.tensor(-1.0)).expand(2), atol=0.05)
    env.reset(options={"reset_ids": [0]})
    t = terms(env)["inc"]
    assert t[0] == 0
    assert t[1] == pytest.approx(0.0, abs=0.05)


def test_joint_velocity_and_limit_penalties(build) -> None:
    env = build(
        rewards={
            "v": RewardCfg(func=rewards.joint_velocity_penalty, params={"part_name": "arm"}),
            "vj": RewardCfg(func=rewards.joint_velocity_penalty, params={"joint_ids": [0]}),
            "lim": RewardCfg(func=rewards.joint_limit_penalty, params={"margin": 0.1, "joint_ids": list(range(7))}),
            "all": RewardCfg(func=rewards.joint_limit_penalty),
        }
    )
    env.reset()
    t = terms(env)
    assert torch.allclose(t["lim"], torch.zeros(4), atol=1e-6)
    assert torch.allclose(t["all"], torch.full((4,), -0.2), atol=1e-4)  # both fingers rest on a limit
    arm = env.scene["arm"]
    arm.set_qpos(torch.tensor([[2.75]]).expand(4, 1), joint_ids=[0], target=False)
    arm.set_qvel(torch.ones(4, 9), target=False)
    reward = env.reward_manager.compute(env.get_obs(), None, env.get_info(), torch.zeros(4))[1]
    assert torch.allclose(reward["v"], torch.full((4,), -math.sqrt(7)), atol=1e-4)
    assert torch.allclose(reward["vj"], torch.full((4,), -1.0), atol=1e-5)
    near = (5.6 * 0.1 - 0.05) / 5.6  # margin minus the normalized distance to the upper limit
    assert torch.allclose(reward["lim"], torch.full((4,), -near), atol=1e-3)


def test_action_smoothness_zero_first_then_negative_and_reset(build) -> None:
    env = build(rewards={"s": RewardCfg(func=rewards.action_smoothness_penalty)})
    env.reset()
    a = torch.zeros(env.action_space.shape)
    assert torch.equal(terms(env, a)["s"], torch.zeros(4))
    b = a.clone()
    b[:, 0] = 0.3
    assert torch.allclose(terms(env, b)["s"], torch.full((4,), -0.3))
    env.reset(options={"reset_ids": [3]})
    t = terms(env, a)["s"]
    assert t[3] == 0
    assert torch.allclose(t[:3], torch.full((3,), -0.3))


def test_action_smoothness_with_dict_actions() -> None:
    class Env:
        num_envs = 2

    term = rewards.action_smoothness_penalty.__new__(rewards.action_smoothness_penalty)
    term._prev, term._valid = None, torch.zeros(2, dtype=torch.bool)
    first = {"qpos": torch.zeros(2, 3), "ik_success": torch.ones(2, dtype=torch.bool)}
    assert torch.equal(term(Env(), None, first, {}), torch.zeros(2))
    second = {"qpos": torch.ones(2, 3), "ik_success": torch.ones(2, dtype=torch.bool)}
    assert torch.allclose(term(Env(), None, second, {}), torch.full((2,), -math.sqrt(3)))


def test_orientation_alignment(build) -> None:
    env = build(
        rewards={
            "o": RewardCfg(
                func=rewards.orientation_alignment,
                params={"source_entity_cfg": E(uid="cube"), "target_entity_cfg": E(uid="table")},
            )
        }
    )
    env.reset()
    cube = env.scene["cube"]
    pose = cube.get_local_pose()
    pose[2:, 3:] = torch.tensor([0.0, 1.0, 0.0, 0.0])  # 180 deg about x
    cube.set_local_pose(pose)
    r = env.reward_manager.compute(env.get_obs(), None, env.get_info(), torch.zeros(4))[1]["o"]
    assert torch.allclose(r, torch.tensor([1.0, 1.0, -1.0, -1.0]), atol=1e-5)


def test_success_reward() -> None:
    class Env:
        num_envs = 3

    assert torch.equal(rewards.success_reward(Env(), None, None, {}), torch.zeros(3))
    assert torch.equal(
        rewards.success_reward(Env(), None, None, {"success": torch.tensor([True, False, True])}),
        torch.tensor([1.0, 0.0, 1.0]),
    )
    assert torch.equal(rewards.success_reward(Env(), None, None, {"success": True}), torch.ones(3))


def test_reaching_behind_object(build) -> None:
    env = build(
        robot=toy_ik_arm_cfg(),
        rewards={
            "r": RewardCfg(
                func=rewards.reaching_behind_object,
                params={
                    "object_cfg": E(uid="cube"),
                    "target_pose_key": "goal",
                    "behind_offset": 0.1,
                    "height_offset": 0.0,
                },
            )
        },
    )
    env.goal = torch.tensor([[1.0, 0.0, 0.025]]).expand(4, 3)
    env.reset()
    arm = env.scene["arm"]
    target = torch.tensor([CUBE_POS[0] - 0.1, 0.0, CUBE_POS[2], 0.0])  # toy TCP = (q1, q2, q3)
    arm.set_qpos(target.expand(4, 4), joint_ids=[0, 1, 2, 3], target=False)
    r = env.reward_manager.compute(env.get_obs(), None, env.get_info(), torch.zeros(4))[1]["r"]
    assert torch.allclose(r, torch.ones(4), atol=1e-3)
    del env.goal
    with pytest.raises(KeyError, match="goal"):
        env.reward_manager.compute(env.get_obs(), None, env.get_info(), torch.zeros(4))


@pytest.mark.parametrize(
    "func, params, param",
    [
        (
            rewards.distance_between_objects,
            {"source_entity_cfg": E(uid="cube"), "target_entity_cfg": E(uid="ball"), "sigma": 0.0},
            "sigma",
        ),
        (rewards.joint_velocity_penalty, {"part_name": "leg"}, "part_name"),
        (rewards.joint_limit_penalty, {"robot_uid": "cube"}, "robot_uid"),
    ],
)
def test_bad_params(build, func, params, param) -> None:
    # the functor's check_params runs when the reward manager is built
    with pytest.raises(ConfigError) as err:
        build(rewards={"r": RewardCfg(func=func, params=params)})
    assert err.value.path == f"env.rewards.r.params.{param}"
    assert func.__name__ in str(err.value)


def test_bad_class_params_at_build(build) -> None:
    with pytest.raises(ConfigError) as err:
        build(
            rewards={
                "r": RewardCfg(
                    func=rewards.incremental_distance_to_target,
                    params={"source_entity_cfg": E(uid="cube"), "tanh_scale": -1.0},
                )
            }
        )
    assert err.value.path == "env.rewards.r"
    assert "params.tanh_scale" in str(err.value)
