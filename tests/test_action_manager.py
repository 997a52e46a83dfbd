"""ActionManager: single and multiple pre terms, merging by input_key (qpos + qvel ->
position and velocity actuators, qf -> qfrc_applied), post terms, action spaces."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch

from core_testlib import ARM_ACTIVE

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import ActionTerm, ActionTermCfg
from embodichain_core.sim.cfg import JointDrivePropertiesCfg


class ScaledQpos(ActionTerm):
    """qpos = scale * action, policy range [-1, 1]."""

    input_key = "qpos"

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.scale = float(cfg.params.get("scale", 1.0))

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        return -torch.ones(self.action_dim), torch.ones(self.action_dim)

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return action * self.scale


class JointVelocity(ActionTerm):
    input_key = "qvel"

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        return torch.full((self.action_dim,), -2.0), torch.full((self.action_dim,), 2.0)

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return action.clone()


class JointEffort(ActionTerm):
    input_key = "qf"

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return action * 10.0


class FirstJointQpos(ActionTerm):
    """A term with its own dim (1): the first active joint's target, others at 0."""

    input_key = "qpos"

    @property
    def action_dim(self) -> int:
        return 1

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        return torch.tensor([-0.5]), torch.tensor([0.5])

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        out = torch.zeros(action.shape[0], len(self._env.active_joint_ids))
        out[:, 0] = action[:, 0]
        return out


class RecordingPost(ActionTerm):
    """A post term: records what it is given, returns it negated."""

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.seen: list = []

    def process_action(self, action: Any) -> Any:
        self.seen.append(action.clone())
        return -action


def pos_ctrl(env: Any) -> torch.Tensor:
    return env.sim.ctrl[:, env.robot.pos_act[env.active_joint_ids]]


def vel_ctrl(env: Any) -> torch.Tensor:
    return env.sim.ctrl[:, env.robot.vel_act[env.active_joint_ids]]


def test_without_terms_the_action_is_qpos(make_env) -> None:
    env = make_env()
    limits = env.robot.get_qpos_limits()[0, :ARM_ACTIVE].numpy()
    assert env.single_action_space == gym.spaces.Box(limits[:, 0], limits[:, 1], dtype=np.float32)
    assert env.action_space.shape == (2, ARM_ACTIVE)
    env.reset()
    action = torch.linspace(-0.3, 0.3, ARM_ACTIVE).expand(2, -1)
    env.step(action)
    assert torch.allclose(pos_ctrl(env), action.double())
    full = torch.zeros(2, env.robot.dof)  # full-dof commands are sliced to the active joints
    full[:, :ARM_ACTIVE] = 0.1
    env.step(full)
    assert torch.allclose(pos_ctrl(env), torch.full((2, ARM_ACTIVE), 0.1, dtype=torch.float64))
    with pytest.raises(ValueError, match=r"expected shape \(2, 7\)"):
        env.step(torch.zeros(2, 3))


def test_single_pre_term(make_env) -> None:
    env = make_env(actions={"arm": ActionTermCfg(func=ScaledQpos, params={"scale": 0.5})})
    assert env.single_action_space == gym.spaces.Box(-1.0, 1.0, (ARM_ACTIVE,), np.float32)
    assert env.action_manager.action_dim() == ARM_ACTIVE
    assert list(env.action_manager.terms("pre")) == ["arm"]
    env.reset()
    action = torch.full((2, ARM_ACTIVE), 0.8)
    env.step(action)
    assert torch.allclose(pos_ctrl(env), torch.full((2, ARM_ACTIVE), 0.4, dtype=torch.float64))


def test_two_pre_terms_split_flat_action_and_merge_by_input_key(make_env) -> None:
    env = make_env(
        actions={
            "pos": ActionTermCfg(func=ScaledQpos, params={"scale": 1.0}),
            "vel": ActionTermCfg(func=JointVelocity),
        }
    )
    space = env.single_action_space
    assert space.shape == (2 * ARM_ACTIVE,)
    assert np.allclose(space.low, [-1.0] * ARM_ACTIVE + [-2.0] * ARM_ACTIVE)
    assert np.allclose(space.high, [1.0] * ARM_ACTIVE + [2.0] * ARM_ACTIVE)
    assert env.action_space.shape == (2, 2 * ARM_ACTIVE)
    env.reset()
    qpos = torch.tensor([[0.1 * i for i in range(ARM_ACTIVE)], [-0.05 * i for i in range(ARM_ACTIVE)]])
    qvel = torch.tensor([[0.2] * ARM_ACTIVE, [-0.3] * ARM_ACTIVE])
    command = env.action_manager.process_action(torch.cat((qpos, qvel), -1))
    assert set(command) == {"qpos", "qvel"}
    env.step(torch.cat((qpos, qvel), -1))
    assert torch.allclose(pos_ctrl(env), qpos.double())
    assert torch.allclose(vel_ctrl(env), qvel.double())
    with pytest.raises(ValueError, match="total 14"):
        env.step(torch.zeros(2, ARM_ACTIVE))
    # a dict action is keyed by input_key
    env.step({"qpos": torch.zeros(2, ARM_ACTIVE), "qvel": torch.full((2, ARM_ACTIVE), 0.5)})
    assert torch.allclose(vel_ctrl(env), torch.full((2, ARM_ACTIVE), 0.5, dtype=torch.float64))


def test_terms_with_their_own_dims(make_env) -> None:
    env = make_env(actions={"first": ActionTermCfg(func=FirstJointQpos), "vel": ActionTermCfg(func=JointVelocity)})
    assert env.single_action_space.shape == (1 + ARM_ACTIVE,)
    assert env.single_action_space.low[0] == pytest.approx(-0.5)
    env.reset()
    action = torch.zeros(2, 1 + ARM_ACTIVE)
    action[:, 0] = torch.tensor([0.3, -0.2])
    action[:, 1:] = 0.7
    env.step(action)
    assert torch.allclose(pos_ctrl(env)[:, 0], torch.tensor([0.3, -0.2], dtype=torch.float64))
    assert torch.all(pos_ctrl(env)[:, 1:] == 0)
    assert torch.allclose(vel_ctrl(env), torch.full((2, ARM_ACTIVE), 0.7, dtype=torch.float64))


def test_qvel_command_drives_velocity(make_env, make_cfg) -> None:
    from core_testlib import base_cfg

    robot = base_cfg().robot.replace(drive_pros=JointDrivePropertiesCfg(stiffness=0.0, damping=200.0))
    env = make_env(make_cfg(robot=robot, actions={"vel": ActionTermCfg(func=JointVelocity)}))
    env.reset()
    action = torch.zeros(2, ARM_ACTIVE)
    action[:, 0] = torch.tensor([0.5, -0.8])  # joint1: vertical axis, no gravity load
    command = env.action_manager.process_action(action)
    assert isinstance(command, dict)
    assert set(command) == {"qvel"}
    for _ in range(3):
        obs, *_ = env.step(action)
    assert obs["robot"]["qvel"][:, 0].tolist() == pytest.approx([0.5, -0.8], abs=0.02)
    assert obs["robot"]["qpos"][0, 0] > 0.03
    assert obs["robot"]["qpos"][1, 0] < -0.05


def test_qf_command_writes_applied_forces(make_env, make_cfg) -> None:
    from core_testlib import base_cfg

    robot = base_cfg().robot.replace(drive_pros=JointDrivePropertiesCfg(stiffness=0.0, damping=0.0))
    env = make_env(make_cfg(robot=robot, actions={"effort": ActionTermCfg(func=JointEffort)}))
    env.reset()
    action = torch.zeros(2, ARM_ACTIVE)
    action[:, 0] = torch.tensor([0.2, -0.1])
    obs, *_ = env.step(action)
    dof = env.robot.dof_adr[env.active_joint_ids]
    assert torch.allclose(env.sim.qfrc_applied[:, dof], (action * 10.0).double())
    assert obs["robot"]["qf"][:, 0].tolist() == pytest.approx([2.0, -1.0])
    assert obs["robot"]["qvel"][0, 0] > 0
    assert obs["robot"]["qvel"][1, 0] < 0
    assert torch.all(env.sim.ctrl == 0)  # no drive target was written


def test_post_terms_run_after_the_step(make_env) -> None:
    env = make_env(
        actions={
            "arm": ActionTermCfg(func=ScaledQpos, params={"scale": 2.0}),
            "post": ActionTermCfg(func=RecordingPost, mode="post"),
        }
    )
    assert env.single_action_space.shape == (ARM_ACTIVE,)  # post terms add no action dims
    assert env.action_manager.action_dim("post") == ARM_ACTIVE
    post = env.action_manager.get_functor("post")
    env.reset()
    env.step(torch.full((2, ARM_ACTIVE), 0.1))
    assert len(post.seen) == 1
    assert torch.allclose(post.seen[0], torch.full((2, ARM_ACTIVE), 0.2))  # the pre-processed command
    assert torch.allclose(pos_ctrl(env), torch.full((2, ARM_ACTIVE), 0.2, dtype=torch.float64))
    out = env.action_manager.process_action(torch.ones(2, ARM_ACTIVE), "post")
    assert torch.equal(out, -torch.ones(2, ARM_ACTIVE))
    assert env.action_manager.process_action(torch.ones(2, ARM_ACTIVE), "pre").tolist() == [[2.0] * ARM_ACTIVE] * 2


def test_class_action_terms_are_reset(make_env) -> None:
    class Stateful(ScaledQpos):
        def __init__(self, cfg: Any, env: Any):
            super().__init__(cfg, env)
            self.resets: list = []

        def reset(self, env_ids: Any = None) -> None:
            self.resets.append(torch.as_tensor(env_ids).tolist())

    env = make_env(actions={"arm": ActionTermCfg(func=Stateful)})
    env.reset(options={"reset_ids": [1]})
    assert env.action_manager.get_functor("arm").resets == [[1]]


def test_action_term_errors(make_env) -> None:
    def not_a_term(env: Any, action: Any) -> Any:
        return action

    with pytest.raises(ConfigError, match=r"env\.actions\.arm\.func"):
        make_env(actions={"arm": ActionTermCfg(func=not_a_term)})
    with pytest.raises(ConfigError, match=r"env\.actions\.arm\.mode"):
        make_env(actions={"arm": ActionTermCfg(func=ScaledQpos, mode="during")})


class InvertibleQpos(ScaledQpos):
    """ScaledQpos that can express joint targets as its action."""

    def action_from_qpos(self, qpos: torch.Tensor) -> torch.Tensor:
        return qpos / self.scale


def test_joint_targets_become_the_terms_actions(make_env) -> None:
    """A scripted demo's joint targets in the env's action space: each pre term's action
    side by side; a term without the inverse is named; no terms: the targets as they are."""
    env = make_env(actions={"arm": ActionTermCfg(func=InvertibleQpos, params={"scale": 0.5})})
    env.reset()
    qpos = torch.linspace(-0.2, 0.2, ARM_ACTIVE).expand(2, -1)
    action = env.action_manager.action_from_qpos(qpos)
    assert torch.allclose(action, 2 * qpos)
    env.step(action)
    assert torch.allclose(pos_ctrl(env), qpos.double(), atol=1e-6)
    assert env.action_manager.action_names() == [str(env.robot.joint_names[j]) for j in env.active_joint_ids]
    two = make_env(actions={"a": ActionTermCfg(func=InvertibleQpos), "vel": ActionTermCfg(func=JointVelocity)})
    with pytest.raises(ValueError, match=r"actions\.vel: JointVelocity cannot express joint position targets"):
        two.action_manager.action_from_qpos(qpos)
    plain = make_env()
    assert torch.equal(plain.action_manager.action_from_qpos(qpos), qpos)


def test_a_term_of_its_own_width_names_its_values(make_env) -> None:
    env = make_env(actions={"first": ActionTermCfg(func=FirstJointQpos)})
    assert env.action_manager.action_names() == ["FirstJointQpos.0"]
