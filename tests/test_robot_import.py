"""A robot from the user's own URDF/MJCF file: meshes by package:// and relative paths,
unbalanced inertias, mimic and continuous joints, unreadable meshes, the model's own
actuators (replaced with a notice, or kept as the joints' drives)."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
import torch
from robot_files import ARM_JOINT_NAMES, HOME, urdf_robot_section, write_mjcf_arm, write_urdf_arm

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import RobotCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.scene_build.import_checks import ModelImportWarning


def build(section: dict, num_envs: int = 2) -> tuple[Scene, list[str]]:
    """A scene with the robot of a JSON robot section (round-tripped through JSON text)."""
    cfg = RobotCfg.from_dict(json.loads(json.dumps(section)))
    scene = Scene(SimulationManagerCfg(), num_envs=num_envs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene.add_robot(cfg)
        scene.build()
    return scene, [str(w.message) for w in caught if issubclass(w.category, ModelImportWarning)]


def hold(scene: Scene, uid: str, steps: int = 100) -> float:
    """Largest joint drift (rad or m) over ``steps`` physics steps from the reset pose."""
    start = scene[uid].get_qpos().clone()
    for _ in range(steps):
        scene.sim.step(1)
    return float((scene[uid].get_qpos() - start).abs().max())


def test_urdf_arm_loads_with_meshes_mimic_and_continuous_joints(tmp_path: Path) -> None:
    scene, notices = build(urdf_robot_section(write_urdf_arm(tmp_path)))
    robot = scene["arm"]
    assert notices == []  # balanced inertias, no actuators in a URDF: nothing to report
    assert robot.joint_names == ARM_JOINT_NAMES + ["finger_left", "finger_right"]
    model = scene.model
    files = {Path(model.mesh(i).name).name for i in range(model.nmesh)}
    assert len(files) == 7  # package:// (even links) and ../meshes (odd links) both resolved
    assert robot.mimic_ids == [7]
    assert robot.mimic_parents == [6]
    limits = robot.get_qpos_limits()[0]
    assert torch.isinf(limits[0]).all()  # the continuous shoulder_pan stays unlimited
    assert torch.allclose(limits[1], torch.tensor([-3.0, 3.0]))
    assert torch.allclose(robot.get_qpos()[:, :6], torch.tensor(HOME).expand(2, 6))
    assert hold(scene, "arm") < 1e-3


def test_unbalanced_inertia_is_balanced_with_one_warning(tmp_path: Path) -> None:
    scene, notices = build(urdf_robot_section(write_urdf_arm(tmp_path, unbalanced=True)))
    assert len(notices) == 1
    assert "'forearm'" in notices[0]
    assert "balanceinertia" in notices[0]
    assert "'upper_arm'" not in notices[0]
    body = scene.model.body("arm/forearm").id
    moments = np.sort(scene.model.body_inertia[body])
    assert moments[0] + moments[1] >= moments[2] - 1e-12
    assert hold(scene, "arm") < 1e-3


def test_missing_mesh_names_the_file_and_the_link(tmp_path: Path) -> None:
    path = write_urdf_arm(tmp_path, mesh_override={"wrist1": "package://test_arm/meshes/gone.stl"})
    with pytest.raises(ConfigError) as err:
        build(urdf_robot_section(path))
    assert err.value.path == "robot.fpath"
    assert "gone.stl" in str(err.value)
    assert "'wrist1'" in str(err.value)


def test_unreadable_mesh_names_the_file_and_the_link(tmp_path: Path) -> None:
    path = write_urdf_arm(tmp_path)
    (path.parent.parent / "meshes" / "forearm.stl").write_bytes(b"not an stl file")
    with pytest.raises(ConfigError) as err:
        build(urdf_robot_section(path))
    assert err.value.path == "robot.fpath"
    message = str(err.value)
    assert "forearm.stl" in message
    assert "'arm/forearm'" in message
    assert "STL" in message


def test_model_actuators_are_replaced_with_a_notice(tmp_path: Path) -> None:
    section = {"uid": "servo", "fpath": str(write_mjcf_arm(tmp_path)), "init_qpos": [0.3, 0.5, -0.4]}
    scene, notices = build(section)
    assert len(notices) == 1
    assert all(name in notices[0] for name in ("'servo1'", "'servo2'", "'torque3'", "keep_actuators"))
    names = [scene.model.actuator(i).name for i in range(scene.model.nu)]
    assert names == [f"servo/j{i}:{k}" for i in (1, 2, 3) for k in ("pos", "vel")]
    assert hold(scene, "servo") < 1e-3


def test_kept_servos_are_the_joints_drives(tmp_path: Path) -> None:
    section = {
        "uid": "servo",
        "fpath": str(write_mjcf_arm(tmp_path)),
        "init_qpos": [0.3, 0.5, -0.4],
        "keep_actuators": True,
        "drive_pros": {"stiffness": 300.0, "damping": 30.0, "armature": 0.01},
    }
    scene, notices = build(section)
    robot = scene["servo"]
    assert notices == []
    names = [scene.model.actuator(i).name for i in range(scene.model.nu)]
    assert names[:3] == ["servo/servo1", "servo/servo2", "servo/torque3"]
    assert robot.pos_act.tolist() == [0, 1, 3]  # the servos; the motor joint got a drive_pros drive
    stiffness, damping = robot.get_joint_drive()
    assert torch.allclose(stiffness[0], torch.tensor([400.0, 400.0, 300.0]))  # the model's kp kept
    assert torch.allclose(damping[0], torch.tensor([20.0, 20.0, 30.0]))
    assert np.allclose(scene.model.dof_armature[robot.dof_adr.numpy()], 0.01)  # drive_pros on top
    assert hold(scene, "servo") < 1e-3
    robot.set_qpos(torch.tensor([[0.0, 0.2, 0.0]]).expand(2, 3))
    assert torch.allclose(scene.sim.ctrl[:, :2].float(), torch.tensor([0.0, 0.2]).expand(2, 2))
    for _ in range(300):
        scene.sim.step(1)
    assert torch.allclose(robot.get_qpos(), torch.tensor([0.0, 0.2, 0.0]).expand(2, 3), atol=0.02)


def test_mjcf_missing_mesh_names_the_file_and_the_link(tmp_path: Path) -> None:
    path = tmp_path / "one_link.xml"
    path.write_text(
        '<mujoco><compiler meshdir="meshes"/><asset><mesh name="shell" file="shell.stl"/></asset>'
        '<worldbody><body name="link"><joint name="j" type="hinge"/>'
        '<geom type="mesh" mesh="shell" mass="1"/></body></worldbody></mujoco>'
    )
    with pytest.raises(ConfigError) as err:
        build({"uid": "one", "fpath": str(path)})
    assert err.value.path == "robot.fpath"
    assert str(tmp_path / "meshes" / "shell.stl") in err.value.reason
    assert "'one/link'" in err.value.reason


def test_kept_servos_drive_a_passive_articulation(tmp_path: Path) -> None:
    section = {
        "uid": "servo",
        "fpath": str(write_mjcf_arm(tmp_path)),
        "keep_actuators": True,
        "drive_pros": {"drive_type": "none"},
    }
    scene, notices = build(section)
    robot = scene["servo"]
    assert notices == []
    assert scene.model.nu == 3  # the file's actuators only: no drive_pros drives
    assert robot.pos_act.tolist() == [0, 1, -1]  # the motor joint has no position drive
    robot.set_qpos(torch.tensor([0.2, -0.1, 0.0]).expand(2, 3))
    assert torch.allclose(scene.sim.ctrl[:, :2].float(), torch.tensor([0.2, -0.1]).expand(2, 2))
