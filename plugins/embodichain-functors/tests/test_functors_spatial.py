"""Spatial randomization: poses, joint positions, end-effector poses through IK (a toy
solver: the robots plugin provides real ones), root poses, virtual targets."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import CUBE_POS, apply, event, others, toy_ik_arm_cfg

from embodichain_core.config.errors import ConfigError
from embodichain_core.envs.episode_rng import EpisodeRandom
from embodichain_core.managers import SceneEntityCfg as E
from embodichain_core.sim.cfg import ArticulationCfg
from embodichain_core.utils.math import quat_to_euler_xyz

import embodichain_functors.randomization as rand

IDS = [0, 2]


def test_rigid_object_pose_relative_position_and_rotation(build) -> None:
    env = build(
        events=event(
            rand.randomize_rigid_object_pose,
            entity_cfg=E(uid="cube"),
            position_range=[[-0.1, -0.2, 0.0], [0.1, 0.2, 0.0]],
            rotation_range=[[0, 0, -90], [0, 0, 90]],
        )
    )
    cube = env.scene["cube"]
    before = cube.get_local_pose()
    cube.set_velocity(torch.ones(4, 6))
    ids = apply(env, IDS)
    pose = cube.get_local_pose()
    offset = pose[ids, :3] - torch.tensor(CUBE_POS)
    assert (offset[:, 0].abs() <= 0.1 + 1e-6).all()
    assert (offset[:, 1].abs() <= 0.2 + 1e-6).all()
    assert torch.allclose(offset[:, 2], torch.zeros(2), atol=1e-6)
    yaw = quat_to_euler_xyz(pose[ids, 3:].double())[:, 2]
    assert (yaw.abs() <= 90 + 1e-4).all()
    assert (yaw.abs() > 0).all()
    assert torch.equal(pose[others(IDS)], before[others(IDS)])
    assert torch.equal(cube.get_velocity()[ids], torch.zeros(2, 6))
    assert (cube.get_velocity()[others(IDS)] != 0).any()  # untouched envs keep their state


def test_rigid_object_pose_absolute_and_physics_steps_only_in_chosen_envs(build) -> None:
    env = build(
        events=event(
            rand.randomize_rigid_object_pose,
            entity_cfg=E(uid="cube"),
            position_range=[[0.3, 0.0, 0.3], [0.3, 0.0, 0.3]],
            relative_position=False,
            physics_update_step=10,
        )
    )
    before = env.scene["cube"].get_local_pose()
    ids = apply(env, IDS)
    pose = env.scene["cube"].get_local_pose()
    assert (pose[ids, 2] < 0.3).all()
    assert (pose[ids, 2] > 0.2).all()
    assert torch.equal(pose[others(IDS)], before[others(IDS)])


def test_robot_qpos_relative_and_clamped(build) -> None:
    env = build(
        events=event(
            rand.randomize_robot_qpos, entity_cfg=E(uid="arm", joint_names=["joint[1-3]"]), qpos_range=[-0.2, 0.2]
        )
    )
    arm = env.scene["arm"]
    before = arm.get_qpos()
    ids = apply(env, IDS)
    q = arm.get_qpos()
    assert ((q[ids, :3] - before[ids, :3]).abs() <= 0.2 + 1e-6).all()
    assert (q[ids, :3] != before[ids, :3]).all()
    assert torch.equal(q[ids, 3:], before[ids, 3:])
    assert torch.equal(q[others(IDS)], before[others(IDS)])
    assert torch.allclose(arm.get_qpos(target=True)[ids, :3], q[ids, :3])  # drive targets follow


def test_robot_qpos_absolute_with_joint_ids(build) -> None:
    env = build(
        events=event(
            rand.randomize_robot_qpos,
            entity_cfg=E(uid="arm"),
            qpos_range=[[2.0, -9], [2.5, -8]],
            relative_qpos=False,
            joint_ids=[0, 1],
        )
    )
    ids = apply(env, IDS)
    q = env.scene["arm"].get_qpos()
    assert ((q[ids, 0] >= 2.0) & (q[ids, 0] <= 2.5)).all()
    assert torch.allclose(q[ids, 1], torch.full((2,), -2.8))  # clamped to the lower limit


def test_robot_eef_pose_goes_through_ik_for_chosen_envs(build) -> None:
    env = build(
        robot=toy_ik_arm_cfg(),
        events=event(
            rand.randomize_robot_eef_pose,
            entity_cfg=E(uid="arm", control_parts=["arm"]),
            position_range=[[0.05, 0.05, 0.05], [0.1, 0.1, 0.1]],
            rotation_range=[[0, 0, 10], [0, 0, 20]],
        ),
    )
    arm, solver = env.scene["arm"], env.scene["arm"].solvers["arm"]
    before = arm.get_qpos()
    ids = apply(env, IDS)
    call = solver.calls[-1]
    assert len(call["target"]) == 2
    assert torch.allclose(call["seed"].float(), before[ids][:, :7])
    q = arm.get_qpos()
    assert (((q[ids, :3] - before[ids, :3]) >= 0.05 - 1e-5) & ((q[ids, :3] - before[ids, :3]) <= 0.1 + 1e-5)).all()
    dyaw = torch.rad2deg(q[ids, 3] - before[ids, 3])
    assert ((dyaw >= 10 - 1e-3) & (dyaw <= 20 + 1e-3)).all()
    assert torch.equal(q[others(IDS)], before[others(IDS)])


def test_robot_eef_pose_keeps_joints_where_ik_fails(build) -> None:
    env = build(
        robot=toy_ik_arm_cfg(),
        events=event(
            rand.randomize_robot_eef_pose,
            entity_cfg=E(uid="arm", control_parts=["arm"]),
            position_range=[[5.0, 0, 0], [5.0, 0, 0]],
        ),
    )
    before = env.scene["arm"].get_qpos()
    apply(env, IDS)
    assert torch.equal(env.scene["arm"].get_qpos(), before)


def test_robot_eef_pose_needs_a_solver(build) -> None:
    with pytest.raises(ConfigError, match="randomize_robot_eef_pose.*solver") as err:
        build(
            events=event(
                rand.randomize_robot_eef_pose, entity_cfg=E(uid="arm"), position_range=[[0, 0, 0], [0.1, 0.1, 0.1]]
            )
        )
    assert err.value.path == "env.events.ev.params.entity_cfg"


def test_fixed_base_root_pose_moves_the_robot_per_env(build) -> None:
    env = build(
        events=event(
            rand.randomize_articulation_root_pose,
            entity_cfg=E(uid="arm"),
            position_range=[[0.1, 0.2, 0.0], [0.2, 0.3, 0.0]],
            rotation_range=[[0, 0, 30], [0, 0, 30]],
        )
    )
    arm = env.scene["arm"]
    ids = apply(env, IDS)
    apply(env, IDS)  # relative to the configured pose: no drift
    root = arm.get_local_pose()
    assert ((root[ids, 0] >= 0.1 - 1e-6) & (root[ids, 0] <= 0.2 + 1e-6)).all()
    assert torch.allclose(
        quat_to_euler_xyz(root[ids, 3:].double())[:, 2], torch.full((2,), 30.0, dtype=torch.float64), atol=1e-3
    )
    assert torch.allclose(root[others(IDS)], torch.tensor([0.0, 0, 0, 1, 0, 0, 0]).expand(2, 7))
    hand = arm.get_link_pose("hand")
    assert not torch.allclose(hand[0, :3], hand[1, :3])  # the whole arm moved in env 0


def floating_box() -> ArticulationCfg:
    """A floating-base articulation ``box`` at (0, -0.5, 0.1)."""
    return ArticulationCfg(
        uid="box",
        fix_base=False,
        init_pos=(0.0, -0.5, 0.1),
        mjcf=(
            '<mujoco><worldbody><body name="base"><geom type="box" size=".05 .05 .05" mass="1"/>'
            '<body name="lid" pos="0 0 .06"><joint name="hinge" axis="1 0 0"/><geom type="box" size=".05 .05 .01" mass=".1"/>'
            "</body></body></worldbody></mujoco>"
        ),
    )


def test_floating_root_pose(build) -> None:
    env = build(
        articulation=[floating_box()],
        events=event(
            rand.randomize_articulation_root_pose, entity_cfg=E(uid="box"), position_range=[[0, 0, 0.2], [0, 0, 0.3]]
        ),
    )
    ids = apply(env, IDS)
    root = env.scene["box"].get_local_pose()
    assert ((root[ids, 2] >= 0.3 - 1e-5) & (root[ids, 2] <= 0.4 + 1e-5)).all()
    assert torch.allclose(root[others(IDS), 2], torch.full((2,), 0.1))


def test_floating_root_pose_draws_around_the_edited_init_root_pose(build) -> None:
    """An edited ``init_root_pose`` (what the articulation resets to) is the draws' centre."""
    env = build(
        articulation=[floating_box()],
        events=event(
            rand.randomize_articulation_root_pose, entity_cfg=E(uid="box"), position_range=[[0, 0, 0.2], [0, 0, 0.3]]
        ),
    )
    box = env.scene["box"]
    box.init_root_pose[:3] = torch.tensor([0.7, 0.2, 0.5], dtype=box.init_root_pose.dtype)  # in place
    ids = apply(env, IDS)
    root = box.get_local_pose()
    assert torch.allclose(root[ids, :2], torch.tensor([0.7, 0.2]).expand(2, 2), atol=1e-5)
    assert ((root[ids, 2] >= 0.7 - 1e-5) & (root[ids, 2] <= 0.8 + 1e-5)).all()


def test_target_pose_created_and_written_per_env(build) -> None:
    env = build(
        events=event(
            rand.randomize_target_pose,
            position_range=[[0.3, -0.2, 0.05], [0.6, 0.2, 0.05]],
            rotation_range=[[0, 0, -45], [0, 0, 45]],
            store_key="goal_pose",
        )
    )
    assert getattr(env, "goal_pose", None) is None
    ids = apply(env, IDS)
    goal = env.goal_pose
    assert goal.shape == (4, 4, 4)
    assert torch.equal(goal[others(IDS)], torch.eye(4).expand(2, 4, 4))
    assert ((goal[ids, 0, 3] >= 0.3) & (goal[ids, 0, 3] <= 0.6)).all()
    assert torch.allclose(goal[ids, 2, 3], torch.full((2,), 0.05))


def test_target_pose_relative_to_a_reference_entity(build) -> None:
    env = build(
        events=event(
            rand.randomize_target_pose,
            position_range=[[0, 0, 0.1], [0, 0, 0.1]],
            relative_position=True,
            reference_entity_cfg=E(uid="cube"),
        )
    )
    apply(env, [1])
    assert torch.allclose(env.goal_pose[1, :3, 3], torch.tensor(CUBE_POS) + torch.tensor([0, 0, 0.1]), atol=1e-5)


def test_get_random_pose_is_reproducible() -> None:
    class Env:
        rng = EpisodeRandom(5, seed=3)

    init = torch.tensor([[0.0, 0, 0, 1, 0, 0, 0]]).expand(5, 7)
    a = rand.get_random_pose(Env(), init, [[-1, -1, -1], [1, 1, 1]], [[0, 0, -180], [0, 0, 180]])
    Env.rng = EpisodeRandom(5, seed=3)
    b = rand.get_random_pose(Env(), init, [[-1, -1, -1], [1, 1, 1]], [[0, 0, -180], [0, 0, 180]])
    assert torch.equal(a, b)
    assert torch.allclose(a[:, 3:].norm(dim=-1), torch.ones(5, dtype=torch.float64))
    Env.rng = EpisodeRandom(5, seed=3)
    c = rand.get_random_pose(Env(), init[:2], [[-1, -1, -1], [1, 1, 1]], None, env_ids=[4, 1])
    assert torch.equal(c[:, :3], a[[4, 1], :3])  # row i draws from env env_ids[i]'s stream


@pytest.mark.parametrize(
    "func, params, param",
    [
        (
            rand.randomize_rigid_object_pose,
            {"entity_cfg": E(uid="cube"), "position_range": [[0, 0], [1, 1]]},
            "position_range",
        ),
        (rand.randomize_rigid_object_pose, {"entity_cfg": E(uid="arm")}, "entity_cfg"),
        (rand.randomize_robot_qpos, {"entity_cfg": E(uid="arm"), "qpos_range": [[0, 0], [1, 1]]}, "qpos_range"),
        (rand.randomize_robot_qpos, {"entity_cfg": E(uid="arm"), "qpos_range": [0, 1], "joint_ids": [42]}, "joint_ids"),
        (rand.randomize_target_pose, {"store_key": "not an identifier"}, "store_key"),
        (rand.randomize_articulation_root_pose, {"entity_cfg": E(uid="cube")}, "entity_cfg"),
    ],
)
def test_bad_params(build, func, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        apply(build(events=event(func, **params)), IDS)
    assert err.value.path == f"env.events.ev.params.{param}"
    assert func.__name__ in str(err.value)
