"""Action terms: qpos variants, EEF pose through IK (toy solver), velocity and effort
terms that really drive velocity and effort; bad params are construction errors."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch
from functors_testlib import toy_ik_arm_cfg

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import ActionTermCfg

import embodichain_functors.actions as actions

NA = 7  # active joints of the arm part


def pos_ctrl(env) -> torch.Tensor:
    return env.sim.ctrl[:, env.robot.pos_act[env.active_joint_ids]].float()


def vel_ctrl(env) -> torch.Tensor:
    return env.sim.ctrl[:, env.robot.vel_act[env.active_joint_ids]].float()


def term(func, mode: str = "pre", **params) -> dict:
    return {"a": ActionTermCfg(func=func, mode=mode, params=params)}


def test_delta_qpos_on_a_subset_of_joints(build) -> None:
    env = build(control_parts=None, active_joint_ids=[1, 3, 5], actions=term(actions.DeltaQposTerm, scale=0.1))
    assert env.single_action_space == gym.spaces.Box(-1.0, 1.0, (3,), np.float32)
    env.reset()
    q = env.robot.get_qpos()[:, [1, 3, 5]]
    env.step(torch.tensor([[1.0, -1.0, 0.5]]).expand(4, 3))
    target = env.sim.ctrl[:, env.robot.pos_act[[1, 3, 5]]].float()
    assert torch.allclose(target, q + torch.tensor([0.1, -0.1, 0.05]), atol=1e-6)


def test_delta_qpos_clips_to_the_limits(build) -> None:
    env = build(actions=term(actions.DeltaQposTerm, scale=10.0))
    env.reset()
    env.step(torch.ones(4, NA))
    assert torch.allclose(pos_ctrl(env), torch.full((4, NA), 2.8))


def test_qpos_and_denormalized(build) -> None:
    env = build(actions=term(actions.QposTerm, scale=0.5))
    assert np.allclose(env.single_action_space.high, 5.6)
    env.reset()
    env.step(torch.full((4, NA), 0.4))
    assert torch.allclose(pos_ctrl(env), torch.full((4, NA), 0.2))
    env = build(actions=term(actions.QposDenormalizedTerm, joint_ids=[0, 1]))
    env.reset()
    env.step(torch.tensor([[-1.0, 1.0, 0.3, 0, 0, 0, 0]]).expand(4, NA))
    assert torch.allclose(pos_ctrl(env)[:, :3], torch.tensor([-2.8, 2.8, 0.3]).expand(4, 3), atol=1e-6)
    assert env.single_action_space.low[0] == -1
    assert env.single_action_space.low[2] == pytest.approx(-2.8)


def test_qpos_normalized_as_a_post_term(build) -> None:
    env = build(
        actions={**term(actions.QposTerm), **{"n": ActionTermCfg(func=actions.QposNormalizedTerm, mode="post")}}
    )
    env.reset()
    env.step(torch.tensor([[-2.8, 0.0, 2.8, 0, 0, 0, 0]]).expand(4, NA))
    assert torch.allclose(env.last_action[:, :3], torch.tensor([0.0, 0.5, 1.0]).expand(4, 3), atol=1e-6)
    assert torch.allclose(pos_ctrl(env)[:, 2], torch.full((4,), 2.8))  # the robot got real qpos


def test_eef_pose_7d_and_6d_through_ik(build) -> None:
    env = build(robot=toy_ik_arm_cfg(), actions=term(actions.EefPoseTerm, part_name="arm"))
    assert env.single_action_space.shape == (7,)
    env.reset()
    action = torch.tensor([[0.3, 0.1, 0.2, math.cos(0.25), 0, 0, math.sin(0.25)]]).expand(4, 7).clone()
    action[3, :3] = torch.tensor([3.0, 0, 0])  # unreachable for the toy solver
    command = env.action_manager.process_action(action)
    assert torch.equal(command["ik_success"], torch.tensor([True, True, True, False]))
    env.step(action)
    ctrl = pos_ctrl(env)
    assert torch.allclose(ctrl[:3, :4], torch.tensor([0.3, 0.1, 0.2, 0.5]).expand(3, 4), atol=1e-5)
    assert torch.allclose(ctrl[3], torch.zeros(NA), atol=1e-5)  # failed IK keeps the current joints
    env6 = build(robot=toy_ik_arm_cfg(), actions=term(actions.EefPoseTerm, pose_dim=6, scale=2.0))
    env6.reset()
    env6.step(torch.tensor([[0.1, 0.0, 0.1, 0.0, 0.0, 0.3]]).expand(4, 6))
    assert torch.allclose(pos_ctrl(env6)[:, :4], torch.tensor([0.2, 0.0, 0.2, 0.3]).expand(4, 4), atol=1e-5)
    with pytest.raises(ValueError, match="6D or 7D"):
        next(iter(env6.action_manager.terms().values())).process_action(torch.zeros(4, 5))


HAND = {"arm": ["joint[1-4]"], "hand": ["joint[5-7]"]}  # the toy solver solves joints 1-4


def eef_with_hand(build, **robot: Any):
    return build(
        robot=toy_ik_arm_cfg(parts=HAND, **robot),
        control_parts=["arm", "hand"],
        actions=term(actions.EefPoseTerm, part_name="arm", gripper_part="hand"),
    )


def test_eef_pose_with_a_gripper_part_expresses_joint_targets(build) -> None:
    """Pose then the hand's joint targets; joint targets -> action (FK) -> step drives them."""
    env = eef_with_hand(build)
    assert env.single_action_space.shape == (10,)
    assert np.allclose(env.single_action_space.low[7:], -2.8)
    names = env.action_manager.action_names()
    assert names[:7] == ["arm.x", "arm.y", "arm.z", "arm.qw", "arm.qx", "arm.qy", "arm.qz"]
    assert names[7:] == [str(env.robot.joint_names[j]) for j in env.robot.get_joint_ids("hand")]
    env.reset()
    qpos = torch.tensor([0.3, 0.1, 0.2, 0.5, 0.4, -0.3, 0.2]).expand(4, NA)
    action = env.action_manager.action_from_qpos(qpos)
    expected = [0.3, 0.1, 0.2, math.cos(0.25), 0, 0, math.sin(0.25), 0.4, -0.3, 0.2]
    assert torch.allclose(action, torch.tensor(expected).expand(4, 10), atol=1e-6)
    env.step(action)
    assert torch.allclose(pos_ctrl(env), qpos, atol=1e-5)
    with pytest.raises(ValueError, match="takes 10 values per env"):
        env.action_manager.process_action(torch.zeros(4, 7))


def test_eef_pose_actions_stay_in_one_quaternion_hemisphere(build) -> None:
    """Yaws of +-2.7 rad are 0.9 rad apart; written with w >= 0 their quaternions would be
    1.95 apart. In the hemisphere of the default pose (yaw 2.8) they stay close, and the
    flipped quaternion still commands the same rotation."""
    env = eef_with_hand(build, init_qpos=[0.0, 0.0, 0.0, 2.8, 0.0, 0.0, 0.0, 0.0, 0.0])
    env.reset()
    qpos = torch.zeros(4, NA)
    qpos[:, 3] = torch.tensor([2.7, -2.7, 2.7, -2.7])
    action = env.action_manager.action_from_qpos(qpos)
    assert (action[1, 3:7] - action[0, 3:7]).norm() < 0.5
    assert action[1, 3] < 0  # -q of the w >= 0 quaternion
    env.step(action)
    assert torch.allclose(pos_ctrl(env)[:, 3], qpos[:, 3], atol=1e-5)


def noisy_eef_run(build, episodes: int = 1) -> list[torch.Tensor]:
    """The toy arm's (x, y, z) joint targets over 5 steps of one clean action, (5, N, 3) per
    episode, each episode from reset seed 0."""
    env = build(robot=toy_ik_arm_cfg(), actions=term(actions.EefPoseTerm, noise_std=0.02, noise_steps=3))
    action = torch.tensor([[0.3, 0.1, 0.2, 1.0, 0.0, 0.0, 0.0]]).expand(4, 7)
    runs = []
    for _ in range(episodes):
        env.reset(seed=0)
        targets = []
        for _ in range(5):
            env.step(action)
            targets.append(pos_ctrl(env)[:, :3].clone())
        runs.append(torch.stack(targets))
    return runs


def test_eef_execution_noise_moves_the_executed_target_not_the_action(build) -> None:
    """Offsets in the first noise_steps steps only, different per env, the same again from the
    same seed (so an episode replays); the action a recorder keeps is untouched."""
    first, again = noisy_eef_run(build, episodes=2)
    clean = torch.tensor([0.3, 0.1, 0.2])
    offsets = first - clean
    assert (offsets[:3].norm(dim=-1) > 1e-4).all()  # every env, the first 3 steps
    assert offsets[:3].abs().max() < 0.1
    assert not torch.allclose(offsets[0, 0], offsets[0, 1])  # envs draw their own
    assert torch.allclose(offsets[3:], torch.zeros_like(offsets[3:]), atol=1e-6)  # then gone
    assert torch.equal(first, again)


@pytest.mark.parametrize(
    "params, param",
    [
        ({"noise_std": -0.01}, "noise_std"),
        ({"noise_std": 0.01, "noise_tau": 0}, "noise_tau"),
        ({"noise_std": 0.01, "noise_steps": 0}, "noise_steps"),
    ],
)
def test_bad_execution_noise_params(build, params, param) -> None:
    with pytest.raises(ConfigError, match=rf"params\.{param}"):
        build(robot=toy_ik_arm_cfg(), actions=term(actions.EefPoseTerm, **params))


def test_qvel_term_drives_velocity(build) -> None:
    env = build(actions=term(actions.QvelTerm, scale=0.5))
    env.reset()
    action = torch.zeros(4, NA)
    action[:, 0] = 1.0
    for _ in range(20):
        env.step(action)
    assert torch.allclose(vel_ctrl(env)[:, 0], torch.full((4,), 0.5))
    assert torch.allclose(env.robot.get_qvel()[:, 0], torch.full((4,), 0.5), atol=0.05)
    assert env.robot.get_qpos()[:, 0].min() > 0.15  # it keeps moving: no position drive holds it


def test_qf_term_drives_effort(build) -> None:
    env = build(actions=term(actions.QfTerm, scale=0.01))
    env.reset()
    action = torch.zeros(4, NA)
    action[:, 0] = 1.0  # 0.01 N*m about the vertical first joint
    speeds = []
    for _ in range(5):
        env.step(action)
        speeds.append(env.robot.get_qvel()[:, 0])
    assert torch.allclose(env.sim.qfrc_applied[:, env.robot.dof_adr[0]].float(), torch.full((4,), 0.01))
    assert all((b > a).all() for a, b in zip(speeds, speeds[1:]))  # accelerates freely: the drives are off
    assert (speeds[0] > 0).all()


@pytest.mark.parametrize(
    "func, params, param",
    [
        (actions.DeltaQposTerm, {"scael": 0.1}, "scael"),
        (actions.QposTerm, {"scale": 0}, "scale"),
        (actions.QposDenormalizedTerm, {"joint_ids": [9]}, "joint_ids"),
        (actions.QposNormalizedTerm, {"range": [1, 0]}, "range"),
        (actions.EefPoseTerm, {"pose_dim": 5}, "pose_dim"),
        (actions.EefPoseTerm, {"part_name": "leg"}, "part_name"),
        (actions.EefPoseTerm, {"part_name": "arm", "gripper_part": "hnad"}, "gripper_part"),
        (actions.EefPoseTerm, {"part_name": "arm", "gripper_part": "arm"}, "gripper_part"),
    ],
)
def test_bad_params(build, func, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        build(robot=toy_ik_arm_cfg(parts=HAND), control_parts=["arm", "hand"], actions=term(func, **params))
    assert err.value.path == "env.actions.a"
    assert f"params.{param}" in str(err.value)
    assert func.__name__ in str(err.value)


def test_a_gripper_part_must_be_active(build) -> None:
    with pytest.raises(ConfigError, match=r"params\.gripper_part: joints .* of 'hand' are not active .*add 'hand'"):
        build(
            robot=toy_ik_arm_cfg(parts=HAND),
            control_parts=["arm"],
            actions=term(actions.EefPoseTerm, part_name="arm", gripper_part="hand"),
        )


def test_eef_pose_needs_a_solver(build) -> None:
    with pytest.raises(ConfigError, match="solver"):
        build(actions=term(actions.EefPoseTerm))
