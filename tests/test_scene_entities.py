"""Scene entities on a batch: rigid objects, kinematic backgrounds, articulations
(breadth-first joint order, mimic joints, drives), lights, URDF articulations."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import torch

from scenes import DRAWER_URDF, seven_dof_arm_mjcf

from embodichain_core.sim.scene_build.builder import light_diffuse
from embodichain_core.sim.cfg import (
    ArticulationCfg,
    JointDrivePropertiesCfg,
    LightCfg,
    RigidObjectCfg,
    RobotCfg,
    SimulationManagerCfg,
)
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.shapes import CubeCfg

BRANCHING_MJCF = """
<mujoco model="tree">
  <worldbody>
    <body name="root">
      <geom type="sphere" size="0.05" mass="1"/>
      <body name="a" pos="0.1 0 0">
        <joint name="ja" type="hinge" axis="0 0 1"/>
        <geom type="sphere" size="0.02" mass="0.1"/>
        <body name="a1" pos="0.1 0 0">
          <joint name="ja1" type="hinge" axis="0 0 1"/>
          <geom type="sphere" size="0.02" mass="0.1"/>
        </body>
      </body>
      <body name="b" pos="-0.1 0 0">
        <joint name="jb" type="slide" axis="1 0 0" range="-0.1 0.1"/>
        <geom type="sphere" size="0.02" mass="0.1"/>
        <body name="b1" pos="-0.1 0 0">
          <joint name="jb1" type="hinge" axis="0 1 0"/>
          <geom type="sphere" size="0.02" mass="0.1"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

MIMIC_MJCF = """
<mujoco model="pair">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <geom type="box" size="0.05 0.05 0.05" mass="1"/>
      <body name="l1" pos="0 0 0.1">
        <joint name="lead" type="hinge" axis="0 0 1" range="-2 2"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/>
      </body>
      <body name="l2" pos="0 0 0.2">
        <joint name="follow" type="hinge" axis="0 0 1" range="-2 2"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/>
      </body>
    </body>
  </worldbody>
  <equality><joint joint1="follow" joint2="lead" polycoef="0.1 -0.5 0 0 0"/></equality>
</mujoco>
"""


def build(num_envs: int = 3, **entities) -> Scene:
    scene = Scene(SimulationManagerCfg(), num_envs)
    for cfg in entities.get("robots", []):
        scene.add_robot(cfg)
    for cfg in entities.get("articulations", []):
        scene.add_articulation(cfg)
    for cfg in entities.get("objects", []):
        scene.add_rigid_object(cfg)
    for cfg in entities.get("backgrounds", []):
        scene.add_rigid_object(cfg, background=True)
    for cfg in entities.get("lights", []):
        scene.add_light(cfg)
    scene.build()
    return scene


def cube_scene(num_envs: int = 3) -> Scene:
    return build(
        num_envs, objects=[RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.1, 0.1, 0.1]), init_pos=(0.0, 0.0, 0.5))]
    )


# -- rigid objects ------------------------------------------------------------------------------------------
def test_rigid_pose_and_world_velocity_round_trip() -> None:
    scene = cube_scene()
    cube = scene["cube"]
    half = math.sqrt(0.5)
    pose = torch.tensor(
        [
            [0.1, 0.2, 0.6, half, 0.0, 0.0, half],  # 90 deg about z
            [0.3, 0.1, 0.7, half, half, 0.0, 0.0],  # 90 deg about x
            [0.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0],
        ]
    )
    cube.set_local_pose(pose)
    assert torch.allclose(cube.get_local_pose(), pose, atol=1e-6)
    vel = torch.tensor([[1.0, 2.0, 3.0, 0.5, 0.0, 0.0], [0.0, 0.0, 0.1, 0.0, 0.3, 0.4], [0.2, 0.0, 0.0, 0.0, 0.0, 1.0]])
    cube.set_velocity(vel)
    assert torch.allclose(cube.get_velocity(), vel, atol=1e-6)
    # independent check with MuJoCo: world-frame angular and linear velocity of the body
    res = np.zeros(6)
    for env in range(3):
        data = scene.sim.get_data(env)
        mujoco.mj_objectVelocity(scene.sim.get_model(env), data, mujoco.mjtObj.mjOBJ_BODY, cube.body_id, res, 0)
        assert np.allclose(res[:3], vel[env, 3:].numpy(), atol=1e-6)
        assert np.allclose(res[3:], vel[env, :3].numpy(), atol=1e-6)
    # the free joint stores env 0's angular velocity in the body frame: world x -> body -y... after 90 deg about z
    assert scene.sim.qvel[0, cube.dof_adr + 3 : cube.dof_adr + 6].tolist() == pytest.approx([0.0, -0.5, 0.0], abs=1e-9)
    # a push without spin (the fast path) stops the spin and keeps the world-frame linear part
    push = torch.tensor([[0.2, -0.1, 0.0, 0.0, 0.0, 0.0]] * 3)
    cube.set_velocity(push)
    assert torch.allclose(cube.get_velocity(), push, atol=1e-6)
    assert not scene.sim.qvel[:, cube.dof_adr + 3 : cube.dof_adr + 6].any()
    cube.set_local_pose(pose[[2]] + torch.tensor([[0.0, 0.0, 1.0, 0, 0, 0, 0]]), env_ids=[2])
    assert torch.equal(cube.get_local_pose()[:2], pose[:2].float())


def test_matrix_pose_and_env_id_forms() -> None:
    scene = cube_scene()
    cube = scene["cube"]
    mat = torch.eye(4).expand(2, 4, 4).clone()
    mat[:, :3, 3] = torch.tensor([[1.0, 0.0, 0.2], [2.0, 0.0, 0.2]])
    cube.set_local_pose(mat, env_ids=torch.tensor([True, False, True]))
    pose = cube.get_local_pose()
    assert pose[:, 0].tolist() == pytest.approx([1.0, 0.0, 2.0])
    assert torch.allclose(cube.get_local_pose(to_matrix=True)[2], mat[1], atol=1e-6)


def test_set_mass_per_env_only_affects_those_envs() -> None:
    scene = cube_scene()
    cube = scene["cube"]
    base_inertia = scene.model.body_inertia[cube.body_id].copy()
    cube.set_mass(torch.tensor([2.0, 4.0]), env_ids=[0, 2])
    assert cube.get_mass().tolist() == pytest.approx([2.0, 1.0, 4.0])
    for env, mass in enumerate([2.0, 1.0, 4.0]):
        model = scene.sim.get_model(env)
        assert model.body_mass[cube.body_id] == pytest.approx(mass)
        assert np.allclose(model.body_inertia[cube.body_id], base_inertia * mass)
    with pytest.raises(ValueError):
        cube.set_mass(0.0, env_ids=[1])
    # a heavier cube does not fall faster, but a push of the same impulse moves it less
    scene.sim.xfrc_applied[:, cube.body_id, 0] = 10.0
    scene.sim.step(5)
    vx = cube.get_velocity()[:, 0]
    assert vx[1] > vx[0] > vx[2] > 0


def test_kinematic_background_moves_per_env() -> None:
    table = RigidObjectCfg(
        uid="table", shape=CubeCfg(size=[0.4, 0.4, 0.4]), init_pos=(0.0, 0.0, 0.2), body_type="kinematic"
    )
    scene = build(3, backgrounds=[table])
    bg = scene["table"]
    assert "table" in scene.backgrounds
    assert not bg.is_dynamic
    pose = bg.get_local_pose()[[1]].clone()
    pose[:, 0] += 0.5
    bg.set_local_pose(pose, env_ids=[1])
    scene.sim.step(10)  # kinematic: no gravity, stays where it was put
    assert bg.get_local_pose()[:, 0].tolist() == pytest.approx([0.0, 0.5, 0.0])
    assert scene.sim.xpos[:, bg.body_id, 0].tolist() == pytest.approx([0.0, 0.5, 0.0])
    assert scene.sim.xpos[:, bg.body_id, 2].tolist() == pytest.approx([0.2] * 3)
    assert torch.all(bg.get_velocity() == 0)
    bg.reset([1])
    assert bg.get_local_pose()[1, 0] == pytest.approx(0.0)


def test_dynamic_object_falls_and_resets() -> None:
    scene = cube_scene(2)
    cube = scene["cube"]
    scene.sim.step(40)
    z = cube.get_local_pose()[:, 2]
    assert torch.all(z < 0.2)
    cube.reset([0])
    assert cube.get_local_pose()[:, 2].tolist() == pytest.approx([0.5, float(z[1])])
    assert torch.all(cube.get_velocity()[0] == 0)


# -- articulations -------------------------------------------------------------------------------------------
def test_bfs_joint_order_differs_from_mujoco_dfs() -> None:
    scene = build(2, articulations=[ArticulationCfg(uid="tree", mjcf=BRANCHING_MJCF)])
    tree = scene["tree"]
    model = scene.model
    mujoco_order = [
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j).split("/", 1)[1]
        for j in range(model.njnt)
        if mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j).startswith("tree/")
    ]
    assert mujoco_order == ["ja", "ja1", "jb", "jb1"]  # depth first
    assert tree.joint_names == ["ja", "jb", "ja1", "jb1"]  # EmbodiChain: breadth first
    assert tree.link_names == ["root", "a", "b", "a1", "b1"]
    tree.set_qpos(torch.tensor([0.1, 0.05, 0.3, 0.4]), target=False)
    for name, value in zip(tree.joint_names, [0.1, 0.05, 0.3, 0.4]):
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"tree/{name}")
        assert scene.sim.qpos[:, model.jnt_qposadr[jid]].tolist() == pytest.approx([value, value])
    assert tree.find_joints("j.1")[0] == [2, 3]
    limits = tree.get_qpos_limits()[0]
    assert limits[1].tolist() == pytest.approx([-0.1, 0.1])
    assert math.isinf(limits[0, 0])
    assert limits[0, 0] < 0


def test_mimic_joint_follows_its_parent_on_teleport() -> None:
    scene = build(2, articulations=[ArticulationCfg(uid="pair", mjcf=MIMIC_MJCF)])
    pair = scene["pair"]
    assert pair.joint_names == ["lead", "follow"]
    assert pair.mimic_ids == [1]
    assert pair.mimic_parents == [0]
    pair.set_qpos(torch.tensor([[0.4], [-0.6]]), joint_ids=[0], env_ids=[0, 1], target=False)
    q = pair.get_qpos()
    assert q[:, 0].tolist() == pytest.approx([0.4, -0.6])
    assert q[:, 1].tolist() == pytest.approx([0.1 - 0.5 * 0.4, 0.1 + 0.5 * 0.6])
    scene.sim.step(20)  # the equality constraint keeps it there
    q = pair.get_qpos()
    assert q[:, 1].tolist() == pytest.approx((0.1 - 0.5 * q[:, 0]).tolist(), abs=1e-3)


def test_robot_mimic_finger_and_active_joints() -> None:
    scene = build(
        2,
        robots=[
            RobotCfg(
                uid="arm", mjcf=seven_dof_arm_mjcf(), control_parts={"arm": ["joint[1-7]"], "hand": ["finger_joint.*"]}
            )
        ],
    )
    arm = scene["arm"]
    assert arm.dof == 9
    assert arm.mimic_ids == [8]
    assert arm.active_joint_ids == list(range(8))
    assert arm.get_joint_ids("hand") == [7, 8]
    assert arm.get_joint_ids("hand", remove_mimic=True) == [7]
    arm.set_qpos(torch.tensor([0.03]), joint_ids=[7], target=False)
    assert arm.get_qpos()[:, 8].tolist() == pytest.approx([0.03, 0.03])
    with pytest.raises(KeyError, match="Did you mean 'arm'"):
        arm.get_joint_ids("arms")


def arm_scene(num_envs: int = 2) -> Scene:
    return build(
        num_envs, robots=[RobotCfg(uid="arm", mjcf=seven_dof_arm_mjcf(), control_parts={"arm": ["joint[1-7]"]})]
    )


def test_set_qpos_teleport_versus_target() -> None:
    scene = arm_scene()
    arm = scene["arm"]
    target = torch.tensor([0.3, -0.2, 0.1, 0.4, 0.0, 0.2, -0.1])
    arm.set_qpos(target, joint_ids=list(range(7)), env_ids=[1])  # target=True by default
    assert torch.all(arm.get_qpos() == 0)  # nothing moved yet
    assert torch.allclose(arm.get_qpos(target=True)[1, :7], target)
    assert torch.all(arm.get_qpos(target=True)[0] == 0)
    assert torch.allclose(scene.sim.ctrl[1, arm.pos_act[:7]], target.double())
    arm.set_qpos(target, joint_ids=list(range(7)), env_ids=[0], target=False)
    assert torch.allclose(arm.get_qpos()[0, :7], target)  # teleported
    assert torch.allclose(arm.get_qpos(target=True)[0, :7], target)  # and holds there
    assert torch.all(arm.get_qpos()[1] == 0)
    # the link poses follow the teleport once derived fields are read
    assert not torch.allclose(arm.get_link_pose("hand")[0], arm.get_link_pose("hand")[1])


def test_drive_tracks_its_target() -> None:
    scene = arm_scene()
    arm = scene["arm"]
    target = torch.tensor([0.5, 0.3, -0.4, 0.6, 0.2, -0.3, 0.1])
    arm.set_qpos(target, joint_ids=list(range(7)), env_ids=[0])
    scene.sim.step(100)  # 1 s
    q = arm.get_qpos()
    assert torch.allclose(q[0, :7], target, atol=0.01)
    assert torch.allclose(q[1], torch.zeros(9), atol=1e-3)
    assert arm.get_qvel()[0].abs().max() < 0.05


def test_joint_drive_and_velocity_targets() -> None:
    scene = build(
        2,
        robots=[
            RobotCfg(
                uid="arm", mjcf=seven_dof_arm_mjcf(), drive_pros=JointDrivePropertiesCfg(stiffness=0.0, damping=100.0)
            )
        ],
    )
    arm = scene["arm"]
    arm.set_qvel(torch.tensor([0.4]), joint_ids=[0], env_ids=[1])
    assert arm.get_qvel(target=True)[:, 0].tolist() == pytest.approx([0.0, 0.4])
    scene.sim.step(10)
    assert arm.get_qvel()[:, 0].tolist() == pytest.approx([0.0, 0.4], abs=0.01)
    arm.set_qf(torch.tensor([1.5]), joint_ids=[1], env_ids=[0])
    assert scene.sim.qfrc_applied[:, arm.dof_adr[1]].tolist() == [1.5, 0.0]
    arm.set_joint_drive(stiffness=50.0, joint_ids=[0], env_ids=[1])
    gain = scene.sim.model_field("actuator_gainprm")[:, int(arm.pos_act[0]), 0]
    assert gain.tolist() == pytest.approx([0.0, 50.0])


# -- lights ---------------------------------------------------------------------------------------------------
def test_light_color_and_intensity_per_env() -> None:
    scene = build(3, lights=[LightCfg(uid="lamp", init_pos=(0.0, 0.0, 2.0), color=(1.0, 1.0, 1.0), intensity=30.0)])
    lamp = scene["lamp"]
    lid = lamp.light_id
    lamp.set_color(torch.tensor([[1.0, 0.0, 0.0]]), env_ids=[1])
    lamp.set_intensity(torch.tensor([15.0]), env_ids=[2])
    diffuse = scene.sim.model_field("light_diffuse")[:, lid]
    assert diffuse[0].tolist() == pytest.approx(light_diffuse((1, 1, 1), 30.0))
    assert diffuse[1].tolist() == pytest.approx([1.0, 0.0, 0.0])
    assert diffuse[2].tolist() == pytest.approx([0.5, 0.5, 0.5])
    for env, expected in enumerate([[1, 1, 1], [1, 0, 0], [0.5, 0.5, 0.5]]):
        assert scene.sim.get_model(env).light_diffuse[lid].tolist() == pytest.approx(expected)
    assert scene.sim.model_field("light_intensity")[:, lid].tolist() == pytest.approx([30.0, 30.0, 15.0])
    assert lamp.get_color()[1].tolist() == [1.0, 0.0, 0.0]
    lamp.set_position(torch.tensor([[1.0, 0.0, 3.0]]), env_ids=[0])
    scene.sim.forward()
    assert scene.sim.light_xpos[:, lid, 0].tolist() == pytest.approx([1.0, 0.0, 0.0])
    lamp.reset([1])
    assert scene.sim.get_model(1).light_diffuse[lid].tolist() == pytest.approx([1, 1, 1])
    assert scene.sim.get_model(2).light_diffuse[lid].tolist() == pytest.approx([0.5, 0.5, 0.5])


# -- URDF -------------------------------------------------------------------------------------------------------------
def test_urdf_articulation_keeps_fixed_links_and_limits(tmp_path) -> None:
    path = tmp_path / "drawer.urdf"
    path.write_text(DRAWER_URDF)
    scene = build(2, articulations=[ArticulationCfg(uid="drawer", fpath=str(path), init_pos=(1.0, 0.0, 0.0))])
    drawer = scene["drawer"]
    assert "handle_xpos" in drawer.link_names
    assert drawer.joint_names == ["slide_rails"]
    assert drawer.get_qpos_limits()[:, 0].tolist() == [pytest.approx([0.0, 0.2])] * 2
    before = drawer.get_link_pose("handle_xpos")
    assert before[0, :3].tolist() == pytest.approx([1.18, 0.0, 0.07], abs=1e-4)
    drawer.set_qpos(torch.tensor([[0.15]]), env_ids=[1], target=False)
    after = drawer.get_link_pose("handle_xpos")
    assert (after[:, 0] - before[:, 0]).tolist() == pytest.approx([0.0, 0.15], abs=1e-5)
