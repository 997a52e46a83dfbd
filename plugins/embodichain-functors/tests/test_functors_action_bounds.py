"""Velocity and effort action terms have bounded action spaces: the robot's configured
limits, else an MJCF actuator's range, else the documented defaults; sampling the
action space keeps every env finite."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from functors_testlib import arm_cfg

from embodichain_core.managers import ActionTermCfg
from embodichain_core.sim.cfg import JointDrivePropertiesCfg, RobotCfg

import embodichain_functors.actions as actions

NA = 7
MOTOR_ARM = """<mujoco><compiler angle="radian"/><worldbody><body name="base">
  <geom type="cylinder" size="0.05 0.02" mass="1"/>
  <body name="l1" pos="0 0 0.05"><joint name="j1" axis="0 0 1" range="-2 2"/>
    <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03" mass="1"/>
    <body name="l2" pos="0 0 0.2"><joint name="j2" type="slide" axis="1 0 0" range="-0.1 0.1"/>
      <geom type="box" size="0.03 0.03 0.03" mass="0.2"/></body></body></body></worldbody>
  <actuator><motor joint="j1" ctrlrange="-2 2" gear="3"/>
    <velocity joint="j2" kv="10" ctrlrange="-0.25 0.25"/></actuator></mujoco>"""


def term(func, **params) -> dict:
    return {"a": ActionTermCfg(func=func, params=params)}


@pytest.mark.parametrize(
    "func, default",
    [(actions.QvelTerm, actions.DEFAULT_QVEL_LIMIT["hinge"]), (actions.QfTerm, actions.DEFAULT_QF_LIMIT["hinge"])],
)
def test_unlimited_joints_get_the_default_bounds(build, func, default) -> None:
    env = build(actions=term(func, scale=0.5))
    space = env.single_action_space
    assert np.allclose(space.high, default / 0.5)
    assert np.allclose(space.low, -default / 0.5)


def test_configured_limits_win(build) -> None:
    drives = JointDrivePropertiesCfg(max_velocity={"joint1": 1.5, ".*": 2.0}, max_effort={"joint1": 20.0, ".*": 30.0})
    robot = arm_cfg(drive_pros=drives)
    assert np.allclose(build(robot=robot, actions=term(actions.QvelTerm)).single_action_space.high, [1.5] + [2.0] * 6)
    assert np.allclose(
        build(robot=robot, actions=term(actions.QfTerm, scale=2.0)).single_action_space.high, [10.0] + [15.0] * 6
    )


def test_mjcf_actuator_ranges_bound_joints_without_limits(build) -> None:
    robot = RobotCfg(
        uid="arm",
        mjcf=MOTOR_ARM,
        control_parts={"arm": ["j1", "j2"]},
        drive_pros=JointDrivePropertiesCfg(drive_type="none"),
    )
    qf = build(robot=robot, actions=term(actions.QfTerm, disable_drives=False)).single_action_space
    assert np.allclose(qf.high, [6.0, actions.DEFAULT_QF_LIMIT["slide"]])  # motor: ctrlrange 2 * gear 3
    qvel = build(robot=robot, actions=term(actions.QvelTerm, zero_stiffness=False)).single_action_space
    assert np.allclose(qvel.high, [math.pi, 0.25])  # the velocity servo's ctrlrange


@pytest.mark.parametrize("func", [actions.QvelTerm, actions.QfTerm])
def test_sampled_actions_keep_every_env_finite(build, func) -> None:
    env = build(actions=term(func))
    env.reset(seed=0)
    env.action_space.seed(0)
    for _ in range(50):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert not info["diverged"].any()
        assert torch.isfinite(obs["robot"]["qpos"]).all()
        assert torch.isfinite(reward).all()


def test_out_of_space_actions_are_clipped_and_counted_or_raise_when_strict(build) -> None:
    env = build(actions=term(actions.DeltaQposTerm, scale=0.1))
    env.reset()
    assert env.out_of_space_actions == 0
    env.step(torch.zeros(4, NA))
    huge = torch.zeros(4, NA)
    huge[1, 2] = 1e30
    env.step(huge)  # DeltaQposTerm clips the target to the joint limit
    limits = env.robot.get_qpos_limits()[1, env.active_joint_ids[2]]
    assert env.robot.get_qpos(target=True)[1, env.active_joint_ids[2]] == pytest.approx(float(limits[1]))
    assert env.out_of_space_actions == 1
    env.step(torch.full((4, NA), 2.0))  # every env outside [-1, 1]
    assert env.out_of_space_actions == 5
    strict = build(actions=term(actions.DeltaQposTerm, scale=0.1), strict_actions=True)
    strict.reset()
    with pytest.raises(ValueError, match=r"env\(s\) \[1\]: value 1e\+30 at index 2 is not in \[-1, 1\]"):
        strict.step(huge)
    strict.step(torch.full((4, NA), 1.0))  # the bounds themselves are inside
