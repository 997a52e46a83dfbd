"""The IL demo helpers (embodichain_tasks.il.common): grasp frames, interpolation, W1 config."""

from __future__ import annotations

import math

import pytest
import torch

import embodichain_core  # noqa: F401  (loads the plugins)
from embodichain_tasks.il import common


def test_frame_from_axes_is_a_rotation_with_the_given_axes() -> None:
    approach = torch.tensor([[0.0, 0.0, -1.0], [1.0, 0.2, 0.0]])
    closing = torch.tensor([[0.0, 1.0, 0.3], [0.0, 0.0, 1.0]])  # not orthogonal to approach: fixed up
    rot = common.frame_from_axes(approach, closing)
    eye = torch.eye(3, dtype=torch.float64).expand(2, 3, 3)
    assert torch.allclose(rot.transpose(-1, -2) @ rot, eye, atol=1e-12)
    assert torch.allclose(torch.linalg.det(rot), torch.ones(2, dtype=torch.float64))
    assert torch.allclose(rot[:, :, 2], torch.nn.functional.normalize(approach.double(), dim=-1))
    assert rot[0, 1, 1] > 0.9
    assert rot[1, 2, 1] > 0.99


def test_top_down_grasp_frame_closes_across_the_object() -> None:
    yaw = torch.tensor([0.0, 0.5])
    rot = common.top_down_grasp_frame(yaw)
    long_axis = torch.stack([torch.cos(yaw), torch.sin(yaw), torch.zeros(2)], -1).double()
    assert torch.allclose(rot[:, :, 2], torch.tensor([0.0, 0.0, -1.0], dtype=torch.float64).expand(2, 3))
    assert torch.allclose((rot[:, :, 1] * long_axis).sum(-1), torch.zeros(2, dtype=torch.float64), atol=1e-6)


@pytest.mark.parametrize("yaw", [0.3, 2.0, -2.5, math.pi / 2])
def test_yaw_of_folds_half_turns(yaw: float) -> None:
    rot = common.top_down_grasp_frame(torch.tensor([yaw]))
    z_rot = torch.tensor(
        [[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0, 0, 1]], dtype=torch.float64
    )
    folded = float(common.yaw_of(z_rot.unsqueeze(0))[0])
    assert abs(folded) <= math.pi / 2 + 1e-9
    assert math.isclose(math.cos(2 * folded), math.cos(2 * yaw), abs_tol=1e-9)
    assert rot.shape == (1, 3, 3)


def test_interpolation_is_smooth_and_ends_at_the_goal() -> None:
    start, goal = torch.zeros(2, 3), torch.ones(2, 3)
    path = common.interpolate_joints(start, goal, 10)
    assert path.shape == (10, 2, 3)
    assert torch.allclose(path[-1], goal)
    steps = (path[1:] - path[:-1])[:, 0, 0]
    assert (steps > 0).all()
    assert steps[0] < steps[4]
    assert steps[-1] < steps[4]


def test_w1_init_qpos_mirrors_the_arms_and_opens_the_grippers() -> None:
    qpos = common.w1_init_qpos()
    assert len(qpos) == 24  # W1 with two DH grippers, EmbodiChain breadth-first order
    assert qpos[:4] == list(common.W1_CROUCH)
    assert qpos[4:6] == list(common.W1_HEAD)
    right = qpos[7:20:2]
    assert right == [round(v, 4) for v in common.W1_RIGHT_READY_DOWN]
    assert qpos[6:20:2] == [-v for v in right]
    assert qpos[20:] == [0.0] * 4


def test_w1_robot_cfg_and_tune_contacts_compile_into_the_model() -> None:
    from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
    from embodichain_core.managers.cfg import EventCfg
    from embodichain_core.sim.cfg import RigidObjectCfg
    from embodichain_core.sim.shapes import CubeCfg

    cfg = EmbodiedEnvCfg(
        robot=common.w1_robot_cfg(),
        control_parts=["right_arm", "right_eef"],
        sim_cfg=common.il_sim_cfg(),
        verbose=False,
        rigid_object=[RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.04, 0.04, 0.04]), init_pos=(0.5, -0.2, 0.02))],
        events={
            "contacts": EventCfg(
                func="embodichain_tasks.il.common:tune_contacts",
                mode="startup",
                params={"impratio": 20.0, "entity_cfg": {"uid": "cube"}, "condim": 4, "friction": [1.2, 0.01, 0.0001]},
            )
        },
    )
    env = EmbodiedEnv(cfg, num_envs=1)
    model = env.sim.get_model(0)
    assert model.opt.impratio == 20.0
    assert model.opt.cone == 1
    cube = env.scene["cube"].body_id
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == cube and model.geom_contype[g]]
    assert geoms
    assert all(model.geom_condim[g] == 4 and model.geom_friction[g][0] == 1.2 for g in geoms)
    assert env.active_joint_ids == env.robot.get_joint_ids("right_arm") + env.robot.get_joint_ids("right_eef")
    qpos = env.robot.get_qpos()[0]
    assert torch.allclose(qpos, torch.tensor(common.w1_init_qpos()), atol=1e-5)
    env.close()


def test_demo_builder_rows_follow_the_active_joints() -> None:
    import gymnasium as gym

    env = gym.make("PickFork-v1", num_envs=2, verbose=False).unwrapped
    env.reset(seed=0)
    demo = common.DemoBuilder(env, arm="right_arm", eef="right_eef")
    tcp = env.robot.compute_fk(name="right_arm").to(torch.float64)
    lower = tcp.clone()
    lower[:, 2, 3] -= 0.05
    demo.linear_to_pose(lower, 5)
    demo.set_gripper(1.0, 3)
    demo.hold(2)
    rows = demo.actions()
    assert len(rows) == len(demo) == 10
    assert rows[0].shape == (2, 9)
    assert bool(demo.ik_ok.all())
    reached = env.robot.compute_fk(rows[4][:, :7], name="right_arm")
    assert torch.allclose(reached[:, :3, 3].double(), lower[:, :3, 3], atol=1e-3)
    assert torch.allclose(rows[-1][:, 7:], torch.full((2, 2), 0.025))  # gripper closed (DH: 0.025)
    env.close()
