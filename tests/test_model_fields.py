"""Per-env model fields of articulations and the scene: damping, armature, friction loss,
drive gains, masses, geom friction and gravity; the shape contract of every setter."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from robot_files import urdf_robot_section, write_urdf_arm

from embodichain_core.sim.cfg import RobotCfg, SimulationManagerCfg
from embodichain_core.sim.entities.model_fields import per_env_values, set_gravity
from embodichain_core.sim.scene import Scene

N = 4


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> Scene:
    path = write_urdf_arm(tmp_path_factory.mktemp("arm"))
    section = urdf_robot_section(path, drive_pros={"drive_type": "none"})
    section["gravity_compensation"] = False
    scene = Scene(SimulationManagerCfg(), num_envs=N)
    scene.add_robot(RobotCfg.from_dict(section))
    scene.build()
    return scene


def test_per_env_damping_differs_across_envs_and_changes_the_motion(scene: Scene) -> None:
    robot = scene["arm"]
    damping = torch.tensor([0.5, 5.0, 50.0, 500.0])
    robot.set_joint_damping(damping[:, None], joint_ids=[1])
    got = robot.get_joint_damping(joint_ids=[0, 1])
    assert torch.allclose(got[:, 1], damping)
    assert torch.allclose(got[:, 0], torch.full((N,), 0.5))  # the URDF's <dynamics damping>
    scene.reset()
    for _ in range(20):  # passive joints fall under gravity, slower with more damping
        scene.sim.step(1)
    speed = robot.get_qvel()[:, 1].abs()
    assert (speed[:-1] > speed[1:]).all()
    robot.set_joint_damping(0.5, joint_ids=[1])


def test_armature_friction_loss_and_masses_per_env_and_joint(scene: Scene) -> None:
    robot = scene["arm"]
    values = torch.arange(N * 2, dtype=torch.float64).reshape(N, 2) * 0.01
    robot.set_joint_armature(values, joint_ids=[2, 3])
    assert torch.allclose(robot.get_joint_armature(joint_ids=[2, 3]), values.float())
    robot.set_joint_friction_loss([0.1, 0.2], joint_ids=[4, 5], env_ids=[1, 3])  # (k,): per joint
    friction = robot.get_joint_friction_loss(joint_ids=[4, 5])
    assert torch.allclose(friction[[1, 3]], torch.tensor([0.1, 0.2]).expand(2, 2))
    assert torch.allclose(friction[[0, 2]], torch.zeros(2, 2))
    robot.set_mass(torch.tensor([1.0, 2.0, 3.0, 4.0]), link_names=["forearm", "wrist1"])  # (n,): per env
    assert torch.allclose(robot.get_mass(["forearm", "wrist1"]), torch.tensor([1.0, 2, 3, 4])[:, None].expand(N, 2))


def test_drive_gains_per_env_and_joint(tmp_path: Path) -> None:
    drives = Scene(SimulationManagerCfg(), num_envs=2)
    drives.add_robot(RobotCfg.from_dict(urdf_robot_section(write_urdf_arm(tmp_path))))
    drives.build()
    robot = drives["arm"]
    robot.set_joint_drive(stiffness=[[100.0, 200.0], [300.0, 400.0]], damping=[7.0, 9.0], joint_ids=[0, 1])
    stiffness, damping = robot.get_joint_drive(joint_ids=[0, 1, 2])
    assert torch.allclose(stiffness, torch.tensor([[100.0, 200.0, 2000.0], [300.0, 400.0, 2000.0]]))
    assert torch.allclose(damping, torch.tensor([[7.0, 9.0, 100.0], [7.0, 9.0, 100.0]]))


def test_geom_friction_per_env_and_link(scene: Scene) -> None:
    robot = scene["arm"]
    robot.set_friction([[0.1, 0.9]] * 2, link_names=["forearm", "flange"], env_ids=[0, 2])
    friction = robot.get_friction(link_names=["forearm", "flange", "tool0"])
    assert torch.allclose(friction[[0, 2], :2], torch.tensor([0.1, 0.9]).expand(2, 2))
    assert torch.allclose(friction[[1, 3], :2], torch.full((2, 2), 0.5))
    assert torch.isnan(friction[:, 2]).all()  # tool0 has no colliding geom


def test_gravity_per_env(scene: Scene) -> None:
    robot = scene["arm"]
    scene.set_gravity([[0, 0, -9.81], [0, 0, -9.81], [0, 0, 0], [0, 0, 0]])
    assert torch.allclose(scene.get_gravity()[:, 2], torch.tensor([-9.81, -9.81, 0.0, 0.0]))
    scene.reset()
    for _ in range(20):
        scene.sim.step(1)
    moved = (robot.get_qpos() - robot.default_qpos.float()).abs().amax(-1)
    assert (moved[:2] > 1e-3).all()
    assert (moved[2:] < 1e-6).all()
    scene.set_gravity([0, 0, -9.81])


def test_shape_errors_name_the_field_and_the_shapes(scene: Scene) -> None:
    robot = scene["arm"]
    with pytest.raises(ValueError, match=r"dof_damping: got shape \(3,\); expected .*\(2,\) per joint"):
        robot.set_joint_damping([1.0, 2.0, 3.0], joint_ids=[0, 1])
    with pytest.raises(ValueError, match=r"gravity: got shape \(2,\)"):
        scene.set_gravity([0.0, 1.0])


def test_shape_contract() -> None:
    assert per_env_values(2.0, 3, 2).tolist() == [[2.0, 2.0]] * 3
    assert per_env_values([1.0, 2.0], 3, 2).tolist() == [[1.0, 2.0]] * 3  # (k,): per joint
    assert per_env_values([1.0, 2.0, 3.0], 3, 2)[:, 1].tolist() == [1.0, 2.0, 3.0]  # (n,): per env
    assert per_env_values([1.0, 2.0], 2, 2).tolist() == [[1.0, 2.0]] * 2  # n == k: per joint
    assert per_env_values([[1.0], [2.0]], 2, 2).tolist() == [[1.0, 1.0], [2.0, 2.0]]
    assert per_env_values(np.ones((2, 1)), 2, 1).shape == (2, 1)


def test_global_gravity_backend_is_a_clear_error() -> None:
    class GlobalOptions:
        num_envs = 2

        def set_model_field(self, name, *args, **kwargs):
            raise AttributeError(f"no per-env field {name!r}")

    with pytest.raises(ValueError, match="gravity is a global option"):
        set_gravity(GlobalOptions(), [0, 0, -1])
