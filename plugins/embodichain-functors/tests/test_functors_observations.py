"""Observation functors: shapes and values, caches cleared on reset, sensor queries."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import CUBE_POS, apply, event, scene_cfg, toy_ik_arm_cfg

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import EventCfg, ObservationCfg
from embodichain_core.managers import SceneEntityCfg as E
from embodichain_core.sim.cfg import RobotCfg

import embodichain_functors.observations as obs
import embodichain_functors.randomization as rand


def add(func, name: str, **params) -> ObservationCfg:
    return ObservationCfg(func=func, mode="add", name=name, params=params)


def test_object_poses_velocity_and_scale(build) -> None:
    env = build(
        observations={
            "m": add(obs.get_rigid_object_pose, "object/cube", entity_cfg=E(uid="cube")),
            "p": add(obs.get_rigid_object_pose, "object/cube7", entity_cfg=E(uid="cube"), to_matrix=False),
            "a": add(obs.get_object_pose, "object/arm", entity_cfg=E(uid="arm"), to_matrix=False),
            "v": add(obs.get_rigid_object_velocity, "object/cube_vel", entity_cfg=E(uid="cube")),
            "s": add(obs.get_object_body_scale, "object/cube_scale", entity_cfg=E(uid="cube")),
        }
    )
    o, _ = env.reset()
    objs = o["object"]
    assert objs["cube"].shape == (4, 4, 4)
    assert torch.allclose(objs["cube"][:, :3, 3], torch.tensor(CUBE_POS).expand(4, 3))
    assert objs["cube7"].shape == (4, 7)
    assert objs["arm"].shape == (4, 7)
    assert objs["cube_vel"].shape == (4, 6)
    assert torch.equal(objs["cube_scale"], torch.ones(4, 3))
    assert env.single_observation_space["object"]["cube"].shape == (4, 4)
    # values, not only shapes: a velocity set on envs 1 and 3 is read back in the world frame
    velocity = torch.tensor([[0.1, -0.2, 0.3, 0.5, 0.0, -0.4], [0.0, 0.2, 0.0, 0.0, 0.3, 0.0]])
    pose = env.scene["cube"].get_local_pose().clone()
    pose[[1, 3], 3:] = torch.tensor([0.9238795, 0.0, 0.0, 0.3826834])  # 45 degrees about z
    env.scene["cube"].set_local_pose(pose[[1, 3]], [1, 3])
    env.scene["cube"].set_velocity(velocity, [1, 3])
    objs = env.get_obs()["object"]
    assert torch.allclose(objs["cube_vel"][[1, 3]], velocity, atol=1e-5)
    assert torch.equal(objs["cube_vel"][[0, 2]], torch.zeros(2, 6))
    assert torch.allclose(objs["cube7"][[1, 3], 3:], pose[[1, 3], 3:].float(), atol=1e-6)


def test_object_body_scale_reads_the_configured_scale(build) -> None:
    cfg = scene_cfg(observations={"s": add(obs.get_object_body_scale, "object/s", entity_cfg=E(uid="cube"))})
    cfg.rigid_object[0].body_scale = (2.0, 1.0, 0.5)
    o, _ = build(cfg).reset()
    assert torch.equal(o["object"]["s"], torch.tensor([[2.0, 1.0, 0.5]]).expand(4, 3))


def test_missing_uid_is_a_config_error(build) -> None:
    with pytest.raises(ConfigError, match="uid"):
        build(observations={"m": add(obs.get_rigid_object_pose, "object/x", entity_cfg=E(uid="nope"))})


def test_normalize_robot_joint_data_maps_limits(build) -> None:
    env = build(
        observations={
            "n": ObservationCfg(
                func=obs.normalize_robot_joint_data, mode="modify", name="robot/qpos", params={"joint_ids": [0, 1, 2]}
            )
        }
    )
    arm = env.scene["arm"]
    arm.set_qpos(torch.tensor([[-2.8, 0.0, 2.8]]).expand(4, 3), joint_ids=[0, 1, 2], target=False)
    q = env.get_obs()["robot"]["qpos"]
    assert torch.allclose(q[:, :3], torch.tensor([0.0, 0.5, 1.0]).expand(4, 3), atol=1e-6)
    assert torch.equal(q[:, 3:], arm.get_qpos()[:, 3:7])  # other columns untouched


def test_normalize_qvel_to_symmetric_range(build) -> None:
    from embodichain_core.sim.cfg import JointDrivePropertiesCfg

    env = build(
        robot=RobotCfg(
            uid="arm",
            fpath=scene_cfg().robot.fpath,
            control_parts={"arm": ["joint[1-7]"]},
            drive_pros=JointDrivePropertiesCfg(max_velocity=2.0),
        ),
        observations={
            "n": ObservationCfg(
                func=obs.normalize_robot_joint_data,
                mode="modify",
                name="robot/qvel",
                params={"limit": "qvel_limits", "range": [-1, 1]},
            )
        },
    )
    env.scene["arm"].set_qvel(torch.full((4, 9), 1.0), target=False)
    assert torch.allclose(env.get_obs()["robot"]["qvel"], torch.full((4, 7), 0.5), atol=1e-5)


def test_eef_pose_through_the_robots_fk(build) -> None:
    env = build(
        robot=toy_ik_arm_cfg(),
        observations={
            "ee": add(obs.get_robot_eef_pose, "robot/ee", part_name="arm"),
            "pos": add(obs.get_robot_eef_pose, "robot/ee_pos", position_only=True),
        },
    )
    env.scene["arm"].set_qpos(torch.tensor([0.1, 0.2, 0.3, 0.0]).expand(4, 4), joint_ids=[0, 1, 2, 3], target=False)
    o = env.get_obs()
    assert o["robot"]["ee"].shape == (4, 4, 4)
    assert torch.allclose(o["robot"]["ee_pos"], torch.tensor([0.1, 0.2, 0.3]).expand(4, 3), atol=1e-5)


def test_eef_pose_needs_a_solver(build) -> None:
    with pytest.raises(ConfigError, match="solver"):
        build(observations={"ee": add(obs.get_robot_eef_pose, "robot/ee")})


def test_target_position(build) -> None:
    env = build(
        observations={"g": add(obs.target_position, "task/goal", target_pose_key="goal_pose")},
        events={
            "t": EventCfg(
                func=rand.randomize_target_pose,
                mode="reset",
                params={"position_range": [[0.1, 0.2, 0.3], [0.1, 0.2, 0.3]], "store_key": "goal_pose"},
            )
        },
    )
    assert torch.equal(env.get_obs()["task"]["goal"], torch.zeros(4, 3))
    o, _ = env.reset()
    assert torch.allclose(o["task"]["goal"], torch.tensor([0.1, 0.2, 0.3]).expand(4, 3))
    env.goal_pose = torch.ones(4, 3)
    assert torch.equal(env.get_obs()["task"]["goal"], torch.ones(4, 3))


def test_physics_attributes_cached_until_reset(build) -> None:
    env = build(
        observations={"p": add(obs.get_rigid_object_physics_attributes, "object/phys", entity_cfg=E(uid="cube"))},
        events=event(rand.randomize_rigid_object_mass, entity_cfg=E(uid="cube"), mass_range=[3.0, 4.0]),
    )
    first = env.get_obs()["object"]["phys"]
    assert {k: tuple(v.shape) for k, v in first.items()} == {
        "mass": (4,),
        "friction": (4,),
        "damping": (4, 6),
        "inertia": (4, 3),
    }
    apply(env, [0, 1, 2, 3])
    assert torch.equal(env.get_obs()["object"]["phys"]["mass"], first["mass"])  # cached
    first["mass"][:] = -1  # callers get clones
    assert (env.get_obs()["object"]["phys"]["mass"] > 0).all()
    env.reset(options={"reset_ids": [2]})
    assert (env.get_obs()["object"]["phys"]["mass"] >= 3.0).all()  # the reset cleared the cache


def test_joint_drive_attributes(build) -> None:
    env = build(observations={"d": add(obs.get_articulation_joint_drive, "robot/drive", entity_cfg=E(uid="arm"))})
    drive = env.get_obs()["robot"]["drive"]
    assert set(drive) == {"stiffness", "damping", "max_effort", "max_velocity", "friction", "armature"}
    assert drive["stiffness"].shape == (4, 9)
    assert (drive["stiffness"][:, :8] == 1e4).all()
    assert (drive["stiffness"][:, 8] == 0).all()  # the mimic finger has no drive


def test_class_observation_rejects_wrong_entity(build) -> None:
    with pytest.raises(ConfigError) as err:
        build(observations={"d": add(obs.get_articulation_joint_drive, "robot/drive", entity_cfg=E(uid="cube"))})
    assert err.value.path == "env.observations.d"
    assert "params.entity_cfg" in str(err.value)


# -- sensors ------------------------------------------------------------------------------------------
sensors = pytest.importorskip("embodichain_sensors.cfg", reason="needs embodichain-sensors")


def _cam(**kwargs):
    return sensors.CameraCfg(
        uid="cam",
        width=64,
        height=48,
        intrinsics=(50.0, 50.0, 32.0, 24.0),
        enable_mask=True,
        extrinsics=sensors.CameraCfg.ExtrinsicsCfg(eye=(0.5, -0.5, 0.5), target=(0.5, 0, 0)),
        **kwargs,
    )


def test_sensor_pose_in_robot_frame_and_intrinsics(build) -> None:
    env = build(
        sensor=[_cam()],
        observations={
            "pose": add(obs.get_sensor_pose_in_robot_frame, "sensor_info/pose", entity_cfg=E(uid="cam")),
            "k": add(obs.get_sensor_intrinsics, "sensor_info/k", entity_cfg=E(uid="cam")),
        },
        events={
            "root": EventCfg(
                func=rand.randomize_articulation_root_pose,
                mode="test",
                params={"entity_cfg": E(uid="arm"), "position_range": [[0.1, 0, 0], [0.1, 0, 0]]},
            )
        },
    )
    apply(env, [1])
    o = env.get_obs()["sensor_info"]
    assert torch.allclose(o["pose"][0, :3, 3], torch.tensor([0.5, -0.5, 0.5]), atol=1e-5)
    assert torch.allclose(o["pose"][1, :3, 3], torch.tensor([0.4, -0.5, 0.5]), atol=1e-5)  # robot moved +x
    assert o["k"].shape == (4, 3, 3)
    assert (o["k"][:, 0, 0] == 50).all()
    assert (o["k"][:, 1, 2] == 24).all()


def test_stereo_right_view(build) -> None:
    stereo = sensors.StereoCameraCfg(
        uid="cam",
        width=32,
        height=24,
        intrinsics=(30, 30, 16, 12),
        intrinsics_right=(31, 31, 16, 12),
        left_to_right_pos=(0.1, 0, 0),
        extrinsics=sensors.CameraCfg.ExtrinsicsCfg(pos=(0, 0, 1)),
    )
    env = build(
        sensor=[stereo],
        observations={
            "k": add(obs.get_sensor_intrinsics, "sensor_info/k", entity_cfg=E(uid="cam"), is_right=True),
            "p": add(obs.get_sensor_pose_in_robot_frame, "sensor_info/p", entity_cfg=E(uid="cam"), is_right=True),
        },
    )
    o = env.get_obs()["sensor_info"]
    assert (o["k"][:, 0, 0] == 31).all()
    assert torch.allclose(o["p"][:, 0, 3], torch.full((4,), 0.05), atol=1e-5)


def test_semantic_mask_foreground_and_background(build) -> None:
    env = build(
        sensor=[_cam()],
        observations={
            "sem": add(
                obs.compute_semantic_mask,
                "sensor/cam/semantic",
                entity_cfg=E(uid="cam"),
                foreground_uids=["cube", "ghost"],
            )
        },
    )
    o = env.get_obs()
    sem, mask = o["sensor"]["cam"]["semantic"], o["sensor"]["cam"]["mask"]
    cam = env.scene.sensors["cam"]
    assert sem.shape == (4, 48, 64, 4)
    assert sem.dtype == torch.bool
    assert torch.equal(sem[..., 1], mask == cam.mask_id_of("cube"))
    assert sem[..., 1].any()
    assert torch.equal(sem[..., 0], ~sem[..., 1:].any(-1))
    assert not sem[..., 2:].any()  # the arm has no left_/right_ links


def test_semantic_mask_robot_sides(build) -> None:
    mjcf = (
        '<mujoco><worldbody><body name="torso"><geom type="box" size=".05 .05 .05"/>'
        '<body name="left_arm" pos="0.5 0.1 0.1"><joint name="l" axis="0 0 1"/><geom type="box" size=".03 .03 .03"/>'
        '</body><body name="right_arm" pos="0.5 -0.1 0.1"><joint name="r" axis="0 0 1"/>'
        '<geom type="box" size=".03 .03 .03"/></body></body></worldbody></mujoco>'
    )
    cam = sensors.CameraCfg(
        uid="cam",
        width=64,
        height=48,
        intrinsics=(50.0, 50.0, 32.0, 24.0),
        enable_mask=True,
        extrinsics=sensors.CameraCfg.ExtrinsicsCfg(eye=(0.5, 0.0, 0.8), target=(0.5, 0.0, 0.0), up=(1.0, 0.0, 0.0)),
    )
    env = build(
        robot=RobotCfg(uid="bot", mjcf=mjcf),
        control_parts=None,
        sensor=[cam],
        observations={
            "sem": add(obs.compute_semantic_mask, "sensor/cam/semantic", entity_cfg=E(uid="cam"), foreground_uids=[])
        },
    )
    sem = env.get_obs()["sensor"]["cam"]["semantic"]
    left, right = sem[..., 2], sem[..., 3]
    assert left.any()
    assert right.any()
    assert not (left & right).any()
    cols = torch.arange(64).float()
    assert (left.float() * cols).sum() / left.sum() != (right.float() * cols).sum() / right.sum()


def test_sensor_functors_reject_non_sensors(build) -> None:
    with pytest.raises(ConfigError) as err:
        env = build(observations={"k": add(obs.get_sensor_intrinsics, "x/k", entity_cfg=E(uid="cube"))})
        env.get_obs()
    assert "get_sensor_intrinsics" in str(err.value)
    assert "entity_cfg" in str(err.value)
